"""The dashboard in a real headless Chromium: the page loads, the 3-D robot is drawn, and a
scripted mouse tracing a learned pattern makes the robot recognise it.

These tests need Chromium at /usr/bin/chromium (scripts/setup.sh installs it) and fail, not
skip, when it cannot run.
"""

from __future__ import annotations

import contextlib
import json
import time
from pathlib import Path

import numpy as np
import pytest

CHROMIUM = Path("/usr/bin/chromium")
FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
    "--disable-quic",
]
TRACE_DT = 0.4
"""The step while the mouse traces: one scripted sample (two drags) must fit in one step."""
TRACE_SAMPLES = 40
RECOGNISED_WITHIN = 25
"""Samples of the traced pattern after which the PB must be nearest to its learned PB."""


@pytest.fixture(scope="module")
def browser():
    if not CHROMIUM.exists():
        pytest.fail(
            f"{CHROMIUM} is missing: install it (apt-get install chromium, or "
            "WITH_BROWSER=1 scripts/setup.sh); the dashboard tests need a browser"
        )
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
    # Playwright evaluates a string predicate of wait_for_function with eval(), which the
    # page's CSP refuses; the tests below that load the page with its CSP in force
    # (_strict_page) wait with function predicates instead.
    page = browser.new_page(viewport={"width": 1400, "height": 1000}, bypass_csp=True)
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    page.goto(server.url)
    page.wait_for_function(
        "window.rnnpbDashboard && rnnpbDashboard.state && "
        "rnnpbDashboard.state.model && !rnnpbDashboard.state.loading",
        timeout=60000,
    )
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
    page.wait_for_function(
        "rnnpbDashboard.steps > 5 && rnnpbDashboard.rendered3d > 2", timeout=20000
    )
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
    page.wait_for_function(
        "document.querySelector('#camera-message').textContent.includes('still driven by')",
        timeout=15000,
    )
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
    # Both markers are traced, one drag each: the other hand does not follow the dragged one.
    page.select_option("#other-hand", "still")
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
                "[rnnpbDashboard.lastStep.step, rnnpbDashboard.lastStep.pb]",
                timeout=10000,
            )
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
        seen_there = (
            f"rnnpbDashboard.lastStep.observed.every((v, i) => Math.abs(v - {expected}[i]) < 0.01)"
        )
        done = page.evaluate("rnnpbDashboard.lastStep.step")
        there = page.wait_for_function(
            f"rnnpbDashboard.lastStep.step > {done} && {seen_there}"
            " && rnnpbDashboard.lastStep.step",
            timeout=10000,
        )
        later = page.wait_for_function(
            f"rnnpbDashboard.lastStep.step > {there.json_value()} "
            "&& rnnpbDashboard.lastStep.observed",
            timeout=10000,
        )
        np.testing.assert_allclose(
            np.array(later.json_value(), dtype=float), sensory[-1], atol=0.01
        )
    finally:
        page.click("#stop")
    elapsed = time.monotonic() - started
    first = next((i for i, name in enumerate(nearest) if name == pattern), None)
    assert first is not None and first <= RECOGNISED_WITHIN, (
        f"pattern {pattern} not recognised within {RECOGNISED_WITHIN} samples: {nearest} "
        f"(started nearest {start_nearest}; {elapsed:.1f} s)"
    )
    tail = nearest[-10:]
    assert tail.count(pattern) >= 6, f"the PB did not stay near pattern {pattern}: {nearest}"
    print(
        f"mouse-traced pattern {pattern}: nearest learned PB from sample {first} on "
        f"(started nearest {start_nearest}); {''.join(nearest)}"
    )


# --- hostile text, the CSP and foreign pages (docs/robustness.md) ------------------------
HOSTILE_NAME = '<img src=x onerror="window.__injected = (window.__injected || 0) + 1">'
"""A pattern or model name as a hostile model file could carry it: markup whose error
handler would run script in the dashboard's origin if the page ever parsed it as HTML."""
FAST_DT = 0.05
"""The step while names are checked: only the page's rendering is under test."""
WATCH_CSP = (
    "window.__cspViolations = [];"
    "document.addEventListener('securitypolicyviolation', (e) =>"
    " window.__cspViolations.push(`${e.violatedDirective} ${e.blockedURI}`));"
)


def _rewrite_names(route) -> None:
    """Pass the page's WebSocket through to the server, renaming learned pattern "1" and the
    model to :data:`HOSTILE_NAME` in everything the server sends (state, steps, errors):
    the page gets the text a hostile model would bring, whatever the server checks when a
    model is loaded."""
    server = route.connect_to_server()

    def rename(value):
        return HOSTILE_NAME if value in ("1", "set1.npz") else value

    def forward(text) -> None:
        message = json.loads(text)
        if message["type"] == "state":
            message["models"] = [rename(m) for m in message["models"]]
            message["model"] = rename(message["model"])
            message["patterns"] = [rename(p) for p in message["patterns"]]
            message["pattern_pb"] = {rename(k): v for k, v in message["pattern_pb"].items()}
        elif message["type"] == "step":
            message["nearest"] = rename(message["nearest"])
            message["truth"] = rename(message["truth"])
            message["recognised"] = rename(message.get("recognised"))
            message["pattern_confidence"] = {
                rename(k): v for k, v in (message.get("pattern_confidence") or {}).items()
            }
        elif message["type"] == "error":
            message["message"] = f"{message['message']} {HOSTILE_NAME}"
        route.send(json.dumps(message))

    server.on_message(forward)


def _until(page, condition: str, timeout: float = 10000):
    """wait_for_function under the page's CSP: a function predicate, not an eval'd string."""
    return page.wait_for_function(f"() => ({condition})", timeout=timeout)


def _mouse_click(page, selector: str) -> None:
    """Click ``selector`` as a person does: the mouse moved to its middle, pressed and let go."""
    box = page.locator(selector).bounding_box()
    assert box is not None, f"{selector} is not shown"
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2, steps=4)
    page.mouse.click(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)


def _swing(page, start, path, seconds: float, period_s: float) -> None:
    """Press the mouse at ``start`` (page pixels) and move it along ``path(phase)`` (page
    pixels, phase in [0, 1) of a cycle) for ``seconds``, a cycle every ``period_s``, as a
    hand does: as often as the browser takes the moves (tens a second), then let go."""
    page.mouse.move(*start)
    page.mouse.down()
    began = time.monotonic()
    while (elapsed := time.monotonic() - began) < seconds:
        page.mouse.move(*path((elapsed / period_s) % 1.0))
        page.wait_for_timeout(15)
    page.mouse.up()


@contextlib.contextmanager
def _strict_page(browser, server, route_ws=None):
    """The dashboard with its CSP in force, violations and page errors recorded."""
    page = browser.new_page(viewport={"width": 1400, "height": 1000})
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    page.add_init_script(WATCH_CSP)
    if route_ws is not None:
        page.route_web_socket("**/ws", route_ws)
    try:
        page.goto(server.url)
        _until(
            page,
            "window.rnnpbDashboard && rnnpbDashboard.state && "
            "rnnpbDashboard.state.model && !rnnpbDashboard.state.loading",
            60000,
        )
        yield page
    finally:
        page.close()
    assert not errors, f"the page raised: {errors}"


@contextlib.contextmanager
def _strict_page_any(browser, server, route_ws=None):
    """As :func:`_strict_page`, but ready once the first state arrived, model or not."""
    page = browser.new_page(viewport={"width": 1400, "height": 1000})
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    page.add_init_script(WATCH_CSP)
    if route_ws is not None:
        page.route_web_socket("**/ws", route_ws)
    try:
        page.goto(server.url)
        _until(page, "window.rnnpbDashboard && rnnpbDashboard.state", 60000)
        yield page
    finally:
        page.close()
    assert not errors, f"the page raised: {errors}"


def _send(page, message: str, condition: str) -> None:
    page.evaluate(f"rnnpbDashboard.send({message})")
    _until(page, condition)


def test_names_from_a_model_file_show_as_text_and_run_no_script(browser, server):
    with _strict_page(browser, server, _rewrite_names) as page:
        _send(page, f'{{type: "dt", dt: {FAST_DT}}}', f"rnnpbDashboard.state.dt === {FAST_DT}")
        _send(
            page,
            '{type: "mode", mode: "demonstrator"}',
            "rnnpbDashboard.state.mode === 'demonstrator'",
        )
        _send(
            page,
            '{type: "pattern", pattern: "1"}',
            "rnnpbDashboard.state.demonstrator_pattern === '1'",
        )
        page.click("#reset")
        page.click("#start")
        _until(
            page,
            "rnnpbDashboard.steps > 3 && rnnpbDashboard.lastStep.nearest === "
            f"{json.dumps(HOSTILE_NAME)}",
            30000,
        )
        page.click("#stop")
        _send(page, '{type: "model", name: "nope.npz"}', "rnnpbDashboard.errors.length > 0")
        page.wait_for_timeout(500)  # time for an image error handler to have run
        # The demonstrator cannot perform a pattern of that name: the note under its buttons
        # names it (as a name of the user's own would be).
        assert HOSTILE_NAME in page.text_content("#patterns-note")
        # The recognition readout may say "not sure"; the nearest learned PB and the
        # confidence bars name every learned pattern.
        assert HOSTILE_NAME in page.text_content("#nearest-distance")
        assert HOSTILE_NAME in page.text_content("#confidence-bars")
        assert HOSTILE_NAME in page.text_content("#error")
        assert page.locator("#model option").all_text_contents() == [HOSTILE_NAME]
        # The text stayed text everywhere: no element was made of it, no handler ran.
        assert page.evaluate("document.querySelectorAll('img:not(#frame)').length") == 0
        assert page.evaluate("window.__injected") is None
        assert page.evaluate("window.__cspViolations") == []


def test_the_page_works_under_its_csp_and_the_csp_stops_inline_script(browser, server):
    with _strict_page(browser, server) as page:
        # app.js and three.js ran under the CSP: the robot moves and is drawn, the plots and
        # the timing table are filled, and nothing was refused.
        page.click("#reset")
        page.click("#start")
        _until(page, "rnnpbDashboard.steps > 3 && rnnpbDashboard.rendered3d > 2", 20000)
        page.click("#stop")
        assert page.evaluate("rnnpbDashboard.connected")
        assert "mirror" in page.text_content("#timings")
        assert page.locator("#joint-legend .line").count() == 4
        assert page.evaluate("window.__cspViolations") == []
        # Were some later change to put markup into the page, its script would still not run.
        page.evaluate("""document.body.insertAdjacentHTML('beforeend',
            '<img id="probe" src="x" onerror="window.__inline = 1">')""")
        _until(page, "window.__cspViolations.length > 0")
        page.wait_for_timeout(300)
        assert page.evaluate("window.__inline") is None
        assert any("script-src" in v for v in page.evaluate("window.__cspViolations"))


def _attack_page(port: int) -> str:
    """The attack: a page from elsewhere, open in the same browser, opens the dashboard's
    WebSocket, sets dt and switches to the mouse (it could as well start the robot and
    switch to the webcam, whose frames every connection receives)."""
    return f"""<!doctype html><title>another site</title><script>
      window.result = {{opened: false, closed: false, messages: 0}};
      const ws = new WebSocket("ws://127.0.0.1:{port}/ws");
      ws.onopen = () => {{
        window.result.opened = true;
        ws.send(JSON.stringify({{type: "dt", dt: 4.25}}));
        ws.send(JSON.stringify({{type: "mode", mode: "pointer"}}));
      }};
      ws.onmessage = () => {{ window.result.messages += 1; }};
      ws.onclose = () => {{ window.result.closed = true; }};
    </script>"""


@contextlib.contextmanager
def _other_site(body: str):
    """Serves ``body`` from another origin on this computer (loopback, another port), as a
    local web app or a downloaded page served by ``python -m http.server`` would."""
    import http.server
    import threading

    class Page(http.server.BaseHTTPRequestHandler):
        def do_GET(self) -> None:  # noqa: N802 — the standard library's name
            data = body.encode()
            self.send_response(200)
            self.send_header("Content-Type", "text/html; charset=utf-8")
            self.send_header("Content-Length", str(len(data)))
            self.end_headers()
            self.wfile.write(data)

        def log_message(self, *args) -> None:
            pass

    site = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Page)
    thread = threading.Thread(target=site.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://localhost:{site.server_port}/"
    finally:
        site.shutdown()
        site.server_close()


@pytest.mark.parametrize("where", ["another origin", "a file"])
def test_a_page_from_another_site_cannot_drive_the_robot(browser, server, tmp_path, where):
    attack = _attack_page(server.port)
    dt_before, mode_before = server.session.dt, server.session.mode
    page = browser.new_page()
    try:
        with contextlib.ExitStack() as stack:
            if where == "a file":  # its Origin is "null"
                (tmp_path / "attack.html").write_text(attack)
                url = (tmp_path / "attack.html").as_uri()
            else:
                url = stack.enter_context(_other_site(attack))
            page.goto(url)
            _until(page, "window.result.closed || window.result.messages > 0", 15000)
            result = page.evaluate("window.result")
            page.wait_for_timeout(500)  # time for sent commands to have been applied
    finally:
        page.close()
    assert result == {"opened": False, "closed": True, "messages": 0}
    assert (server.session.dt, server.session.mode) == (dt_before, mode_before)


# --- a dashboard that never misleads (docs/dashboard.md, "What the page tells you") -------
def _shot(page, name: str, selector: str | None = None) -> Path:
    """A screenshot, kept in the folder ``RNNPB_SCREENSHOTS`` names (to look at) or in a
    temporary one."""
    import os
    import tempfile

    folder = Path(os.environ.get("RNNPB_SCREENSHOTS") or tempfile.mkdtemp())
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}.png"
    (page.locator(selector) if selector else page).screenshot(path=str(path))
    return path


def _restyle(transform):
    """A WebSocket route passing messages through, each state message changed by
    ``transform(state)`` on its way to the page."""

    def route(ws_route) -> None:
        server = ws_route.connect_to_server()

        def forward(text) -> None:
            message = json.loads(text)
            if message["type"] == "state":
                transform(message)
            ws_route.send(json.dumps(message))

        server.on_message(forward)

    return route


def test_a_model_that_cannot_be_used_is_explained_and_start_is_off(browser, server):
    reason = "models/bad.npz: not a readable rnnpb model file (truncated or not an archive)"

    def no_model(state):
        state.update(model=None, patterns=[], pattern_pb={}, model_error=reason, error=reason)

    with _strict_page_any(browser, server, _restyle(no_model)) as page:
        _until(page, "document.querySelector('#error').textContent.includes('not a readable')")
        assert not page.locator("#error").is_hidden()
        assert page.locator("#start").is_disabled()
        assert "no model loaded" in page.text_content("#status")
        assert "not a readable" in page.get_attribute("#start", "title")


def test_user_named_patterns_offer_only_what_the_demonstrator_performs(browser, server):
    def user_names(state):
        pbs = list(state["pattern_pb"].values())
        state["patterns"] = ["wave", "clap", "2"][: len(pbs)]
        state["pattern_pb"] = dict(zip(state["patterns"], pbs, strict=False))

    with _strict_page(browser, server, _restyle(user_names)) as page:
        _until(page, "document.querySelectorAll('#patterns button').length === 9")
        buttons = page.locator("#patterns button").all_text_contents()
        offered = page.eval_on_selector_all(
            "#patterns button", "(all) => all.map((b) => b.dataset.pattern)"
        )
        assert offered == [
            "1",
            "2",
            "3",
            "4",
            "one-arm",
            "asymmetric",
            "figure-eight",
            "diagonal",
            "pause",
        ]
        assert "not learned" in buttons[0] and "not learned" not in buttons[1]
        assert not any("wave" in b or "clap" in b for b in buttons)
        note = page.text_content("#patterns-note")
        assert "wave" in note and "clap" in note and "pointer" in note


def test_a_reload_keeps_the_plots_and_reset_and_stop_say_what_the_values_are(page, browser, server):
    _set(page, f'{{type: "dt", dt: {FAST_DT}}}', f"rnnpbDashboard.state.dt === {FAST_DT}")
    page.click("#reset")
    page.click("#start")
    page.wait_for_function("rnnpbDashboard.history.length >= 40", timeout=20000)
    other = browser.new_page(viewport={"width": 1400, "height": 1000}, bypass_csp=True)
    try:
        other.goto(server.url)
        # A new tab has the run's recent steps before its first live step arrives.
        other.wait_for_function("rnnpbDashboard.replayed >= 40", timeout=10000)
        assert other.text_content("#nearest") != "—"
    finally:
        other.close()
    page.click("#stop")
    page.wait_for_function("!rnnpbDashboard.state.running")
    assert "stopped" in page.text_content("#readouts-note")
    page.click("#reset")
    page.wait_for_function(
        "rnnpbDashboard.state.steps === 0 && rnnpbDashboard.history.length === 0"
    )
    assert page.text_content("#nearest") == "—" and page.text_content("#step") == "0"
    assert page.text_content("#readouts-note") == ""


def test_controls_are_off_while_disconnected_and_a_command_then_is_not_lost_silently(
    browser, server
):
    routes = []

    def keep(ws_route) -> None:
        routes.append(ws_route)
        ws_route.connect_to_server()

    with _strict_page(browser, server, keep) as page:
        assert page.locator("#start").is_enabled() or page.evaluate("rnnpbDashboard.state.running")
        routes[-1].close()
        _until(page, "!rnnpbDashboard.connected")
        for control in (
            "#start",
            "#stop",
            "#reset",
            "#model",
            "#dt",
            "#camera-open",
            ".tab[data-mode=pointer]",
            "#patterns button >> nth=0",
        ):
            assert page.locator(control).is_disabled(), control
        assert "disconnected" in page.text_content("#status")
        assert page.evaluate("rnnpbDashboard.send({type: 'control', action: 'start'})") is False
        assert "not connected" in page.text_content("#error")
        _until(
            page, "rnnpbDashboard.connected && !document.querySelector('#reset').disabled", 15000
        )


def test_the_plots_mark_switches_and_pauses_and_the_views_read_well(page, server):
    _set(page, f'{{type: "dt", dt: {FAST_DT}}}', f"rnnpbDashboard.state.dt === {FAST_DT}")
    _set(
        page, '{type: "mode", mode: "demonstrator"}', "rnnpbDashboard.state.mode === 'demonstrator'"
    )
    _set(
        page, '{type: "pattern", pattern: "1"}', "rnnpbDashboard.state.demonstrator_pattern === '1'"
    )
    page.click("#reset")
    page.click("#start")
    page.wait_for_function("rnnpbDashboard.history.length >= 30", timeout=20000)
    page.click("#patterns button[data-pattern='2']")
    page.wait_for_function(
        "rnnpbDashboard.history.filter((s) => s.truth === '2').length > 25", timeout=20000
    )
    page.click("#patterns button[data-pattern='pause']")
    page.wait_for_function(
        "rnnpbDashboard.history.filter((s) => s.truth === 'pause').length > 10", timeout=20000
    )
    page.click("#patterns button[data-pattern='2']")
    page.wait_for_function(
        "rnnpbDashboard.history.slice(-10).every((s) => s.truth === '2')", timeout=20000
    )
    page.click("#stop")
    marks = page.evaluate("rnnpbDashboard.plotMarks")
    assert marks["switches"] >= 1 and marks["pauses"] >= 1, marks
    page.wait_for_timeout(600)  # the 3-D view eases to the last pose
    for name, selector in (
        ("page", None),
        ("view3d", "#view3d canvas"),
        ("plots", ".panel.plots"),
        ("pb", "#plot-pb"),
    ):
        assert _shot(page, name, selector).stat().st_size > 1000


def test_learned_points_that_coincide_are_drawn_apart(browser, server):
    def coincide(state):
        pbs = list(state["pattern_pb"].values())
        state["pattern_pb"] = {name: pbs[0] for name in state["pattern_pb"]}

    with _strict_page(browser, server, _restyle(coincide)) as page:
        _until(page, "rnnpbDashboard.pbMarkers && rnnpbDashboard.pbMarkers.length === 3")
        markers = page.evaluate("rnnpbDashboard.pbMarkers")
        for i, a in enumerate(markers):
            for b in markers[i + 1 :]:
                assert np.hypot(a["x"] - b["x"], a["y"] - b["y"]) >= 16, markers


def test_switching_models_shows_the_one_loading_and_the_robot_goes_on(browser, model_dir, tmp_path):
    import shutil

    from rnnpb.web import DashboardServer, find_models

    folder = tmp_path / "models"
    folder.mkdir()
    for name in ("a.npz", "b.npz"):
        shutil.copy(model_dir / "set1.npz", folder / name)
    with (
        DashboardServer(
            find_models(folder), port=0, dt=FAST_DT, workdir=tmp_path / "sessions"
        ) as dashboard,
        _strict_page(browser, dashboard) as page,
    ):
        page.click("#start")
        _until(page, "rnnpbDashboard.steps > 3")
        page.select_option("#model", "b.npz")
        # The choice stays chosen and the status names it while it loads ...
        _until(page, "rnnpbDashboard.state.loading || rnnpbDashboard.state.model === 'b.npz'")
        assert page.input_value("#model") == "b.npz"
        if page.evaluate("rnnpbDashboard.state.loading"):
            assert "b.npz" in page.text_content("#status")
        # ... and the robot runs on with the new model.
        _until(
            page,
            "rnnpbDashboard.state.model === 'b.npz' && rnnpbDashboard.state.running"
            " && rnnpbDashboard.lastStep !== null",
            60000,
        )
        assert page.input_value("#model") == "b.npz"
        assert "model b.npz" in page.text_content("#status")
        page.click("#stop")


def test_the_readout_names_the_pattern_taking_over_while_recognition_confirms_it(page):
    # Recognition holds "1" for a few steps after the person switched to 3 (no flicker);
    # the readout does not say "1 (0 %)" while 3 is already the likely one.
    said = page.evaluate(
        """rnnpbDashboard.readout({recognised: "1", confidence: 0.0001, novelty: "familiar",
            pattern_confidence: {"1": 0.0001, "2": 0.0, "3": 0.93}})"""
    )
    assert said.startswith("3") and "93 %, confirming; was 1" in said
    # Not while no other pattern is more likely than not.
    said = page.evaluate(
        """rnnpbDashboard.readout({recognised: "1", confidence: 0.2, novelty: "familiar",
            pattern_confidence: {"1": 0.2, "2": 0.0, "3": 0.4}})"""
    )
    assert said.startswith("1") and "20 %" in said
