"""Safety by experience: the checks, the command filter, the map file and the guarded
regression (docs/safety.md)."""

from __future__ import annotations

import numpy as np
import pytest

from rnnpb.demonstrator import learning_set, novel_scenario
from rnnpb.errors import ModelFileError
from rnnpb.interaction import InteractionLoop, read_session
from rnnpb.interaction.recorder import SessionRecorder
from rnnpb.model import MirrorSystem, OnlineConfig, TrainConfig, train
from rnnpb.robot import ELBOW_AT_ZERO_PITCH, JOINT_LIMITS, KinematicRobot, SelfCollision
from rnnpb.safety import (
    CommandFilter,
    SafetyChecker,
    describe_safety_map,
    find_safety_map,
    load_safety_map,
    safety_map_path,
)
from rnnpb.sources import ArraySensorySource

from .maps import constructed_map

REST = np.array([0.0, 0.0, 0.0, ELBOW_AT_ZERO_PITCH] * 2)
# The left arm swung across the body, upper arm turned in, elbow fully bent: the hand and
# forearm inside the chest.
HAND_IN_TORSO = np.array([0.3, -0.25, 1.6, 2.4, 0.0, 0.0, 0.0, ELBOW_AT_ZERO_PITCH])


@pytest.fixture(scope="module")
def checker():
    return SafetyChecker()


def test_the_hand_in_the_torso_is_a_collision_and_the_rest_pose_is_not(checker):
    collision = SelfCollision()
    assert collision.first_contact(HAND_IN_TORSO).endswith("-chest")
    assert not collision.collides(REST)
    report = checker.check(np.array([REST, HAND_IN_TORSO]))
    assert report.reasons[0] == ""
    assert "collision:" in report.reasons[1]


def test_a_command_putting_a_hand_into_the_torso_is_never_sent(checker):
    robot = KinematicRobot(initial=REST)
    command_filter = CommandFilter(checker, initial=REST)
    collision = SelfCollision()
    with robot:
        for _ in range(5):
            decision = command_filter(HAND_IN_TORSO)
            robot.send(decision.command)
            assert decision.unsafe and decision.filtered in ("held", "shortened")
    sent = robot.history
    assert not any(collision.collides(pose) for pose in sent)
    assert command_filter.prevented == 5


def test_a_command_faster_than_the_servo_is_slowed(checker):
    command_filter = CommandFilter(checker, initial=REST)
    fast = REST.copy()
    fast[0] = REST[0] + 3.0  # shoulder pitch 3 rad in one 0.4 s step
    decision = command_filter(fast)
    assert "speed:lshp" in decision.unsafe and decision.filtered == "slowed"
    assert abs(decision.command[0] - REST[0]) <= checker.limits.step_limit + 1e-12


def test_a_learned_pattern_that_is_safe_passes_the_filter_untouched(checker):
    for sequence in learning_set("1", seed=0):
        assert not checker.check(sequence.motor).unsafe.any()
        command_filter = CommandFilter(checker, initial=sequence.motor[0])
        for command in sequence.motor:
            decision = command_filter(command)
            assert decision.filtered == "" and decision.unsafe == ""
            np.testing.assert_array_equal(decision.command, command)


def test_the_loop_records_unsafe_and_filtered(tmp_path, model):
    class Unsafe(CommandFilter):
        def __call__(self, command):
            return super().__call__(HAND_IN_TORSO if self.steps % 2 else command)

    path = tmp_path / "session.csv"
    sensory = novel_scenario("1", n_steps=6, seed=0).sensory
    with ArraySensorySource(sensory) as source, SessionRecorder(path) as recorder:
        loop = InteractionLoop(
            MirrorSystem(model), source, recorder=recorder, command_filter=Unsafe(initial=REST)
        )
        loop.run()
    session = read_session(path)
    assert all("collision:" in session["unsafe"][i] for i in (1, 3, 5))
    assert all(session["filtered"][i] in ("held", "shortened") for i in (1, 3, 5))
    assert loop.prevented_commands >= 3


@pytest.fixture(scope="module")
def model(set1_model):
    """Learning set 1 with the fast preset: the session's shared model (tests/conftest.py)."""
    return set1_model


def test_a_constructed_unsafe_region_keeps_the_regressed_pb_out(model):
    pattern = model.patterns[1]
    centre = model.pattern_pb[pattern]
    maps = constructed_map(model, centre, familiarity_width=0.08)
    assert maps.risk(centre) > 0.9
    from rnnpb.demonstrator import held_scenario

    sensory = held_scenario(pattern, n_steps=60, seed=3).sensory
    distances = {}
    for guard in ("off", "projection", "barrier"):
        online = OnlineConfig(safety_guard=guard)
        mirror = MirrorSystem(model, online, meta=maps.meta)
        pbs = np.array([mirror.step(u).pb for u in sensory])
        distances[guard] = np.linalg.norm(pbs[20:] - centre, axis=1)
        risk = maps.risk(pbs[20:])
        if guard != "off":
            assert risk.max() < 0.5, (guard, risk.max())
    # Unguarded, the PB goes into the region the map calls unsafe.
    assert distances["off"].min() < 0.2


def test_a_missing_or_damaged_map_is_a_clear_error_or_the_documented_fallback(tmp_path, model):
    model_path = tmp_path / "m.npz"
    assert safety_map_path(model_path).name == "m.safety.npz"
    assert find_safety_map(model_path, model) is None  # fallback: the filter alone
    with pytest.raises(ModelFileError, match="no such file"):
        load_safety_map(safety_map_path(model_path))
    assert "none" in describe_safety_map(safety_map_path(model_path))
    maps = constructed_map(model, model.pattern_pb[model.patterns[0]], familiarity_width=0.08)
    maps.save(safety_map_path(model_path))
    assert load_safety_map(safety_map_path(model_path), model).fingerprint == maps.fingerprint
    assert "experienced PBs" in describe_safety_map(safety_map_path(model_path))
    data = safety_map_path(model_path).read_bytes()
    safety_map_path(model_path).write_bytes(data[: len(data) // 2])
    with pytest.raises(ModelFileError, match="m.safety.npz"):
        find_safety_map(model_path, model)
    assert "unusable" in describe_safety_map(safety_map_path(model_path))
    other = train(
        learning_set("2", seed=0), JOINT_LIMITS, config=TrainConfig.fast(iterations=50, seed=1)
    )
    maps.save(safety_map_path(model_path))
    with pytest.raises(ModelFileError, match="another model"):
        load_safety_map(safety_map_path(model_path), other)
