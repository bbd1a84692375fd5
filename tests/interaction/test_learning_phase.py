"""The paper's learning phase from a camera: joint angles from the balls, cut into cycles."""

from __future__ import annotations

import numpy as np
import pytest

from rnnpb.cli import main
from rnnpb.demonstrator import Imperfection, MirrorMapping, PatternConfig, perform
from rnnpb.errors import RnnpbError
from rnnpb.interaction import ArraySensorySource, open_source
from rnnpb.interaction.learning_phase import (
    cut_sequences,
    cycle_bounds,
    record_demonstration,
)
from rnnpb.robot.camera import RobotCamera
from rnnpb.sequences import read_sequence_files, write_sensory_stream


@pytest.mark.parametrize("pattern", ["2", "4"])
def test_joint_angles_from_the_synthetic_camera_match_the_demonstrators(pattern):
    # the default scene: clutter, noise, lighting change, motion blur, occlusions
    with open_source(f"synthetic:{pattern}", steps=40, seed=11) as source:
        demonstration = record_demonstration(source)
    truth = MirrorMapping().motor_from_hands(source.frames.hands)
    valid = demonstration.valid
    assert valid.mean() > 0.7
    rms = np.sqrt(np.mean((demonstration.motor[valid] - truth[valid]) ** 2))
    assert rms < 0.05, f"joint angles off by {rms:.3f} rad RMS"


def test_cycles_are_cut_where_the_performance_starts_a_new_one():
    config = PatternConfig()
    for pattern in ("1", "3"):
        motion = perform([(pattern, 80)], config, np.random.default_rng(4))
        sensory = RobotCamera().sensory_from_hands(motion.measured)
        bounds = cycle_bounds(sensory)
        assert len(bounds) >= 4
        cycles = (motion.phase - motion.phase[0]) / (2 * np.pi)
        for start, stop in bounds:
            # each piece is one cycle of the performed phase, to within a step
            step = (cycles[-1] - cycles[0]) / (len(cycles) - 1)
            assert abs(cycles[stop] - cycles[start] - 1.0) < 1.5 * step


def test_a_still_or_shapeless_recording_has_no_cycles():
    rng = np.random.default_rng(0)
    assert cycle_bounds(np.full((60, 4), 0.5) + 1e-4 * rng.standard_normal((60, 4))) == []
    stream = 0.5 + 0.02 * np.cumsum(rng.standard_normal((60, 4)), axis=0) / 10
    with ArraySensorySource(stream) as source:
        demonstration = record_demonstration(source)
    assert demonstration.depth == "plane"
    with pytest.raises(RnnpbError, match="no stretch of 4 whole cycles"):
        cut_sequences(demonstration, "new")


def test_record_writes_sequences_that_train_reads(tmp_path, capsys):
    out = tmp_path / "three"
    assert (
        main(
            [
                "record",
                "synthetic:3",
                "--steps",
                "40",
                "--cycles",
                "2",
                "--pattern",
                "three",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    sequences = read_sequence_files([out])
    assert sequences and all(s.pattern == "three" for s in sequences)
    assert all(s.n_steps >= 20 for s in sequences)  # two whole cycles of about 12 steps
    assert "depth from ball size" in capsys.readouterr().out


def test_record_from_a_stream_without_depth_uses_the_plane(tmp_path, capsys):
    # a user without imperfection keeps the hands on the plane x = 0.68 m
    config = PatternConfig(imperfection=Imperfection.none())
    motion = perform([("2", 60)], config, np.random.default_rng(1))
    stream = tmp_path / "stream.csv"
    write_sensory_stream(stream, RobotCamera().sensory_from_hands(motion.measured))
    out = tmp_path / "two"
    assert (
        main(
            [
                "record",
                f"csv:{stream}",
                "--cut",
                "length",
                "--length",
                "25",
                "--pattern",
                "two",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    sequences = read_sequence_files([out])
    assert [s.n_steps for s in sequences] == [25, 25]
    # on the plane the synthetic user moves in, the angles are the demonstrator's own
    truth = MirrorMapping().motor_from_hands(motion.measured)
    assert np.abs(sequences[0].motor - truth[:25]).max() < 1e-4
    assert "fixed plane" in capsys.readouterr().out
    assert main(["record", f"csv:{stream}", "--pattern", "<x>", "--out", str(out)]) == 2


def test_a_demonstration_from_3d_hands_keeps_their_depth():
    from rnnpb.interaction.learning_phase import demonstration_from_hands

    motion = perform([("4", 30)], PatternConfig(), np.random.default_rng(2))
    hands = motion.hands.copy()
    hands[:, :, 0] += np.linspace(-0.1, 0.1, len(hands))[:, None]  # towards and away
    hands[7] = np.nan
    demonstration = demonstration_from_hands(hands, source="capture")
    valid = demonstration.valid
    assert demonstration.depth == "3-d" and not valid[7] and valid.sum() == 29
    np.testing.assert_allclose(
        demonstration.sensory[valid], RobotCamera().sensory_from_hands(hands[valid])
    )
    # the joint angles come from the 3-D hands, not from hands put back on one plane
    np.testing.assert_allclose(
        demonstration.motor[valid], MirrorMapping().motor_from_hands(hands[valid])
    )
    flat = hands.copy()
    flat[:, :, 0] = PatternConfig().body.hand_depth
    assert (
        np.abs(demonstration.motor[valid] - MirrorMapping().motor_from_hands(flat)[valid]).max()
        > 0.05
    )
