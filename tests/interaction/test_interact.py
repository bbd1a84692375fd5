"""The interaction loop and `rnnpb interact`: recordings, lost hands, timings, sources."""

import json
import shutil
import time

import numpy as np
import pytest

from rnnpb.cli import main
from rnnpb.demonstrator import learning_set
from rnnpb.errors import ConfigError
from rnnpb.interaction import (
    CAMERA_KINDS,
    InteractionLoop,
    LoopConfig,
    SessionRecorder,
    SourceSpec,
    open_source,
    parse_source_spec,
    read_session,
)
from rnnpb.model import MirrorSystem, OnlineConfig
from rnnpb.robot import JOINT_LIMITS, KinematicRobot
from rnnpb.sequences import write_sensory_stream
from rnnpb.sources import ArraySensorySource, FrameStepSource
from rnnpb.vectors import MOTOR_NAMES, SENSORY_NAMES


@pytest.fixture(scope="module")
def model_path(set1_model_dir, tmp_path_factory):
    """Learning set 1's fast-preset model, in a folder of this module's own (a command writes
    beside it)."""
    path = tmp_path_factory.mktemp("model") / "set1.npz"
    shutil.copy(set1_model_dir / "set1.npz", path)
    return path


def test_interact_writes_recording_plot_and_summary(model_path, tmp_path, capsys):
    out = tmp_path / "run"
    assert (
        main(
            [
                "interact",
                "--model",
                str(model_path),
                "--source",
                "scenario:switch:1,2",
                "--out",
                str(out),
                "--steps",
                "60",
            ]
        )
        == 0
    )
    session = read_session(out / "session.csv")
    assert len(session["step"]) == 60
    for column in (*SENSORY_NAMES, *MOTOR_NAMES, "pred_lhy", "pb0", "pb3", "prediction_error"):
        assert column in session
    assert list(session["truth_pattern"][:2]) == ["1", "1"]
    assert session["truth_pattern"][-1] == "2"
    # What each step recognised, in exactly the contract's words.
    assert set(session["novelty"]) <= {"familiar", "novel", "unstructured", "still", ""}
    assert set(session["recognised"]) <= {"1", "2", "3", ""}
    assert np.all((session["confidence"] >= 0) & (session["confidence"] <= 1))
    # Motor commands within the joint limits; the prediction error falls once locked.
    motor = np.stack([session[name] for name in MOTOR_NAMES], axis=1)
    assert np.all(motor >= JOINT_LIMITS[:, 0]) and np.all(motor <= JOINT_LIMITS[:, 1])
    assert np.nanmean(session["prediction_error"][30:50]) < np.nanmean(
        session["prediction_error"][1:6]
    )
    summary = json.loads((out / "summary.json").read_text())
    assert summary["loop"]["steps"] == 60
    assert set(summary["loop"]["section_ms"]) == {"perceive", "mirror", "act", "record"}
    assert (out / "session.png").stat().st_size > 20_000
    printed = capsys.readouterr().out
    assert "mirror" in printed
    assert "recognition timeline:" in printed and "step 1:" in printed
    # The timeline covers every step once, in order.
    timeline = summary["recognition_timeline"]
    assert timeline[0]["first"] == 0 and timeline[-1]["last"] == 59
    assert all(a["last"] + 1 == b["first"] for a, b in zip(timeline, timeline[1:], strict=False))


def test_ungated_regression_is_recorded_in_the_summary(model_path, tmp_path):
    out = tmp_path / "ungated"
    assert (
        main(
            [
                "interact",
                "--model",
                str(model_path),
                "--source",
                "scenario:held:1",
                "--out",
                str(out),
                "--steps",
                "12",
                "--online",
                "ungated",
            ]
        )
        == 0
    )
    summary = json.loads((out / "summary.json").read_text())
    assert summary["online_config"]["surprise_gate"] == 0 < OnlineConfig().surprise_gate


def test_lost_hands_from_a_csv_stream_are_marked_and_bridged(model_path, tmp_path):
    sensory = learning_set("1")[0].sensory[:40].copy()
    sensory[20:24, :2] = np.nan  # the left hand is lost for 4 steps
    stream = tmp_path / "stream.csv"
    write_sensory_stream(stream, sensory)
    out = tmp_path / "run"
    assert (
        main(
            ["interact", "--model", str(model_path), "--source", f"csv:{stream}", "--out", str(out)]
        )
        == 0
    )
    session = read_session(out / "session.csv")
    np.testing.assert_array_equal(session["lost_left"], np.isnan(sensory[:, 0]).astype(float))
    assert np.all(session["lost_right"] == 0)
    assert np.all(np.isfinite(session["pb0"])) and np.all(np.isfinite(session["lshp"]))


def test_loop_sections_subscribers_and_pacing(model_path, tmp_path):
    from rnnpb.model import TrainedModel

    model = TrainedModel.load(model_path)
    sensory = learning_set("1")[2].sensory[:8]
    seen = []
    with (
        ArraySensorySource(sensory) as source,
        KinematicRobot() as robot,
        SessionRecorder(tmp_path / "s.csv") as recorder,
    ):
        loop = InteractionLoop(
            MirrorSystem(model), source, robot, recorder, LoopConfig(dt=0.05, paced=True)
        )
        loop.subscribe(seen.append)
        summary = loop.run()
    assert summary.steps == 8 and len(seen) == 8
    # Subscribers are called once the step is complete: every section is measured.
    assert all(r.timings["mirror"] > 0 and r.timings["record"] > 0 for r in seen)
    assert seen[-1].time_s >= 7 * 0.05 - 0.005
    np.testing.assert_array_equal(robot.read(), seen[-1].motor)
    assert len(read_session(tmp_path / "s.csv")["step"]) == 8


def test_frame_step_keeps_every_nth_observation():
    source = FrameStepSource(ArraySensorySource(np.arange(40.0).reshape(10, 4) / 40), 3)
    with source:
        values = []
        while (observation := source.read()) is not None:
            values.append(observation.sensory[0])
    np.testing.assert_allclose(values, np.array([0, 12, 24, 36]) / 40)


@pytest.mark.parametrize(
    "spec, message",
    [
        ("nothing", "expected KIND:ARGUMENT"),
        ("scenario:dance:1", "unknown scenario"),
        ("scenario:held:9", "unknown movement pattern .9."),
        ("ftp:x", "unknown kind"),
        ("scenario:held", "needs an argument"),
        ("scenario:steps:1*ten", "steps must be an integer"),
        ("scenario:steps:figure-eight", "expected MOVEMENT.STEPS"),
        ("scenario:steps:wave*10", "unknown movement pattern"),
    ],
)
def test_bad_source_specifications(spec, message):
    with pytest.raises(ConfigError, match=message):
        open_source(spec)


@pytest.mark.parametrize(
    "spec, parsed",
    [
        ("scenario:switch:1,2", SourceSpec("scenario", "switch:1,2")),
        ("csv:run/a:b.csv", SourceSpec("csv", "run/a:b.csv")),
        ("webcam:2", SourceSpec("webcam", 2)),
        (" Video:clip.mp4", SourceSpec("video", "clip.mp4")),
        ("synthetic:rotation-in-phase", SourceSpec("synthetic", "rotation-in-phase")),
    ],
)
def test_the_one_grammar_of_source_specifications(spec, parsed):
    assert parse_source_spec(spec) == parsed


def test_a_scenario_of_any_movements_one_after_another():
    source = open_source("scenario:steps:1*10,figure-eight*5,random-walk*4,pause*3")
    with source:
        labels = []
        while (observation := source.read()) is not None:
            labels.append(observation.truth["pattern"])
    assert labels == ["1"] * 10 + ["figure-eight"] * 5 + ["random-walk"] * 4 + ["pause"] * 3


@pytest.mark.parametrize(
    "spec, message",
    [
        ("camera:0", "unknown kind 'camera'; expected one of webcam:INDEX"),
        ("video:", "expected KIND:ARGUMENT, one of webcam:INDEX, video:PATH, images:DIR"),
        ("webcam:front", "the webcam index must be an integer"),
        ("csv:stream.csv", "a csv source cannot be used here"),
        ("scenario:held:1", "a scenario source cannot be used here"),
    ],
)
def test_camera_only_specifications(spec, message):
    with pytest.raises(ConfigError, match=message):
        parse_source_spec(spec, kinds=CAMERA_KINDS)


def test_the_loop_paces_itself_and_hands_its_waits_to_a_controller(model_path):
    """A controller applies its commands in ``between_steps``: it changes dt, stops the run
    (a pause: running again carries on), and replaces the source."""
    from rnnpb.model import TrainedModel

    sensory = learning_set("1")[2].sensory
    loop = InteractionLoop(
        MirrorSystem(TrainedModel.load(model_path)),
        ArraySensorySource(sensory[:30]),
        config=LoopConfig(0.1, paced=True),
    )
    seen = []
    loop.subscribe(seen.append)
    waits = []

    def controller(wait_s):
        waits.append(wait_s)
        # Checked on every call: a step that overran on a busy machine leaves little to wait.
        if loop.steps == 3:
            loop.set_dt(0.2)
        if loop.steps == 6:
            loop.stop()
            return
        if wait_s > 0.01:
            time.sleep(0.005)  # returns before the step is due: it is called again
            return
        time.sleep(max(wait_s, 0.0))

    with loop.source:
        loop.run(between_steps=controller)
        assert loop.steps == 6 and [r.step for r in seen] == list(range(6))
        starts = np.array([r.time_s for r in seen])
        # Paced at the deadlines (step 0, which compiles, may overrun and move them later):
        # steps 2 and 3 after 0.1 s each, 4 and 5 after the new 0.2 s (steps far shorter than
        # dt, even on a busy machine, so that every deadline is kept).
        assert starts[5] - starts[1] >= 2 * 0.1 + 2 * 0.2 - 0.01
        assert starts[5] - starts[3] >= 2 * 0.2 - 0.01
        assert max(waits) <= 0.2 + 1e-9 and len(waits) > 2 * 6
        # Running again resumes the interaction where it stopped, from the replaced source.
        loop.source = ArraySensorySource(sensory[40:44])
        loop.source.connect()
        summary = loop.run(between_steps=lambda wait_s: time.sleep(wait_s))
    assert summary.steps == 10 and [r.step for r in seen[6:]] == [6, 7, 8, 9]
    np.testing.assert_array_equal(seen[6].observed, sensory[40])
    # The window carried on: the prediction for step 6 was made at step 5.
    np.testing.assert_array_equal(seen[6].predicted, seen[5].predicted_next)


def test_side_by_side_video(model_path, tmp_path):
    out = tmp_path / "run"
    assert (
        main(
            [
                "interact",
                "--model",
                str(model_path),
                "--source",
                "scenario:held:2",
                "--out",
                str(out),
                "--steps",
                "6",
                "--render",
                "--robot",
                "mujoco",
            ]
        )
        == 0
    )
    import cv2

    capture = cv2.VideoCapture(str(out / "session.mp4"))
    frames = int(capture.get(cv2.CAP_PROP_FRAME_COUNT))
    ok, frame = capture.read()
    capture.release()
    assert ok and frames == 6
    assert frame.shape == (480, 1280, 3)
    # The right half shows the rendered robot, not a blank image.
    assert frame[:, 640:].std() > 20


def test_long_runs_keep_bounded_histories(model_path):
    from rnnpb.interaction.loop import TIMING_WINDOW
    from rnnpb.model import TrainedModel

    robot = KinematicRobot(history_length=5)
    with robot:
        for _ in range(12):
            robot.send(np.zeros(8))
    assert robot.history.shape == (5, 8)
    model = TrainedModel.load(model_path)
    loop = InteractionLoop(MirrorSystem(model), ArraySensorySource(learning_set("1")[0].sensory))
    for name in loop._timings:
        assert loop._timings[name].maxlen == TIMING_WINDOW
