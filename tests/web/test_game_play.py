"""The mirror game played with the real mouse in Chromium: Start and Stop say whether a game
runs, the leader of the movement found is the same wherever the page names it, the hints
never lead to a movement found already, a figure-eight's tempo is its own, and the game's log
stays in ``games/`` of the folder the server was started in.

Where a test needs the robot to make a given movement, the robot is scripted: it performs the
demonstrator's patterns in a set order (:class:`_ScriptedRobot`) instead of choosing them, so
that what the page must say follows from what the person does with the mouse."""

from __future__ import annotations

import json
import math
import time

import numpy as np
import pytest

from rnnpb.analysis import dyad as measures

from .test_browser import WATCH_CSP, _mouse_click, _until, browser  # noqa: F401 — fixture

GAME_DT = 0.1
"""The game's step: a 12-step cycle is 1.2 s of mouse movement."""
CYCLE_S = 12 * GAME_DT
REST = (0.62, 0.55)  # where the page puts your left hand (lhy, lhz)
# Hints that lead the person to the movement the robot makes now.
LEADING = ("the other hand mirror", "the other hand parallel", "the other hand opposite")


class _ScriptedRobot:
    """The game's robot performing ``script`` ([(pattern, steps), ...], the last one for
    ever) as the demonstrator performs patterns: its hands where the robot's camera saw its
    teachers' hands, one cycle every 12 steps."""

    name = "robot"

    def __init__(self, script: list[tuple[str, int]]) -> None:
        from rnnpb.demonstrator import PatternConfig, perform

        *first, (last, _) = script
        motion = perform([*first, (last, 2400)], PatternConfig(), np.random.default_rng(5), 0.0)
        self._hands = motion.measured
        self._step = 0

    @property
    def hands(self) -> np.ndarray:
        return self._hands[min(self._step, len(self._hands) - 1)]

    def act(self, view: np.ndarray):
        from rnnpb.interaction.dyad import AgentStep

        self._step += 1
        return AgentStep(hands=self.hands, view=np.asarray(view, dtype=np.float64))


@pytest.fixture()
def scripted(monkeypatch):
    """``scripted(script)``: the next game's robot performs ``script``."""
    import rnnpb.web._game as game

    def use(script: list[tuple[str, int]]) -> None:
        monkeypatch.setattr(game, "RobotAgent", lambda *args, **kwargs: _ScriptedRobot(script))

    return use


@pytest.fixture()
def game_server(set1_model_dir, tmp_path, monkeypatch):
    """A server started in a folder of this test's own, with no folder given for anything:
    what `rnnpb serve` does."""
    from rnnpb.web import DashboardServer, find_models

    monkeypatch.chdir(tmp_path)
    with DashboardServer(find_models(set1_model_dir), port=0, dt=GAME_DT) as server:
        yield server


def _open_game(browser, server):  # noqa: F811
    page = browser.new_page(viewport={"width": 1200, "height": 800})
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    page.add_init_script(WATCH_CSP)
    page.add_init_script(
        "window.__steps = [];"
        "window.addEventListener('game-step', (e) => window.__steps.push(e.detail));"
    )
    page.goto(server.url.rstrip("/") + "/game")
    _until(page, "document.querySelector('#model').options.length > 0", 30000)
    return page, errors


def _field(page):
    """Page pixels of a view value (y, z) on the game's field, as the mirror view shows it."""
    box = page.locator("#view").bounding_box()

    def at(y: float, z: float):
        return box["x"] + (1 - y) * box["width"], box["y"] + (1 - z) * box["height"]

    return at


def _play(page, path, seconds: float, done=lambda: False) -> None:
    """Press on your left hand and move it along ``path(phase)`` (view values of the left
    hand, a cycle every :data:`CYCLE_S`) for ``seconds`` or until ``done()``."""
    at = _field(page)
    page.mouse.move(*at(*REST))
    page.mouse.down()
    began = looked = time.monotonic()
    try:
        while (elapsed := time.monotonic() - began) < seconds:
            if time.monotonic() - looked > 0.5:
                looked = time.monotonic()
                if done():
                    return
            page.mouse.move(*at(*path((elapsed / CYCLE_S) % 1.0)))
            page.wait_for_timeout(15)
    finally:
        page.mouse.up()


def _swing(phase: float):
    """Pattern 1's left hand, as taught, about where the left hand rests."""
    cycle = measures.movement_templates()["1"][:, :2]
    k = phase * len(cycle)
    i = int(k) % len(cycle)
    y, z = cycle[i] + (k - int(k)) * (cycle[(i + 1) % len(cycle)] - cycle[i])
    return REST[0] + y, REST[1] + z


def _tall_eight(phase: float):
    """A figure-eight twice as tall as wide: up and down twice in each cycle."""
    angle = 2 * math.pi * phase
    return REST[0] + 0.08 * math.sin(angle), REST[1] + 0.16 * math.sin(2 * angle)


def _start(page) -> None:
    _mouse_click(page, "#start")
    _until(page, "/step [1-9]/.test(document.querySelector('#time').textContent)", 90000)


def test_start_is_off_while_a_game_runs_and_stop_while_none_does(browser, game_server):  # noqa: F811
    page, errors = _open_game(browser, game_server)
    try:
        assert page.is_enabled("#start")
        _start(page)
        assert page.is_disabled("#start") and page.is_enabled("#stop")
        _mouse_click(page, "#stop")
        _until(page, "document.querySelector('#status').textContent.startsWith('stopped')")
        assert page.is_enabled("#start") and page.is_disabled("#stop")
        assert not page.evaluate("() => window.__cspViolations || []")
    finally:
        page.close()
    assert not errors, f"the page raised: {errors}"


def test_a_tall_figure_eight_at_the_robot_s_tempo_is_not_told_to_slow_down(
    browser,  # noqa: F811
    game_server,
    scripted,
):
    scripted([("1", 1)])  # the horizontal swing, a cycle every 12 steps
    page, errors = _open_game(browser, game_server)
    try:
        _start(page)
        # A figure-eight at 12 steps a cycle, up and down twice in each: its tempo is the
        # robot's, however often it crosses its middle.
        _play(page, _tall_eight, seconds=16)
        steps = page.evaluate("() => window.__steps")[-90:]
        # Not moving in step with the robot, nor together: where the game gives its hints.
        from rnnpb.web._game import IN_STEP

        apart = [s for s in steps if s["synchrony"] < IN_STEP and not s["coherent"]]
        assert len(apart) > len(steps) // 2, "the case is not reached"
        hints = [s["hint"] for s in apart]
        assert not [h for h in hints if h in ("slower", "faster")], hints
    finally:
        page.close()
    assert not errors, f"the page raised: {errors}"


def test_the_leader_is_named_alike_and_no_hint_leads_back_to_a_found_movement(
    browser,  # noqa: F811
    game_server,
    scripted,
):
    # The robot circles first and only then swings: the person, swinging from the start, led.
    scripted([("3", 60), ("1", 1)])
    page, errors = _open_game(browser, game_server)
    try:
        _start(page)

        def found() -> bool:
            return bool(page.evaluate("() => window.__steps.some((s) => s.found.length)"))

        _play(page, _swing, seconds=90, done=found)
        _until(page, "document.querySelectorAll('#found-list li').length > 0")
        (first,) = page.evaluate("() => window.__steps.at(-1).found_at")
        assert first["pattern"] == "1" and first["led_by"] == "you", first
        # Who led it, the same in the list and under "Last switch led by".
        assert "led by you" in page.text_content("#found-list")
        assert page.text_content("#leader") == "you"

        # The person changes how the other hand follows; the robot swings on: no hint leads
        # back to the movement found.
        page.select_option("#coupling", "parallel")
        page.evaluate("() => window.__steps.splice(0)")
        _play(page, _swing, seconds=10)
        after = page.evaluate("() => window.__steps")
        hints = [s["hint"] for s in after]
        assert any(hints), "the game gave no hint at all: the case is not reached"
        assert not [h for h in hints if h.startswith(LEADING)], hints
    finally:
        page.close()
    assert not errors, f"the page raised: {errors}"


def test_the_game_s_log_stays_in_games_of_the_folder_the_server_started_in(
    browser,  # noqa: F811
    set1_model_dir,
    tmp_path,
    monkeypatch,
):
    from rnnpb.web import DashboardServer, find_models

    monkeypatch.chdir(tmp_path)
    with DashboardServer(find_models(set1_model_dir), port=0, dt=GAME_DT) as server:
        page, errors = _open_game(browser, server)
        try:
            _mouse_click(page, "#start")
            _until(page, "/step [1-9][0-9]/.test(document.querySelector('#time').textContent)")
            _play(page, _swing, seconds=2)
            _mouse_click(page, "#stop")
            _until(page, "document.querySelector('#status').textContent.startsWith('stopped')")
        finally:
            page.close()
        assert not errors, errors
    # The server has stopped and removed its own temporary folder; the log is the person's.
    (summary,) = sorted((tmp_path / "games").glob("game-*.json"))
    assert json.loads(summary.read_text())["steps"] > 10
    assert summary.with_suffix(".csv").exists()
