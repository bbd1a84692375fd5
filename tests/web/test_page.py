"""The dashboard page as a person first meets it in Chromium, with the real mouse: the game is
a click away, nothing empty shows, and starting the robot does not move the page."""

from __future__ import annotations

import pytest

from .test_browser import _mouse_click, _shot, _strict_page, _until, browser  # noqa: F401


def test_the_game_is_a_click_away(browser, server):  # noqa: F811
    with _strict_page(browser, server) as page:
        _mouse_click(page, "a[href='/game']")
        page.wait_for_url("**/game", timeout=10000)
        _until(page, "document.querySelector('#model').options.length > 0", 30000)
        # ...and the game leads back.
        _mouse_click(page, "a[href='/']")
        page.wait_for_url(server.url, timeout=10000)


def test_nothing_empty_shows_at_load(browser, server):  # noqa: F811
    with _strict_page(browser, server) as page:
        # Nothing was taught: there is nothing to rename, so no Rename row with an empty list.
        assert page.evaluate("rnnpbDashboard.state.teaching.taught") == []
        assert page.locator("#rename").is_hidden()
        # Every element the page hides is hidden, whatever its style says.
        shown = page.evaluate(
            "() => [...document.querySelectorAll('[hidden]')]"
            ".filter((e) => getComputedStyle(e).display !== 'none').map((e) => e.id)"
        )
        assert shown == []


@pytest.mark.parametrize("width", [1400, 1100, 800])
def test_starting_the_robot_does_not_move_the_page(browser, server, width):  # noqa: F811
    with _strict_page(browser, server) as page:
        page.set_viewport_size({"width": width, "height": 900})
        _mouse_click(page, "#reset")
        _until(page, "!rnnpbDashboard.state.running")
        before = page.locator("main").bounding_box()
        toolbar = page.locator(".toolbar").bounding_box()
        _mouse_click(page, "#start")
        # Running, with a step number of three digits in the status line.
        _until(
            page,
            "rnnpbDashboard.state.running && rnnpbDashboard.lastStep"
            " && rnnpbDashboard.lastStep.step >= 100",
            60000,
        )
        after = page.locator("main").bounding_box()
        _shot(page, f"toolbar-running-{width}", ".toolbar")
        _mouse_click(page, "#stop")
        assert after["y"] == before["y"], f"the page moved {after['y'] - before['y']:.0f} px"
        assert page.locator(".toolbar").bounding_box()["height"] == toolbar["height"]
