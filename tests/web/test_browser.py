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
    # Playwright evaluates a string predicate of wait_for_function with eval(), which the
    # page's CSP refuses; the tests below that load the page with its CSP in force
    # (_strict_page) wait with function predicates instead.
    page = browser.new_page(viewport={"width": 1400, "height": 1000}, bypass_csp=True)
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


# --- hostile text, the CSP and foreign pages (docs/robustness.md) ------------------------
HOSTILE_NAME = '<img src=x onerror="window.__injected = (window.__injected || 0) + 1">'
"""A pattern or model name as a hostile model file could carry it: markup whose error
handler would run script in the dashboard's origin if the page ever parsed it as HTML."""
FAST_DT = 0.05
"""The step while names are checked: only the page's rendering is under test."""
WATCH_CSP = ("window.__cspViolations = [];"
             "document.addEventListener('securitypolicyviolation', (e) =>"
             " window.__cspViolations.push(`${e.violatedDirective} ${e.blockedURI}`));")


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
        elif message["type"] == "error":
            message["message"] = f"{message['message']} {HOSTILE_NAME}"
        route.send(json.dumps(message))

    server.on_message(forward)


def _until(page, condition: str, timeout: float = 10000):
    """wait_for_function under the page's CSP: a function predicate, not an eval'd string."""
    return page.wait_for_function(f"() => ({condition})", timeout=timeout)


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
        _until(page, "window.rnnpbDashboard && rnnpbDashboard.state && "
                     "rnnpbDashboard.state.model && !rnnpbDashboard.state.loading", 60000)
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
        _send(page, '{type: "mode", mode: "demonstrator"}',
              "rnnpbDashboard.state.mode === 'demonstrator'")
        _send(page, '{type: "pattern", pattern: "1"}',
              "rnnpbDashboard.state.demonstrator_pattern === '1'")
        page.click("#reset")
        page.click("#start")
        _until(page, "rnnpbDashboard.steps > 3 && rnnpbDashboard.lastStep.nearest === "
                     f"{json.dumps(HOSTILE_NAME)}", 30000)
        page.click("#stop")
        _send(page, '{type: "model", name: "nope.npz"}', "rnnpbDashboard.errors.length > 0")
        page.wait_for_timeout(500)  # time for an image error handler to have run
        buttons = page.locator("#patterns button").all_text_contents()
        assert any(f"Pattern {HOSTILE_NAME}" in text for text in buttons), buttons
        assert HOSTILE_NAME in page.text_content("#nearest")
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
