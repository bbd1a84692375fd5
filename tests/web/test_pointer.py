"""The pointer panel in a real headless Chromium, driven by the real mouse: one hand dragged
performs a learned two-hand pattern (the other hand follows it, as the game's "Other hand"
says), and a one-hand movement kept as a new one is said so in the panel."""

from __future__ import annotations

import shutil
import time

import numpy as np
import pytest

from rnnpb.analysis import dyad as measures

from .test_browser import _mouse_click, _shot, _strict_page, _until, browser  # noqa: F401 — fixture

POINTER_DT = 0.1
"""The step while the mouse swings: a 12-step cycle is 1.2 s of mouse movement."""
CYCLE_STEPS = 12


@pytest.fixture()
def dashboard(model_dir, tmp_path):
    """A server of this test's own (its short-term memory is this test's), safety as
    ``rnnpb serve`` has it."""
    from rnnpb.web import DashboardServer, find_models

    folder = tmp_path / "models"
    folder.mkdir()
    shutil.copy(model_dir / "set1.npz", folder / "set1.npz")
    with DashboardServer(
        find_models(folder), port=0, dt=POINTER_DT, workdir=tmp_path / "sessions"
    ) as server:
        yield server


def _left_hand_path(page, pattern: str):
    """Page pixels of the left hand (the red marker) along one cycle of ``pattern`` as taught,
    about where the marker rests: a function of the phase in [0, 1)."""
    cycle = measures.movement_templates()[pattern][:, :2]  # (12, 2): lhy, lhz offsets
    rest = page.evaluate("rnnpbDashboard.state.rest_hands")
    rect = page.evaluate("rnnpbDashboard.panelRect()")

    def at(phase: float):
        k = phase * len(cycle)
        i = int(k) % len(cycle)
        y, z = cycle[i] + (k - int(k)) * (cycle[(i + 1) % len(cycle)] - cycle[i])
        return (
            rect["left"] + (rest[0] + y) * rect["width"],
            rect["top"] + (1 - (rest[1] + z)) * rect["height"],
        )

    return at


def _swing_until(page, path, period_s: float, done, timeout_s: float) -> None:
    """Press on the red marker and swing it along ``path`` until ``done()`` (looked at twice
    a second) or ``timeout_s``; the mouse is let go at the end only."""
    page.mouse.move(*page.evaluate("rnnpbDashboard.panelPoint(0)"))
    page.mouse.down()
    began = looked = time.monotonic()
    try:
        while not (time.monotonic() - looked > 0.5 and (looked := time.monotonic()) and done()):
            elapsed = time.monotonic() - began
            assert elapsed < timeout_s, "the swing did not get there in time"
            page.mouse.move(*path((elapsed / period_s) % 1.0))
            page.wait_for_timeout(15)
    finally:
        page.mouse.up()


def test_one_hand_dragged_performs_a_two_hand_pattern_and_nothing_is_kept(browser, dashboard):  # noqa: F811
    with _strict_page(browser, dashboard) as page:
        _mouse_click(page, ".tab[data-mode=pointer]")
        _until(page, "rnnpbDashboard.state.mode === 'pointer'")
        _mouse_click(page, "#start")
        _until(page, "rnnpbDashboard.lastStep !== null", 30000)
        path = _left_hand_path(page, "1")
        started = page.evaluate("rnnpbDashboard.lastStep.step")

        def recognised() -> bool:
            steps = page.evaluate(
                f"rnnpbDashboard.history.filter((s) => s.step > {started} + 24)"
                ".map((s) => s.recognised)"
            )
            return len(steps) >= 24 and steps[-12:].count("1") >= 9

        # One marker dragged, horizontally apart and together (pattern 1, the swing the
        # robot learned with both hands in opposite phase), about one cycle every 12 steps.
        _swing_until(page, path, CYCLE_STEPS * POINTER_DT, recognised, timeout_s=45)
        history = page.evaluate(f"rnnpbDashboard.history.filter((s) => s.step > {started})")
        _mouse_click(page, "#stop")
        seen = np.array([s["observed"] for s in history[-36:]], dtype=float)
        # The right hand (the blue marker, never touched) moved with the left, mirrored.
        assert seen[:, 2].std() > 0.02, "the other hand did not follow the dragged one"
        assert np.corrcoef(seen[:, 0], seen[:, 2])[0, 1] < -0.9
        # Recognised as the learned pattern, so nothing was kept as a new movement.
        teaching = page.evaluate("rnnpbDashboard.state.teaching")
        assert teaching["pending"] == 0 and teaching["episodes"] == [], teaching["episodes"]
        # One name for the mode, wherever the page names it.
        assert page.text_content(".tab[data-mode=pointer]").strip() == "Pointer"
        assert page.text_content("#truth") == "you (pointer)"


def test_a_one_hand_movement_kept_as_new_is_said_in_the_pointer_panel(browser, dashboard):  # noqa: F811
    with _strict_page(browser, dashboard) as page:
        _mouse_click(page, ".tab[data-mode=pointer]")
        _until(page, "rnnpbDashboard.state.mode === 'pointer'")
        # The person chooses to move one hand only.
        page.select_option("#other-hand", "still")
        _mouse_click(page, "#start")
        _until(page, "rnnpbDashboard.lastStep !== null", 30000)
        path = _left_hand_path(page, "1")

        def kept() -> bool:
            return page.evaluate("rnnpbDashboard.state.teaching.pending") >= 1

        _swing_until(page, path, CYCLE_STEPS * POINTER_DT, kept, timeout_s=120)
        (episode,) = page.evaluate("rnnpbDashboard.state.teaching.episodes")
        assert episode["source"] == "pointer"
        # Said where the person is looking: the movement was kept, and as what.
        _until(
            page,
            f"document.querySelector('#pointer-note').textContent.includes('{episode['pattern']}')",
        )
        note = page.text_content("#pointer-note")
        assert "kept" in note.lower() and "one hand" in note, note
        _shot(page, "pointer-kept", ".drive")
        _mouse_click(page, "#stop")
