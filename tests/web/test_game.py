"""The mirror game page (/game) in a real headless Chromium with its CSP in force: two robots
play, and a person's hands reach the robot; its messages are checked like the dashboard's."""

from __future__ import annotations

import json

import pytest

from rnnpb.web import ProtocolError, parse_client_message

from .test_browser import WATCH_CSP, _until, browser  # noqa: F401 — the browser fixture


def _game_page(browser, server):  # noqa: F811
    page = browser.new_page(viewport={"width": 1200, "height": 800})
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    page.add_init_script(WATCH_CSP)
    page.goto(server.url.rstrip("/") + "/game")
    return page, errors


def test_two_robots_play_and_the_page_shows_the_measures(browser, server, tmp_path):  # noqa: F811
    page, errors = _game_page(browser, server)
    try:
        _until(page, "document.querySelector('#model').options.length > 0", 30000)
        page.select_option("#mode", "robots")
        page.click("#start")
        _until(page, "/step [1-9][0-9]/.test(document.querySelector('#time').textContent)", 90000)
        meter = float(page.eval_on_selector("#meter", "m => m.value"))
        assert 0.0 <= meter <= 1.0
        assert "of" in page.text_content("#found")
        page.screenshot(path=str(tmp_path / "game.png"))
        # The person's hands: the page sends them and the robot sees them.
        page.select_option("#mode", "person")
        page.click("#start")
        _until(page, "/step [1-9][0-9]/.test(document.querySelector('#time').textContent)", 90000)
        box = page.locator("#view").bounding_box()
        page.mouse.move(box["x"] + 0.62 * box["width"], box["y"] + 0.45 * box["height"])
        page.mouse.down()
        page.mouse.move(box["x"] + 0.70 * box["width"], box["y"] + 0.35 * box["height"])
        page.mouse.up()
        page.click("#stop")
        _until(page, "document.querySelector('#status').textContent.startsWith('stopped')", 20000)
        violations = page.evaluate("window.__cspViolations || []")
        assert not violations, violations
    finally:
        page.close()
    assert not errors, f"the page raised: {errors}"


@pytest.mark.parametrize(
    "message, problem",
    [
        ({"type": "game", "action": "fly", "mode": "person", "model": None}, "game action"),
        ({"type": "game", "action": "start", "mode": "solo", "model": None}, "game mode"),
        ({"type": "game", "action": "start", "mode": "person", "model": 3}, "game model"),
        ({"type": "game", "action": "start", "mode": "person"}, "needs field"),
        ({"type": "game_hands", "hands": [0.1, 0.2, 2.0, 0.5]}, "rhy"),
        ({"type": "game_hands", "hands": [0.1, 0.2]}, "4 values"),
    ],
)
def test_bad_game_messages_are_refused(message, problem):
    with pytest.raises(ProtocolError, match=problem):
        parse_client_message(json.dumps(message))


def test_game_messages_are_normalized():
    hands = parse_client_message(json.dumps({"type": "game_hands", "hands": [0.1, None, 0.5, 1]}))
    assert hands["type"] == "game_hands" and hands["hands"][2] == 0.5
    start = parse_client_message(
        json.dumps({"type": "game", "action": "start", "mode": "robots", "model": "set1"})
    )
    assert start == {"type": "game", "action": "start", "mode": "robots", "model": "set1"}
