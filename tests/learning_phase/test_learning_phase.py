"""The one learning phase: every source's movement through the step, framing, the robot's
servos and whole cycles to data `rnnpb train` learns."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rnnpb.cli import main
from rnnpb.demonstrator import Imperfection, MirrorMapping, PatternConfig, UserBody, perform
from rnnpb.errors import RnnpbError
from rnnpb.interaction import ArraySensorySource, open_source
from rnnpb.learning_phase import (
    Performance,
    PhaseOptions,
    fit_to_servos,
    from_source,
    learning_phase,
    resampled,
)
from rnnpb.robot import joint_step_limit
from rnnpb.robot.camera import RobotCamera
from rnnpb.safety import check_data
from rnnpb.sequences import read_sequence_files, write_sensory_stream
from tests.mocap.bvh_files import write_bvh

FPS = 30


@pytest.mark.parametrize("pattern", ["2", "4"])
def test_joint_angles_from_the_synthetic_camera_match_the_demonstrators(pattern):
    # the default scene: clutter, noise, lighting change, motion blur, occlusions
    with open_source(f"synthetic:{pattern}", steps=40, seed=11) as source:
        performance = from_source(source)
    assert performance.depth == "size" and not performance.body
    steps = resampled(performance, 0.4)
    truth = MirrorMapping().motor_from_hands(source.frames.hands)
    motor = MirrorMapping().motor_from_hands(steps.hands)
    valid = np.isfinite(motor).all(axis=1)
    assert valid.mean() > 0.7
    rms = np.sqrt(np.mean((motor[valid] - truth[valid]) ** 2))
    assert rms < 0.05, f"joint angles off by {rms:.3f} rad RMS"


def test_a_still_or_shapeless_recording_is_one_line_saying_it_does_not_repeat():
    rng = np.random.default_rng(0)
    stream = 0.5 + 0.02 * np.cumsum(rng.standard_normal((60, 4)), axis=0) / 10
    with ArraySensorySource(stream) as source:
        performance = from_source(source)
    assert performance.depth == "plane"
    with pytest.raises(RnnpbError, match="does not repeat in 60 steps") as caught:
        learning_phase(performance, "new")
    assert len(str(caught.value).splitlines()) == 1


def test_record_writes_sequences_that_train_reads(tmp_path, capsys):
    out = tmp_path / "three"
    assert (
        main(["record", "synthetic:3", "--steps", "40", "--pattern", "three", "--out", str(out)])
        == 0
    )
    sequences = read_sequence_files([out])
    assert sequences and all(s.pattern == "three" for s in sequences)
    assert all(s.n_steps >= 20 for s in sequences)  # two whole cycles of about 12 steps at least
    printed = capsys.readouterr().out
    assert "depth from ball size" in printed and "framed by the camera" in printed


def test_record_from_a_stream_without_depth_uses_the_plane(tmp_path, capsys):
    # a user without imperfection keeps the hands on the plane x = 0.68 m
    config = PatternConfig(imperfection=Imperfection.none())
    motion = perform([("2", 60)], config, np.random.default_rng(1))
    stream = tmp_path / "stream.csv"
    write_sensory_stream(stream, RobotCamera().sensory_from_hands(motion.measured))
    out = tmp_path / "two"
    args = ["record", f"csv:{stream}", "--cut", "length", "--length", "25", "--out", str(out)]
    assert main([*args, "--pattern", "two"]) == 0
    sequences = read_sequence_files([out])
    assert [s.n_steps for s in sequences] == [25, 25]
    # on the plane the synthetic user moves in, the angles are the demonstrator's own
    truth = MirrorMapping().motor_from_hands(motion.measured)
    assert np.abs(sequences[0].motor - truth[:25]).max() < 1e-4
    assert "fixed plane" in capsys.readouterr().out
    assert main([*args, "--pattern", "<x>"]) == 2


def _performer(seconds: float, period: float, rests: float = 0.0) -> np.ndarray:
    """A person (relative to the standard body) swinging both arms from the hips to above the
    head every ``period`` seconds, at 30 frames a second, resting ``rests`` seconds at the
    bottom of each cycle: larger and faster than the robot's servos follow at 0.1 s."""
    body = UserBody()
    times = np.arange(round(seconds * FPS) + 1) / FPS
    cycle = period + rests
    phase = np.clip((times % cycle) / period, 0.0, 1.0)
    lift = 0.5 - 0.5 * np.cos(2 * np.pi * phase)  # 0 at the hips, 1 above the head
    angle = np.deg2rad(-70 + 220 * lift)  # the arm from down by the side to over the head
    hands = np.empty((len(times), 2, 3))
    for i, side in enumerate((-1.0, 1.0)):
        shoulder = body.shoulders[i]
        reach = 0.97 * body.arm_reach
        hands[:, i] = shoulder + np.stack(
            [-0.15 * np.ones_like(angle), side * 0.2 * np.cos(angle) ** 2, reach * np.sin(angle)], 1
        )
    return hands


def test_a_performer_above_the_head_and_faster_than_the_servos_records_what_train_learns(
    tmp_path, capsys
):
    take = write_bvh(tmp_path / "exercise.bvh", _performer(10.0, period=0.9), 1 / FPS)
    out = tmp_path / "data"
    assert (
        main(["record", f"bvh:{take}", "--dt", "0.1", "--pattern", "exercise", "--out", str(out)])
        == 0
    )
    printed = capsys.readouterr().out
    assert "the whole reach of the body in view" in printed
    assert "made smaller to keep within the servos' speed at the person's tempo" in printed
    entry = json.loads((out / "recording.json").read_text())["recordings"]["exercise"]
    assert entry["servos"]["reduced_steps"] > 0 and not entry["time"]["retimed"]
    # the tempo is the person's: a 0.9 s cycle is 9 steps of 0.1 s
    assert entry["cycles"]["median_steps"] == pytest.approx(9, abs=1)
    sequences = read_sequence_files([out])
    safety = check_data(sequences, dt=0.1)
    assert safety.unsafe == 0 and safety.outside == 0
    model = tmp_path / "m.npz"
    assert (
        main(
            [
                "train",
                "--data",
                str(out),
                "--out",
                str(model),
                "--preset",
                "fast",
                "--iterations",
                "50",
                "--no-progress",
            ]
        )
        == 0
    )
    assert "framed at" in capsys.readouterr().out


def test_the_servo_fit_keeps_the_tempo_and_the_servos_speed():
    from rnnpb.analysis.metrics import phase_lag

    hands = _performer(6.0, period=0.9)[::3]  # 0.1 s a step
    mapping = MirrorMapping(dt=0.1)
    fit = fit_to_servos(hands, mapping, window=9)
    assert fit.reduced_steps > 0 and 0.2 < fit.amplitude.min() < 1.0
    change = np.abs(np.diff(fit.motor, axis=0)).max(axis=1)
    assert change.max() <= joint_step_limit(0.1) * 0.95 + 1e-9
    # in step with the person; the safe retargeting alone, holding each joint to its servo,
    # falls behind
    person = MirrorMapping(dt=10.0).retarget(hands).joints
    held = mapping.retarget(hands).joints
    assert abs(phase_lag(fit.motor[10:], person[10:])) <= 0.5
    assert phase_lag(held[10:], person[10:]) > abs(phase_lag(fit.motor[10:], person[10:])) + 0.5


def test_gestures_with_rests_are_cut_one_gesture_a_cycle(tmp_path):
    hands = _performer(12.0, period=1.2, rests=0.8)  # a raise, then 0.8 s still, every 2 s
    performance = Performance(
        np.arange(len(hands)) / FPS, hands, None, None, True, "3-d", "gestures"
    )
    for dt, steps in ((0.1, 20), (0.4, 5)):
        recording = learning_phase(performance, "raise", PhaseOptions(dt=dt))
        lengths = [b - a for a, b in recording.cycles.cycles]
        assert len(lengths) >= 4 and np.median(lengths) == pytest.approx(steps, abs=1)


def test_every_source_takes_the_time_scale(tmp_path):
    motion = perform([("1", 96)], PatternConfig(), np.random.default_rng(3))
    stream = tmp_path / "stream.csv"
    write_sensory_stream(stream, RobotCamera().sensory_from_hands(motion.measured))
    counts = {}
    for scale in ("1", "2"):
        out = tmp_path / f"x{scale}"
        assert (
            main(
                [
                    "record",
                    f"csv:{stream}",
                    "--time-scale",
                    scale,
                    "--pattern",
                    "one",
                    "--out",
                    str(out),
                ]
            )
            == 0
        )
        entry = json.loads((out / "recording.json").read_text())["recordings"]["one"]
        counts[scale] = (entry["steps"], entry["cycles"]["median_steps"])
    assert counts["2"][0] == pytest.approx(2 * counts["1"][0], abs=2)
    assert counts["2"][1] == pytest.approx(2 * counts["1"][1], abs=1)
