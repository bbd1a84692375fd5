"""What a hostile web page, a forged request or a hostile client cannot do to the dashboard:
read it under a foreign ``Host`` name (DNS rebinding), open its WebSocket from a foreign
origin, or drop a connection with a number too large for a float; and the page goes out with
its Content-Security-Policy (docs/robustness.md, "The dashboard's origin, host and input
checks")."""

from __future__ import annotations

import contextlib
import json
import logging
import re
import socket
import threading
import time
import urllib.error
import urllib.request

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect

from rnnpb.errors import ConfigError
from rnnpb.web import (
    CONTENT_SECURITY_POLICY,
    STATIC_DIR,
    AccessPolicy,
    CommandLimits,
    DashboardServer,
    ProtocolError,
    Session,
    create_app,
    find_models,
    parse_client_message,
)

UNLIMITED = CommandLimits(commands_per_s=1e9, command_burst=1e9, hands_per_s=1e9, hands_burst=1e9)
"""Rate limits no test sends enough to reach (they are tested in test_session_robustness)."""
HUGE = 10**309
"""An integer beyond the largest float (about 1.8e308)."""


@pytest.fixture(scope="module")
def idle_session(model_dir, tmp_path_factory):
    """A session that is never started: commands queue up and are never applied, so any
    stream of messages can be sent to its app without moving the shared robot."""
    session = Session(
        find_models(model_dir), workdir=tmp_path_factory.mktemp("idle"), max_queued_commands=100_000
    )
    yield session
    session.close()


@contextlib.contextmanager
def _serving(app):
    """``app`` on a free loopback port, served as ``DashboardServer`` serves it; yields the
    port. (Starlette's TestClient warns that it wants httpx2, which this project does not
    install, so the tests use real connections.)"""
    import uvicorn

    from rnnpb.web import WS_MAX_SIZE

    server = uvicorn.Server(
        uvicorn.Config(
            app,
            host="127.0.0.1",
            port=0,
            log_level="warning",
            ws="websockets-sansio",
            ws_max_size=WS_MAX_SIZE,
            lifespan="off",
        )
    )
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    deadline = time.monotonic() + 10
    while not server.started:
        assert thread.is_alive() and time.monotonic() < deadline, "the server did not start"
        time.sleep(0.02)
    try:
        yield server.servers[0].sockets[0].getsockname()[1]
    finally:
        server.should_exit = True
        thread.join(timeout=10)


def _get(server, path: str, host: str | None = None) -> tuple[int, bytes]:
    return _request(server.port, path, host)


def _request(port: int, path: str, host: str | None = None) -> tuple[int, bytes]:
    """GET ``path`` from the server on ``port`` with ``host`` in the Host header."""
    request = urllib.request.Request(f"http://127.0.0.1:{port}{path}")
    if host is not None:
        request.add_header("Host", host)
    try:
        with urllib.request.urlopen(request, timeout=10) as response:
            return response.status, response.read()
    except urllib.error.HTTPError as error:
        return error.code, error.read()


def _ws_url(server) -> str:
    return server.url.replace("http", "ws") + "ws"


def _ws_as(port: int, host: str, origin: str | None = None):
    """A WebSocket to the server on ``port`` that names ``host`` in its Host header, as a
    browser does that reached the server under that name."""
    sock = socket.create_connection(("127.0.0.1", port), timeout=10)
    headers = {} if origin is None else {"Origin": origin}
    return connect(f"ws://{host}/ws", sock=sock, additional_headers=headers, open_timeout=10)


def _refused(port: int, host: str, origin: str | None = None) -> int:
    """The HTTP status that refused the handshake (fails if it opened)."""
    with pytest.raises(InvalidStatus) as refused, _ws_as(port, host, origin):
        pass
    return refused.value.response.status_code


def _next(ws, kind: str, timeout: float = 10.0) -> dict:
    deadline = time.monotonic() + timeout
    while True:
        message = json.loads(ws.recv(timeout=max(0.01, deadline - time.monotonic())))
        if message["type"] == kind:
            return message


# --- Host: DNS rebinding -------------------------------------------------------------------
@pytest.mark.parametrize(
    "host",
    [
        "evil.example",
        "evil.example:{port}",
        "127.0.0.1.evil.example",
        "localhost.:{port}",
        "0.0.0.0:{port}",
        "[::2]:{port}",
    ],
)
def test_a_request_under_a_foreign_host_name_gets_no_data(server, host):
    # Before the check the recording (there is one as soon as a model is loaded) downloaded
    # under any name, so a page on a name rebound to 127.0.0.1 could read it.
    assert server.session.recording_path is not None
    for path in ("/api/recording.csv", "/api/state", "/", "/static/app.js"):
        status, body = _get(server, path, host=host.format(port=server.port))
        assert status == 400, (path, status, body[:80])
        assert b"lhy" not in body and b"pattern_pb" not in body


@pytest.mark.parametrize(
    "host",
    ["127.0.0.1:{port}", "localhost:{port}", "[::1]:{port}", "LOCALHOST:{port}", "127.0.0.1"],
)
def test_the_loopback_names_are_answered(server, host):
    status, body = _get(server, "/api/state", host=host.format(port=server.port))
    assert status == 200 and json.loads(body)["model"] == "set1.npz"


def test_a_websocket_under_a_foreign_host_name_is_refused(server):
    assert _refused(server.port, f"evil.example:{server.port}") == 400
    assert (
        _refused(server.port, f"evil.example:{server.port}", f"http://evil.example:{server.port}")
        == 400
    )


# --- Origin: other web pages --------------------------------------------------------------
FOREIGN_ORIGINS = [
    "http://evil.example",
    "null",
    "file://",
    "http://evil.example:{port}",
    "http://127.0.0.1:1",
    "https://127.0.0.1:{port}",
    "http://localhost",
    "http://127.0.0.1:{port}.evil.example",
    "chrome-extension://abc",
    "http://user@127.0.0.1:{port}",
    "not an origin",
]


@pytest.mark.parametrize("origin", FOREIGN_ORIGINS)
def test_a_websocket_handshake_from_a_foreign_origin_is_refused(server, caplog, origin):
    origin = origin.format(port=server.port)
    dt_before = server.session.dt
    with caplog.at_level(logging.WARNING, logger="rnnpb.web"):
        with pytest.raises(InvalidStatus) as refused:
            with connect(
                _ws_url(server), additional_headers={"Origin": origin}, open_timeout=10
            ) as ws:
                # Before the check: the page could steer the robot and see the camera.
                ws.send(json.dumps({"type": "dt", "dt": 4.5}))
                time.sleep(0.3)
    assert refused.value.response.status_code == 403
    assert b"--allow-origin" in refused.value.response.body
    assert any("refused a WebSocket" in r.getMessage() for r in caplog.records)
    assert server.session.dt == dt_before


@pytest.mark.parametrize(
    "origin",
    [
        "http://127.0.0.1:{port}",
        "http://localhost:{port}",
        "http://[::1]:{port}",
        "HTTP://LocalHost:{port}",
        None,
    ],
)
def test_the_servers_own_page_and_scripts_without_origin_connect(server, origin):
    headers = {} if origin is None else {"Origin": origin.format(port=server.port)}
    with connect(_ws_url(server), additional_headers=headers, open_timeout=10) as ws:
        assert _next(ws, "state")["model"] == "set1.npz"


def test_allowed_hosts_and_origins_open_the_dashboard_to_a_named_machine(idle_session):
    access = AccessPolicy(hosts=("Robot.Lab",), origins=("https://proxy.lab",))
    with _serving(create_app(idle_session, access)) as port:
        # The page as another machine reaches it: http://robot.lab:8765 (a port forwarded
        # to this one, so the Host's port differs from the listening port).
        assert _request(port, "/api/state", host="robot.lab:8765")[0] == 200
        for origin in (
            "http://robot.lab:8765",
            "https://proxy.lab",
            "https://proxy.lab:443",
            "http://127.0.0.1:8765",
        ):
            with _ws_as(port, "robot.lab:8765", origin) as ws:
                assert _next(ws, "state")["type"] == "state"
        for origin in (
            "http://robot.lab:9000",
            "http://proxy.lab",
            "https://robot.lab:8765",
            "http://evil.example:8765",
        ):
            assert _refused(port, "robot.lab:8765", origin) == 403, origin
        assert _request(port, "/api/state", host="other.lab:8765")[0] == 400


def test_the_listening_address_is_answered_unless_it_means_every_interface(model_dir, tmp_path):
    models = find_models(model_dir)
    opened = DashboardServer(models, host="192.168.7.20", workdir=tmp_path / "a")
    everywhere = DashboardServer(
        models,
        host="0.0.0.0",
        allow_hosts=("robot.lab",),
        allow_origins=("http://robot.lab:9000",),
        workdir=tmp_path / "b",
    )
    try:
        with _serving(opened.app) as port:
            assert _request(port, "/api/state", host="192.168.7.20:8765")[0] == 200
        with _serving(everywhere.app) as port:
            assert _request(port, "/api/state", host="0.0.0.0:8765")[0] == 400  # names no host
            assert _request(port, "/api/state", host="robot.lab:8765")[0] == 200
            with _ws_as(port, "robot.lab:8765", "http://robot.lab:9000") as ws:
                _next(ws, "state")
        # The address printed for 0.0.0.0 is one the server answers.
        assert everywhere.url == "http://127.0.0.1:8765/"
    finally:
        opened.session.close()
        everywhere.session.close()


def test_access_policy_normalizes_names_and_refuses_what_is_not_a_host_or_origin():
    policy = AccessPolicy.for_address(
        "::",
        ["ROBOT.lab", "::1", "fe80::0:1", "10.0.0.2"],
        ["http://Robot.Lab", "https://[::1]:8443/"],
    )
    assert policy.hosts == ("robot.lab", "[fe80::1]", "10.0.0.2")
    assert policy.origins == ("http://robot.lab:80", "https://[::1]:8443")
    assert policy.allowed_hosts[:3] == ("127.0.0.1", "localhost", "[::1]")
    assert AccessPolicy.for_address("0.0.0.0").hosts == ()
    assert AccessPolicy.for_address("localhost").hosts == ()
    for host in ("http://robot.lab", "robot.lab:8765", "*.lab", "robot lab", "", "a/b"):
        with pytest.raises(ConfigError, match="not a host name"):
            AccessPolicy(hosts=(host,))
    for origin in (
        "robot.lab",
        "ftp://robot.lab",
        "http://robot.lab/page",
        "http://:80",
        "http://robot.lab:99999",
        "null",
    ):
        with pytest.raises(ConfigError, match="not a web origin"):
            AccessPolicy(origins=(origin,))
    with pytest.raises(ConfigError, match="not one string"):
        AccessPolicy(hosts="robot.lab")


def test_the_command_line_refuses_a_bad_allowed_host_or_origin(model_dir, capsys):
    from rnnpb.cli import main

    assert main(["serve", "--model", str(model_dir), "--allow-host", "http://robot.lab"]) == 2
    assert "not a host name" in capsys.readouterr().err
    assert main(["serve", "--model", str(model_dir), "--allow-origin", "robot.lab"]) == 2
    assert "not a web origin" in capsys.readouterr().err


# --- the page's headers -------------------------------------------------------------------
def test_every_response_carries_the_content_security_policy(server):
    assert "script-src 'self'" in CONTENT_SECURITY_POLICY
    assert "unsafe-inline" not in CONTENT_SECURITY_POLICY
    assert "unsafe-eval" not in CONTENT_SECURITY_POLICY
    for path in ("/", "/static/app.js", "/api/state", "/api/recording.csv"):
        with urllib.request.urlopen(server.url + path.lstrip("/"), timeout=10) as response:
            assert response.headers["content-security-policy"] == CONTENT_SECURITY_POLICY
            assert response.headers["x-content-type-options"] == "nosniff"
            assert response.headers["x-frame-options"] == "DENY"


def test_the_page_has_no_inline_script_and_its_script_no_html_sink():
    html = (STATIC_DIR / "index.html").read_text()
    scripts = re.findall(r"<script\b[^>]*>", html)
    assert scripts and all(re.search(r'\bsrc="/static/', tag) for tag in scripts)
    assert not re.search(r"<[^>]*\s(on\w+|style)\s*=", html)  # handlers, inline styles
    app = "\n".join(p.read_text() for p in sorted(STATIC_DIR.glob("*.js")))
    assert "app.js" in {p.name for p in STATIC_DIR.glob("*.js")}
    for sink in (
        "innerHTML",
        "outerHTML",
        "insertAdjacentHTML",
        "document.write",
        "eval(",
        "new Function",
        "setAttribute",
    ):
        assert sink not in app, sink


# --- numbers no float can hold ------------------------------------------------------------
HUGE_MESSAGES = [
    (json.dumps({"type": "dt", "dt": HUGE}), "dt must be in"),
    (json.dumps({"type": "dt", "dt": -HUGE}), "dt must be in"),
    ('{"type": "dt", "dt": 1e309}', "dt must be in"),
    ('{"type": "dt", "dt": NaN}', "dt must be in"),
    (json.dumps({"type": "hands", "hands": [0.5, HUGE, 0.5, 0.5]}), "lhz must be in"),
    (json.dumps({"type": "hands", "hands": [-HUGE, 0.5, None, None]}), "lhy must be in"),
    (json.dumps({"type": "camera", "index": HUGE}), "camera index"),
    (json.dumps({"type": "pattern", "pattern": HUGE}), "pattern must be one of"),
    (json.dumps({"type": "mode", "mode": HUGE}), "mode must be one of"),
    (json.dumps({"type": "control", "action": -HUGE}), "action must be one of"),
]


@pytest.mark.parametrize(("text", "reason"), HUGE_MESSAGES, ids=[t[:40] for t, _ in HUGE_MESSAGES])
def test_a_number_beyond_float_gets_an_error_reply_and_the_connection_stays(
    server, caplog, text, reason
):
    with (
        caplog.at_level(logging.WARNING, logger="rnnpb.web"),
        connect(_ws_url(server), open_timeout=10) as ws,
    ):
        _next(ws, "state")
        ws.send(text)
        error = _next(ws, "error")
        assert error["message"].startswith("rejected:") and reason in error["message"]
        assert len(error["message"]) < 200  # the value is summarised, not echoed
        ws.send('{"type": "ping"}')
        _next(ws, "pong")
    assert not [r for r in caplog.records if r.levelno >= logging.ERROR or r.exc_info]


NUMBERS = st.one_of(
    st.integers(),
    st.integers(min_value=-(10**400), max_value=10**400),
    st.sampled_from([HUGE, -HUGE, 2**1024, 2**63, -1, 0, 1, 16, 17]),
    st.floats(),
    st.booleans(),
    st.none(),
)
VALUES = st.recursive(
    st.one_of(
        NUMBERS,
        st.text(max_size=12),
        st.sampled_from(["1", "pause", "start", "webcam", "set1.npz", ""]),
    ),
    lambda inner: (
        st.lists(inner, max_size=5) | st.dictionaries(st.text(max_size=6), inner, max_size=3)
    ),
    max_leaves=8,
)
KINDS = st.one_of(
    st.sampled_from(["hands", "mode", "camera", "pattern", "control", "dt", "model", "ping"]),
    VALUES,
)
FIELDS = ("hands", "mode", "index", "pattern", "action", "dt", "name", "extra")
MESSAGES = st.one_of(
    st.fixed_dictionaries({"type": KINDS}, optional={f: VALUES for f in FIELDS}).map(json.dumps),
    st.fixed_dictionaries(
        {"type": st.just("hands"), "hands": st.lists(NUMBERS, min_size=4, max_size=4)}
    ).map(json.dumps),
    VALUES.map(json.dumps),
    st.text(max_size=40),
)


def test_any_hostile_message_is_answered_or_accepted_and_the_connection_stays(idle_session, caplog):
    """Hypothesis: whatever JSON a client sends, it gets exactly the answer the protocol
    promises (an error for what :func:`parse_client_message` rejects, nothing for a valid
    command, a pong for a ping), on a connection that stays open, with nothing logged above a
    warning."""
    with (
        caplog.at_level(logging.WARNING, logger="rnnpb.web"),
        _serving(create_app(idle_session, limits=UNLIMITED)) as port,
        connect(f"ws://127.0.0.1:{port}/ws", open_timeout=10) as ws,
    ):
        assert json.loads(ws.recv(timeout=10))["type"] == "state"
        assert json.loads(ws.recv(timeout=10))["type"] == "history"

        @settings(
            max_examples=300,
            deadline=None,
            suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
        )
        @given(text=MESSAGES)
        def answered(text):
            try:
                message = parse_client_message(text)
            except ProtocolError:
                expected = ["error", "pong"]
            else:
                expected = ["pong", "pong"] if message["type"] == "ping" else ["pong"]
            ws.send(text)
            ws.send('{"type": "ping"}')
            replies = [json.loads(ws.recv(timeout=10)) for _ in expected]
            assert [r["type"] for r in replies] == expected, (text, replies)
            if expected[0] == "error":
                assert replies[0]["message"].startswith("rejected:")
                assert "could not check" not in replies[0]["message"]

        answered()
    assert not [r for r in caplog.records if r.levelno >= logging.ERROR or r.exc_info]
