"""The dashboard's words in a real headless Chromium: an error goes once the next command
worked, a refused step time does not stay in its field, and only a learned pattern is shown
as one."""

from __future__ import annotations

from .test_browser import _restyle, _set, _strict_page, _until, browser, page  # noqa: F401


def test_an_error_goes_when_the_next_command_works_and_a_refused_dt_is_not_kept(
    page,  # noqa: F811
    server,
):
    page.evaluate('rnnpbDashboard.send({type: "model", name: "no-such-model.npz"})')
    page.wait_for_function("!document.querySelector('#error').hidden", timeout=10000)
    assert "no-such-model" in page.text_content("#error")
    page.evaluate('rnnpbDashboard.send({type: "control", action: "reset"})')
    # Well before the 8 s after which an error would go anyway.
    page.wait_for_function("document.querySelector('#error').hidden", timeout=3000)
    # A step time out of range: refused, said so, and the field shows the session's again.
    running_at = page.evaluate("rnnpbDashboard.state.dt")
    page.fill("#dt", "9")
    page.dispatch_event("#dt", "change")
    assert "dt must be" in page.text_content("#error")
    assert float(page.input_value("#dt")) == running_at


def test_only_a_learned_pattern_is_shown_as_recognised(page, server):  # noqa: F811
    # The server is shared with the other dashboard tests: say what the robot sees (the
    # demonstrator performing learned pattern 1 of the shipped model) rather than inherit it.
    loaded = "rnnpbDashboard.state.model === 'set1.npz' && !rnnpbDashboard.state.loading"
    _set(page, '{type: "model", name: "set1.npz"}', loaded)
    _set(
        page, '{type: "mode", mode: "demonstrator"}', "rnnpbDashboard.state.mode === 'demonstrator'"
    )
    _set(
        page, '{type: "pattern", pattern: "1"}', "rnnpbDashboard.state.demonstrator_pattern === '1'"
    )
    page.click("#reset")
    page.click("#start")
    try:
        # At first the robot is not sure: neither the readout nor the teaching line says it
        # as if it were a pattern.
        # Generous bounds: on a busy machine the session's steps come slower (these wait for
        # what the page shows, they time nothing).
        page.wait_for_function("rnnpbDashboard.lastStep !== null", timeout=60000)
        page.wait_for_function(
            "document.querySelector('#nearest').textContent.startsWith('not sure')",
            timeout=60000,
        )
        assert page.eval_on_selector("#nearest", "n => n.classList.contains('unsure')")
        assert "sees not sure" not in page.text_content("#teach-text")
        # Then the demonstrator's pattern: shown as recognised, no longer in the unsure style.
        page.wait_for_function(
            "document.querySelector('#nearest').textContent.includes('%')"
            " && !document.querySelector('#nearest').classList.contains('unsure')",
            timeout=90000,
        )
    finally:
        page.click("#stop")


def test_a_long_pattern_name_is_written_whole_inside_the_pb_plot(browser, server):  # noqa: F811
    def rename(state):
        state["pattern_pb"] = {
            f"new-{k + 1}": pb for k, pb in enumerate(state["pattern_pb"].values())
        }

    with _strict_page(browser, server, _restyle(rename)) as shown:
        _until(shown, "rnnpbDashboard.pbMarkers && rnnpbDashboard.pbMarkers.length === 3")
        shown.wait_for_timeout(300)
        for marker in shown.evaluate("rnnpbDashboard.pbMarkers"):
            assert 0 <= marker["labelLeft"] < marker["labelRight"] <= marker["width"], marker
