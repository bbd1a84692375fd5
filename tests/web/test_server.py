"""The dashboard server over real HTTP and WebSocket connections: state, recordings, bad
messages rejected (and logged) while the server keeps running, two clients, disconnects."""

from __future__ import annotations

import json
import logging
import socket
import time
import urllib.error
import urllib.request

import numpy as np
import pytest
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from rnnpb.errors import ConfigError
from rnnpb.web import (
    MAX_MESSAGE_BYTES,
    STATIC_DIR,
    WS_MAX_SIZE,
    DemonstratorSource,
    PointerSource,
    find_models,
)


def _ws(server):
    return connect(server.url.replace("http", "ws") + "ws", open_timeout=10)


def _next(ws, kind: str, timeout: float = 10.0, where=lambda m: True) -> dict:
    deadline = time.monotonic() + timeout
    while True:
        message = json.loads(ws.recv(timeout=max(0.01, deadline - time.monotonic())))
        if message["type"] == kind and where(message):
            return message


def _control(ws, **message) -> None:
    ws.send(json.dumps(message))


def _get(server, path: str) -> tuple[int, bytes, str]:
    try:
        with urllib.request.urlopen(server.url + path.lstrip("/"), timeout=10) as response:
            return response.status, response.read(), response.headers.get("content-type", "")
    except urllib.error.HTTPError as error:
        return error.code, error.read(), ""


def test_page_and_vendored_assets_are_served_with_no_internet_reference(server):
    status, body, kind = _get(server, "/")
    assert status == 200 and "text/html" in kind
    html = body.decode()
    assert "/static/app.js" in html
    # The page's script is ES modules, one per part of the page, loaded from the server.
    scripts = sorted(p.name for p in STATIC_DIR.glob("*.js"))
    assert "app.js" in scripts and len(scripts) > 5
    for path in (
        *(f"/static/{name}" for name in scripts),
        "/static/style.css",
        "/static/vendor/three.module.min.js",
        "/static/vendor/three-LICENSE.txt",
    ):
        assert _get(server, path)[0] == 200, path
    texts = [html, *(_get(server, f"/static/{name}")[1].decode() for name in scripts)]
    for text in texts:
        assert "http://" not in text and "https://" not in text  # nothing from the internet


def test_state_names_the_models_and_the_learned_pbs(server, model):
    status, body, _ = _get(server, "/api/state")
    state = json.loads(body)
    assert status == 200 and state["models"] == ["set1.npz"] and state["model"] == "set1.npz"
    assert state["patterns"] == list(model.patterns)
    assert state["novel_patterns"] == ["4", "one-arm", "asymmetric", "figure-eight", "diagonal"]
    np.testing.assert_allclose(state["pattern_pb"]["1"], model.pattern_pb["1"])


BAD_MESSAGES = [
    ("{not json", "malformed JSON"),
    ("[1, 2]", "JSON object"),
    ('{"type": "dance"}', "unknown message type"),
    ('{"hands": [0.1, 0.2, 0.3, 0.4]}', "'type'"),
    ('{"type": "hands", "hands": [0.1, 0.2, 0.3]}', "4 values"),
    ('{"type": "hands", "hands": [0.1, "0.2", 0.3, 0.4]}', "must be a number"),
    ('{"type": "hands", "hands": [0.1, 1.5, 0.3, 0.4]}', "must be in [0, 1]"),
    ('{"type": "hands", "hands": [true, 0.2, 0.3, 0.4]}', "must be a number"),
    ('{"type": "dt", "dt": 0}', "dt must be in"),
    ('{"type": "dt", "dt": "fast"}', "must be a number"),
    ('{"type": "mode", "mode": "telepathy"}', "mode must be one of"),
    ('{"type": "pattern", "pattern": "7"}', "pattern must be one of"),
    ('{"type": "control", "action": "explode"}', "action must be one of"),
    ('{"type": "control", "action": "start", "extra": 1}', "unknown field"),
    ('{"type": "camera", "index": -1}', "camera index"),
    ('{"type": "model"}', "needs field"),
    (json.dumps({"type": "ping", "pad": "x" * MAX_MESSAGE_BYTES}), "too large"),
]


@pytest.mark.parametrize(("text", "reason"), BAD_MESSAGES, ids=[r for _, r in BAD_MESSAGES])
def test_a_bad_message_is_rejected_and_logged_and_the_server_keeps_running(
    server, caplog, text, reason
):
    with caplog.at_level(logging.WARNING, logger="rnnpb.web"), _ws(server) as ws:
        _next(ws, "state")
        ws.send(text)
        error = _next(ws, "error")
        assert error["message"].startswith("rejected:") and reason in error["message"]
        _control(ws, type="ping")
        _next(ws, "pong")
    assert any(reason in record.getMessage() for record in caplog.records)


def test_binary_and_oversized_frames_are_refused_without_harm(server):
    with _ws(server) as ws:
        _next(ws, "state")
        ws.send(b"\x00\x01")
        assert "binary" in _next(ws, "error")["message"]
        ws.send("x" * (WS_MAX_SIZE + 1))  # beyond the protocol limit: the connection closes
        with pytest.raises(ConnectionClosed):
            for _ in range(100):
                ws.recv(timeout=5)
    with _ws(server) as ws:  # the server still serves
        assert _next(ws, "state")["model"] == "set1.npz"


def test_unknown_model_is_an_error_and_the_current_one_stays(server):
    with _ws(server) as ws:
        _next(ws, "state")
        _control(ws, type="model", name="nope.npz")
        assert "no model 'nope.npz'" in _next(ws, "error")["message"]
    assert server.session.model_name == "set1.npz"


def test_two_clients_share_one_session_and_a_disconnect_mid_stream_is_harmless(server, model):
    with _ws(server) as a, _ws(server) as b:
        _next(a, "state")
        _next(b, "state")
        _control(a, type="mode", mode="demonstrator")
        _control(a, type="pattern", pattern="2")
        _control(b, type="dt", dt=0.05)
        _control(b, type="control", action="reset")
        _control(a, type="control", action="start")
        # Steps from before the reset may still be queued for either tab: skip to this run's.
        _next(a, "step", where=lambda m: m["step"] == 0 and m["truth"] == "2")
        steps_a = [_next(a, "step") for _ in range(4)]
        # One session: the other tab receives the very same step messages.
        _next(b, "step", where=lambda m, s=steps_a[-1]: m == s)
        assert steps_a[-1]["truth"] == "2"
        # Control from either tab is applied in turn and both see the result.
        _control(b, type="pattern", pattern="pause")
        _next(a, "state", where=lambda m: m["demonstrator_pattern"] == "pause")
        _control(a, type="pattern", pattern="2")
        _next(b, "state", where=lambda m: m["demonstrator_pattern"] == "2")

        # A tab that vanishes without a closing handshake mid-stream.
        with _ws(server) as c:
            _next(c, "step")
            c.socket.shutdown(socket.SHUT_RDWR)  # gone, with no closing handshake
        before = _next(a, "step")["step"]
        # The demonstrator performing pattern 2 is recognised and the loop goes on.
        recognised = _next(a, "step", timeout=30, where=lambda m: m["nearest"] == "2")
        assert recognised["step"] > before
        assert model.nearest_pattern(np.array(recognised["pb"]))[0] == "2"
        assert set(recognised["timings_ms"]) == {"perceive", "mirror", "act", "record"}
        assert len(recognised["arms"]["hands"]) == 2
        # What the step recognised travels with it, in the contract's words.
        assert recognised["novelty"] in ("familiar", "novel", "unstructured", "still", "")
        assert recognised["recognised"] in (None, *model.pattern_pb)
        assert 0.0 <= recognised["confidence"] <= 1.0
        assert set(recognised["pattern_confidence"]) == set(model.pattern_pb)
        _control(a, type="control", action="stop")
        _next(b, "state", where=lambda m: not m["running"])
    deadline = time.monotonic() + 5
    while server.session.subscriber_count and time.monotonic() < deadline:
        time.sleep(0.05)
    assert server.session.subscriber_count == 0


def test_the_loop_paces_itself_at_the_chosen_dt_and_commands_apply_while_stopped(server):
    with _ws(server) as ws:
        _next(ws, "state")
        dt = server.session.dt
        _control(ws, type="control", action="stop")
        _next(ws, "state", where=lambda m: not m["running"])
        # Stopped: the session thread still applies commands, and no step is taken.
        _control(ws, type="dt", dt=0.15)
        _control(ws, type="control", action="reset")
        state = _next(ws, "state", where=lambda m: m["dt"] == 0.15 and m["steps"] == 0)
        assert not state["running"]
        _control(ws, type="control", action="start")
        steps = [_next(ws, "step", where=lambda m: m["step"] == 1)]
        steps += [_next(ws, "step") for _ in range(3)]
        _control(ws, type="dt", dt=dt)
        _control(ws, type="control", action="stop")
        _next(ws, "state", where=lambda m: not m["running"] and m["dt"] == dt)
    starts = np.array([m["time_s"] for m in steps])
    assert [m["step"] for m in steps] == [1, 2, 3, 4]
    # One step every 0.15 s from the run's first (a step may start late, never early: a late
    # one does not move the next ones' times), with every section timed.
    assert all(start >= m["step"] * 0.15 - 0.002 for start, m in zip(starts, steps, strict=True))
    assert starts[-1] >= 4 * 0.15 - 0.002
    assert all(m["dt"] == 0.15 for m in steps)
    assert all(m["timings_ms"]["mirror"] > 0 and m["timings_ms"]["record"] > 0 for m in steps)


def test_the_recording_downloads_as_a_session_csv(server, tmp_path):
    from rnnpb.interaction import read_session

    with _ws(server) as ws:
        _next(ws, "state")
        _control(ws, type="control", action="reset")
        _control(ws, type="mode", mode="pointer")
        _control(ws, type="hands", hands=[0.3, 0.6, None, None])
        _control(ws, type="control", action="start")
        _next(ws, "step", where=lambda m: m["step"] >= 4 and m["observed"][0] is not None)
        _control(ws, type="control", action="stop")
        _next(ws, "state", where=lambda m: not m["running"])
    status, body, kind = _get(server, "/api/recording.csv")
    assert status == 200 and "text/csv" in kind
    path = tmp_path / "session.csv"
    path.write_bytes(body)
    session = read_session(path)
    assert len(session["step"]) >= 5
    assert session["lhy"][-1] == pytest.approx(0.3) and np.isnan(session["rhy"][-1])
    assert session["lost_right"][-1] == 1


def test_pointer_source_reads_not_seen_until_placed_then_the_latest():
    source = PointerSource()
    assert np.isnan(source.read().sensory).all()
    source.set_hands(np.array([0.2, 0.3, 0.7, 0.8]))
    source.set_hands(np.array([0.25, 0.3, 0.7, 0.8]))
    np.testing.assert_allclose(source.read().sensory, [0.25, 0.3, 0.7, 0.8])


def test_demonstrator_switch_keeps_the_phase_and_pause_holds_the_hands():
    source = DemonstratorSource(patterns=("1", "2"), n_steps=120)
    for _ in range(17):
        source.read()
    phase_before = source._phase["1"][source._position]  # noqa: SLF001
    source.perform("2")
    phase_after = source._phase["2"][source._position]  # noqa: SLF001
    assert abs(np.angle(np.exp(1j * (phase_after - phase_before)))) < 0.4
    moving = source.read()
    assert moving.truth["pattern"] == "2"
    source.perform("pause")
    held = [source.read().sensory for _ in range(3)]
    np.testing.assert_allclose(held[0], moving.sensory)
    np.testing.assert_allclose(held[2], moving.sensory)
    with pytest.raises(ConfigError, match="no pattern '5'"):
        source.perform("5")


def test_find_models_and_the_command_line(model_dir, tmp_path, capsys):
    from rnnpb.cli import main

    assert list(find_models(model_dir)) == ["set1.npz"]
    assert list(find_models(model_dir / "set1.npz")) == ["set1.npz"]
    with pytest.raises(ConfigError, match="no usable model files"):
        find_models(tmp_path)
    assert main(["serve", "--model", str(tmp_path / "missing")]) == 2
    assert "no such model file or folder" in capsys.readouterr().err
    assert main(["serve", "--model", str(model_dir), "--dt", "0"]) == 2
    assert "--dt must be in" in capsys.readouterr().err


def test_only_models_that_load_are_offered_and_a_bad_one_is_refused_at_start(
    model_dir, tmp_path, capsys, caplog
):
    import shutil

    from rnnpb.cli import main
    from rnnpb.errors import ModelFileError
    from rnnpb.web import offered_models

    folder = tmp_path / "models"
    folder.mkdir()
    (folder / "a-broken.npz").write_bytes(b"not a zip file at all")
    (folder / "b-data.npz").write_text("lhy,lhz,rhy,rhz\n0.1,0.2,0.3,0.4\n")
    shutil.copy(model_dir / "set1.npz", folder / "set1.npz")
    shutil.copy(model_dir / "set1.npz", folder / "set1.checkpoint.npz")
    shutil.copy(model_dir / "set1.npz", folder / ".set1.npz")  # an unfinished write
    models, refused = offered_models(folder)
    # The broken first model is refused with its reason, the checkpoint is never offered.
    assert list(models) == ["set1.npz"]
    assert sorted(refused) == ["a-broken.npz", "b-data.npz"]
    assert all("rnnpb" in reason for reason in refused.values())
    with caplog.at_level(logging.WARNING, logger="rnnpb.web"):
        assert list(find_models(folder)) == ["set1.npz"]
    assert "not offering a-broken.npz" in caplog.text
    # A bad --model file stops serve before it serves: one line, exit status 2.
    for bad in ("a-broken.npz", "b-data.npz"):
        with pytest.raises(ModelFileError):
            find_models(folder / bad)
        assert main(["serve", "--model", str(folder / bad), "--port", "0"]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("rnnpb: error:") and bad in err and len(err.splitlines()) == 1
    (folder / "set1.npz").unlink()
    with pytest.raises(ConfigError, match="no usable model files.*a-broken.npz"):
        find_models(folder)


def test_a_model_that_cannot_be_used_is_named_in_the_state(tmp_path):
    from rnnpb.web import Session

    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"damaged")
    session = Session({"bad.npz": bad}, workdir=tmp_path / "sessions")
    try:
        session.start()
        deadline = time.monotonic() + 30
        while session.state()["model_error"] is None:
            assert time.monotonic() < deadline, "no model error within 30 s"
            time.sleep(0.05)
        state = session.state()
        assert state["model"] is None and not state["loading"]
        assert "bad.npz" in state["model_error"] and "bad.npz" in state["error"]
        session.submit({"type": "control", "action": "start"})
        deadline = time.monotonic() + 10
        while "no model is loaded" not in (session.state()["error"] or ""):
            assert time.monotonic() < deadline
            time.sleep(0.05)
        assert "bad.npz" in session.state()["error"]  # Start says why it cannot start
    finally:
        session.close()


def test_a_new_client_starts_with_the_runs_recent_steps(server):
    from rnnpb.web import RECENT_STEPS

    with _ws(server) as ws:
        _next(ws, "state")
        _control(ws, type="dt", dt=0.02)
        _control(ws, type="control", action="reset")
        _control(ws, type="control", action="start")
        _next(ws, "step", where=lambda m: m["step"] >= 15)
        with _ws(server) as late:
            state = json.loads(late.recv(timeout=10))
            history = json.loads(late.recv(timeout=10))
            assert state["type"] == "state" and history["type"] == "history"
            assert history["run"] == state["run"]
            steps = [m["step"] for m in history["steps"]]
            assert 15 <= len(steps) <= RECENT_STEPS and steps == list(
                range(steps[0], steps[-1] + 1)
            )
            # Then the live steps follow on with no gap and no repeat.
            following = _next(late, "step")["step"]
            assert following == steps[-1] + 1
        _control(ws, type="control", action="stop")
        _control(ws, type="dt", dt=0.05)  # the fixture's step again
        _control(ws, type="control", action="reset")
        state = _next(ws, "state", where=lambda m: m["steps"] == 0 and not m["running"])
    with _ws(server) as fresh:
        _next(fresh, "state")
        assert _next(fresh, "history")["steps"] == []  # a new run: no old steps replayed
    assert state["run"] != history["run"]


def test_state_and_steps_say_what_guards_the_robot(server, model_dir):
    from rnnpb.web import offered_models

    # A safety map beside a model is neither offered as a model nor refused as one.
    (model_dir / "set1.safety.npz").write_bytes(b"")
    try:
        assert offered_models(model_dir) == ({"set1.npz": model_dir / "set1.npz"}, {})
    finally:
        (model_dir / "set1.safety.npz").unlink()
    status, body, _ = _get(server, "/api/state")
    safety = json.loads(body)["safety"]
    assert safety["filter"] and not safety["map"] and safety["risk"] == {}
    with _ws(server) as ws:
        _control(ws, type="control", action="start")
        step = _next(ws, "step")
        _control(ws, type="control", action="stop")
    assert step["prevented"] >= 0 and "filtered" in step and "unsafe" in step
