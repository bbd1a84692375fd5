"""Teaching by showing in the dashboard: the messages, the session's teaching, and the panel in
a real browser (record → consolidate → learned, rename, undo; a failed consolidation)."""

from __future__ import annotations

import json
import shutil

import pytest

from rnnpb.interaction.teaching import TeachingConfig
from rnnpb.web import ProtocolError, parse_client_message

from .conftest import TEST_DT
from .test_browser import _shot, _strict_page, _until, browser  # noqa: F401 — the fixture

CONSOLIDATION_ITERATIONS = 5
"""Learning iterations of the tests' consolidations: the flow is under test, not the learning."""


# --- the messages ------------------------------------------------------------------------
@pytest.mark.parametrize(
    "message",
    [
        {"type": "teach_mode", "mode": "confirm"},
        {"type": "teach_mode", "mode": "auto"},
        {"type": "teach_mode", "mode": "off"},
        {"type": "teach", "action": "confirm"},
        {"type": "teach", "action": "undo"},
        {"type": "teach", "action": "confirm", "pattern": "new-2"},
        {"type": "rename", "pattern": "new-1", "name": "wave"},
        {"type": "pattern", "pattern": "figure-eight"},
        {"type": "pattern", "pattern": "one-arm"},
        {"type": "pattern", "pattern": "asymmetric"},
        {"type": "pattern", "pattern": "diagonal"},
    ],
)
def test_teaching_messages_are_accepted(message):
    assert parse_client_message(json.dumps(message)) == message


@pytest.mark.parametrize(
    ("message", "words"),
    [
        ({"type": "teach_mode", "mode": "always"}, "teach_mode must be one of"),
        ({"type": "teach_mode", "mode": 1}, "teach_mode must be one of"),
        ({"type": "teach", "action": "redo"}, "teach action must be one of"),
        ({"type": "teach"}, "needs field(s) action"),
        ({"type": "teach", "action": "undo", "pattern": "new-1"}, "confirm action only"),
        ({"type": "teach", "action": "confirm", "pattern": ""}, "teach pattern must be"),
        ({"type": "teach", "action": "confirm", "pattern": 2}, "teach pattern must be"),
        ({"type": "rename", "pattern": "new-1"}, "needs field(s) name"),
        ({"type": "rename", "pattern": "new-1", "name": ""}, "rename name must be a string"),
        ({"type": "rename", "pattern": "new-1", "name": "x" * 65}, "1 to 64 characters"),
        ({"type": "rename", "pattern": None, "name": "wave"}, "rename pattern must be"),
        ({"type": "pattern", "pattern": "random-walk"}, "pattern must be one of"),
    ],
)
def test_bad_teaching_messages_are_refused_with_the_reason(message, words):
    with pytest.raises(ProtocolError, match=words.replace("(", r"\(").replace(")", r"\)")):
        parse_client_message(json.dumps(message))


def test_the_demonstrator_performs_the_new_shapes():
    from rnnpb.demonstrator import NEW_SHAPES
    from rnnpb.web import DemonstratorSource

    source = DemonstratorSource(n_steps=60)
    assert set(NEW_SHAPES) <= set(source.patterns)
    source.perform("figure-eight")
    observation = source.read()
    assert observation.truth["pattern"] == "figure-eight"


# --- the model's history keeps a rename --------------------------------------------------
def test_a_rename_is_stored_in_the_model_file_and_its_history(model, tmp_path):
    from rnnpb.errors import ConfigError
    from rnnpb.model import TrainedModel

    renamed = model.renamed("3", "wave")
    renamed.save(tmp_path / "m.npz")
    loaded = TrainedModel.load(tmp_path / "m.npz")
    assert loaded.patterns == ("1", "2", "wave")
    assert "3" not in loaded.pattern_pb and "wave" in loaded.pattern_pb
    last = loaded.history[-1]
    assert last.patterns == ("1", "2", "wave")
    assert [(r["from"], r["to"]) for r in last.details["renamed"]] == [("3", "wave")]
    for bad, words in (("2", "already has"), ("a<b", "holds '<'"), ("", "characters")):
        with pytest.raises(ConfigError, match=words):
            model.renamed("1", bad)
    with pytest.raises(ConfigError, match="no pattern"):
        model.renamed("nope", "wave")


# --- the session (no browser) ------------------------------------------------------------
def _session(model_dir, tmp_path, **teaching):
    from rnnpb.web import Session, TeachingSettings, find_models

    folder = tmp_path / "models"
    folder.mkdir()
    shutil.copy(model_dir / "set1.npz", folder / "set1.npz")
    return Session(
        find_models(folder),
        dt=TEST_DT,
        workdir=tmp_path / "sessions",
        teaching=TeachingSettings(**teaching),
    ), folder


def _wait(condition, timeout_s: float, what: str) -> None:
    import time

    deadline = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < deadline, what
        time.sleep(0.05)


def test_the_session_keeps_a_new_shape_and_answers_commands_it_cannot_carry_out(
    model_dir, tmp_path
):
    session, folder = _session(model_dir, tmp_path, iterations=CONSOLIDATION_ITERATIONS)
    errors = []
    session.subscribe(
        lambda text: errors.append(json.loads(text)) if text.startswith('{"type":"error"') else None
    )
    session.start()
    try:
        _wait(lambda: session.mirror is not None and not session.loading, 90, "no model")
        state = session.state()["teaching"]
        assert state["available"] and state["mode"] == "confirm"
        assert [v["name"] for v in state["versions"]] == ["set1.npz"]
        assert state["can_undo"] is False
        # Nothing kept, nothing to undo: each says why, the robot goes on.
        session.submit({"type": "teach", "action": "confirm"})
        session.submit({"type": "teach", "action": "undo"})
        _wait(lambda: len(errors) >= 2, 10, "no answers")
        assert "no kept movement" in errors[0]["message"]
        assert "nothing to undo" in errors[1]["message"]
        session.submit({"type": "pattern", "pattern": "figure-eight"})
        session.submit({"type": "control", "action": "start"})
        _wait(lambda: session.state()["teaching"]["pending"] == 1, 60, "nothing kept")
        teaching = session.state()["teaching"]
        (episode,) = teaching["episodes"]
        assert (episode["pattern"], episode["status"], episode["n_cycles"]) == (
            "new-1",
            "kept",
            TeachingConfig().episode_cycles,
        )
        # In confirm mode nothing is consolidated until the person says so.
        assert not teaching.get("consolidating")
        # Seen once: the panel says so and the robot goes on watching for another performance
        # (Confirm learns it from this one).
        assert teaching["seen"] == {"new-1": 1} and teaching["performances"] == 2
        assert teaching["waiting"] is False
        assert any(
            e["kind"] == "waiting" and "new-1 seen once" in e["text"] for e in teaching["events"]
        )
        # A kept movement can be named before it is learned: its episode takes the name.
        session.submit({"type": "rename", "pattern": "new-1", "name": "eight"})
        _wait(
            lambda: session.state()["teaching"]["episodes"][0]["pattern"] == "eight",
            10,
            "not renamed",
        )
        session.submit({"type": "rename", "pattern": "eight", "name": "1"})
        _wait(lambda: any("taken" in e["message"] for e in errors), 10, "a taken name passed")
        assert session.running
        assert (folder / "set1.memory.sqlite").exists()
    finally:
        session.close()


# --- the panel in the browser ------------------------------------------------------------
def test_the_panel_records_consolidates_learns_renames_and_undoes(browser, model_dir, tmp_path):  # noqa: F811
    from rnnpb.interaction.teaching import version_path
    from rnnpb.model import TrainedModel
    from rnnpb.web import DashboardServer, TeachingSettings, find_models

    folder = tmp_path / "models"
    folder.mkdir()
    model_file = folder / "set1.npz"
    shutil.copy(model_dir / "set1.npz", model_file)
    with (
        DashboardServer(
            find_models(folder),
            port=0,
            dt=TEST_DT,
            workdir=tmp_path / "sessions",
            teaching=TeachingSettings(iterations=CONSOLIDATION_ITERATIONS),
        ) as dashboard,
        _strict_page(browser, dashboard) as page,
    ):
        assert page.locator("#patterns button[data-pattern='figure-eight']").count() == 1
        for shape in ("one-arm", "asymmetric", "diagonal"):
            assert page.locator(f"#patterns button[data-pattern='{shape}']").count() == 1
        _shot(page, "teach-0-watching", "#teach")
        page.click("#patterns button[data-pattern='figure-eight']")
        page.click("#start")
        _until(page, "rnnpbDashboard.teachPhase === 'recording'", 60000)
        assert "recording a new movement (cycle" in page.text_content("#teach-text")
        _shot(page, "teach-1-recording", "#teach")
        _until(page, "rnnpbDashboard.state.teaching.pending === 1", 60000)
        assert "new-1" in page.text_content("#teach-episodes")
        assert page.locator("#teach-confirm").is_enabled()
        _shot(page, "teach-2-kept", "#teach")

        # A consolidation that fails (the model's file was damaged on disk meanwhile) says
        # why, and the robot runs on with the model it had.
        good = model_file.read_bytes()
        model_file.write_bytes(b"not a model")
        page.click("#teach-confirm")
        _until(page, "!document.querySelector('#teach-failure').hidden", 60000)
        assert "consolidation failed" in page.text_content("#teach-failure")
        assert "running model stays" in page.text_content("#teach-failure")
        assert page.evaluate("rnnpbDashboard.state.patterns") == ["1", "2", "3"]
        assert page.evaluate("rnnpbDashboard.state.running")
        _shot(page, "teach-3-failed", "#teach")

        # Confirm again, with the file whole: learned as new-1, swapped in while running.
        model_file.write_bytes(good)
        page.click("#teach-confirm")
        _until(page, "rnnpbDashboard.teachPhase === 'consolidating'", 20000)
        _shot(page, "teach-4-consolidating", "#teach")
        _until(
            page,
            "(rnnpbDashboard.state.teaching.result || '').includes('learned as pattern new-1')",
            600000,  # minutes on a loaded 2-core machine: the process's JAX start, the
            # learning and the new version's compilation (seconds each on a quiet one)
        )
        assert page.evaluate("rnnpbDashboard.state.patterns") == ["1", "2", "3", "new-1"]
        assert page.locator("#teach-failure").is_hidden()
        _until(page, "document.querySelector('#confidence-bars').textContent.includes('new-1')")
        assert "set1.v2.npz" in page.text_content("#teach-versions")
        # The status bar and the model list name the version that runs, not the old one.
        _until(page, "document.querySelector('#status').textContent.includes('model set1.v2.npz')")
        assert page.input_value("#model") == "set1.v2.npz"
        assert page.evaluate("rnnpbDashboard.state.models") == ["set1.npz", "set1.v2.npz"]
        assert page.locator("#teach-undo").is_enabled()
        eight = "#patterns button[data-pattern='figure-eight']"
        _until(page, f"document.querySelector(\"{eight}\").textContent.includes('as new-1')")
        assert "(novel)" not in page.text_content(eight)
        _shot(page, "teach-5-learned", "#teach")

        # Renamed: in the new version's file and history, and everywhere the page names it.
        page.select_option("#rename-pattern", "new-1")
        page.fill("#rename-name", "eight")
        page.click("#rename-apply")
        _until(
            page,
            "document.querySelector('#confidence-bars').textContent.includes('eight')"
            " && rnnpbDashboard.pbMarkers.some((m) => m.name === 'eight')",
        )
        assert "new-1" not in page.text_content("#confidence-bars")
        assert "eight" in page.text_content("#teach-versions")
        version = TrainedModel.load(version_path(model_file, 2))
        assert version.patterns == ("1", "2", "3", "eight")
        assert version.history[-1].details["renamed"][0]["from"] == "new-1"
        _shot(page, "teach-6-renamed", "#teach")
        _shot(page, "teach-6-page")

        # Undo: the first version again, the old pattern list back; the robot ran throughout.
        page.click("#teach-undo")
        _until(
            page,
            'JSON.stringify(rnnpbDashboard.state.patterns) === \'["1","2","3"]\''
            " && !document.querySelector('#confidence-bars').textContent.includes('eight')",
        )
        assert page.evaluate("rnnpbDashboard.state.running")
        assert "back to set1.npz" in page.text_content("#teach-result")
        _until(page, "document.querySelector('#status').textContent.includes('model set1.npz ')")
        assert page.input_value("#model") == "set1.npz"
        # The episode the undone version learned is kept again, to learn on a Confirm.
        # (and the demonstrator, performing on, may have shown it once more meanwhile)
        _until(page, "rnnpbDashboard.state.teaching.pending >= 1")
        assert "not learned by this model" in page.text_content(eight)
        _shot(page, "teach-7-undone", "#teach")
        page.click("#stop")
    assert version_path(model_file, 2).exists()  # the undone version stays on disk
