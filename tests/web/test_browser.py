"""The dashboard in a real headless Chromium: the page loads, the 3-D robot is drawn, and a
scripted mouse tracing a learned pattern makes the robot recognise it.

These tests need Chromium at /usr/bin/chromium (scripts/setup.sh installs it) and fail, not
skip, when it cannot run.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np
import pytest

CHROMIUM = Path("/usr/bin/chromium")
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--no-first-run", "--disable-quic"]
TRACE_DT = 0.4
"""The step while the mouse traces: one scripted sample (two drags) must fit in one step."""
TRACE_SAMPLES = 40
RECOGNISED_WITHIN = 25
"""Samples of the traced pattern after which the PB must be nearest to its learned PB."""


@pytest.fixture(scope="module")
def browser():
    if not CHROMIUM.exists():
        pytest.fail(f"{CHROMIUM} is missing: install it (apt-get install chromium, or "
                    "WITH_BROWSER=1 scripts/setup.sh); the dashboard tests need a browser")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        try:
            chromium = playwright.chromium.launch(executable_path=str(CHROMIUM), args=FLAGS)
        except Exception as error:  # noqa: BLE001 — any launch failure must fail loudly
            pytest.fail(f"cannot start {CHROMIUM}: {error}")
        try:
            yield chromium
        finally:
            chromium.close()


@pytest.fixture()
def page(browser, server):
    page = browser.new_page(viewport={"width": 1400, "height": 1000})
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    page.goto(server.url)
    page.wait_for_function("window.rnnpbDashboard && rnnpbDashboard.state && "
                           "rnnpbDashboard.state.model && !rnnpbDashboard.state.loading",
                           timeout=60000)
    yield page
    page.close()
    assert not errors, f"the page raised: {errors}"


def _set(page, message: str, condition: str) -> None:
    page.evaluate(f"rnnpbDashboard.send({message})")
    page.wait_for_function(condition, timeout=10000)


def test_page_loads_and_draws_the_robot_in_3d(page, tmp_path):
    assert "rnnpb" in page.title()
    page.click("#reset")
    page.click("#start")
    page.wait_for_function("rnnpbDashboard.steps > 5 && rnnpbDashboard.rendered3d > 2",
                           timeout=20000)
    page.click("#stop")
    shot = tmp_path / "view3d.png"
    page.locator("#view3d canvas").screenshot(path=str(shot))
    import cv2

    image = cv2.imread(str(shot))
    assert image is not None and image.shape[0] > 100 and image.shape[1] > 100
    background = np.median(image.reshape(-1, 3), axis=0)
    differs = np.abs(image.astype(int) - background).sum(axis=2) > 40
    # The robot's body and arms (and the person's hands) cover part of the view; a blank or
    # uniformly coloured canvas would have next to no pixels off the background.
    assert differs.mean() > 0.02, f"the 3-D view looks blank ({differs.mean():.4f} drawn)"
    assert len(np.unique(image[differs], axis=0)) > 50  # shaded surfaces, not one flat colour
    # The plots are drawn too.
    assert page.evaluate("document.querySelector('#timings').textContent").count("mirror") == 1


def test_missing_camera_gives_a_message_on_the_page(page, server):
    page.click(".tab[data-mode=webcam]")
    page.fill("#camera", "15")
    page.click("#camera-open")
    # The page says "opening the camera…" first; wait for the server's answer, not that.
    page.wait_for_function("document.querySelector('#camera-message').textContent"
                           ".includes('still driven by')", timeout=15000)
    text = page.text_content("#camera-message")
    assert "no such camera" in text
    assert server.session.mode != "webcam"
    assert page.evaluate("rnnpbDashboard.connected")


def test_mouse_tracing_a_learned_pattern_is_recognised(page, server, model):
    from rnnpb.demonstrator import held_scenario

    pattern = "1"
    sensory = held_scenario(pattern, n_steps=TRACE_SAMPLES, seed=3).sensory
    page.click(".tab[data-mode=pointer]")
    page.wait_for_function("rnnpbDashboard.state.mode === 'pointer'")
    _set(page, f'{{type: "dt", dt: {TRACE_DT}}}', f"rnnpbDashboard.state.dt === {TRACE_DT}")
    page.click("#reset")
    page.click("#start")
    page.wait_for_function("rnnpbDashboard.lastStep !== null", timeout=10000)
    start_nearest = page.evaluate("rnnpbDashboard.lastStep.nearest")
    rect = page.evaluate("rnnpbDashboard.panelRect()")
    where = [page.evaluate(f"rnnpbDashboard.panelPoint({hand})") for hand in (0, 1)]
    last = page.evaluate("rnnpbDashboard.lastStep.step")
    nearest, pbs = [], []
    started = time.monotonic()
    try:
        for u in sensory:
            # Wait for the next step, then move both markers before the step after it.
            handle = page.wait_for_function(
                f"rnnpbDashboard.lastStep.step > {last} && "
                "[rnnpbDashboard.lastStep.step, rnnpbDashboard.lastStep.pb]", timeout=10000)
            last, pb = handle.json_value()
            pbs.append(pb)
            nearest.append(model.nearest_pattern(np.array(pb))[0])
            for hand in (0, 1):
                x = rect["left"] + u[2 * hand] * rect["width"]
                y = rect["top"] + (1 - u[2 * hand + 1]) * rect["height"]
                page.mouse.move(*where[hand])
                page.mouse.down()
                page.mouse.move(x, y)
                page.mouse.up()
                where[hand] = (x, y)
        # The robot perceived the traced markers, not something else: once the last drag has
        # reached the server (its message can arrive a step after the drag ended in the page),
        # the steps see both markers where they were left, and go on seeing them.
        expected = json.dumps([float(v) for v in sensory[-1]])
        seen_there = (f"rnnpbDashboard.lastStep.observed.every("
                      f"(v, i) => Math.abs(v - {expected}[i]) < 0.01)")
        done = page.evaluate("rnnpbDashboard.lastStep.step")
        there = page.wait_for_function(f"rnnpbDashboard.lastStep.step > {done} && {seen_there}"
                                       " && rnnpbDashboard.lastStep.step", timeout=10000)
        later = page.wait_for_function(f"rnnpbDashboard.lastStep.step > {there.json_value()} "
                                       "&& rnnpbDashboard.lastStep.observed", timeout=10000)
        np.testing.assert_allclose(np.array(later.json_value(), dtype=float), sensory[-1],
                                   atol=0.01)
    finally:
        page.click("#stop")
    elapsed = time.monotonic() - started
    first = next((i for i, name in enumerate(nearest) if name == pattern), None)
    assert first is not None and first <= RECOGNISED_WITHIN, (
        f"pattern {pattern} not recognised within {RECOGNISED_WITHIN} samples: {nearest} "
        f"(started nearest {start_nearest}; {elapsed:.1f} s)")
    tail = nearest[-10:]
    assert tail.count(pattern) >= 6, f"the PB did not stay near pattern {pattern}: {nearest}"
    print(f"mouse-traced pattern {pattern}: nearest learned PB from sample {first} on "
          f"(started nearest {start_nearest}); {''.join(nearest)}")
