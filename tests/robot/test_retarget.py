"""Safe retargeting: never a posture through the robot's own body, never faster than a servo,
and the paper's inverse kinematics unchanged wherever it is safe."""

import numpy as np
import pytest

from rnnpb.demonstrator import MirrorMapping, UserBody, learning_set
from rnnpb.errors import ConfigError
from rnnpb.robot import (
    JOINT_LIMITS,
    RETARGET_CLEARANCE,
    SelfCollision,
    forward_kinematics,
    inverse_kinematics,
    joint_step_limit,
    retarget,
)

# Postures a person takes, as the user's hands in the robot frame (the user stands 1 m away,
# facing the robot; the left hand is at negative y).
PERSON = {
    "hips": [[0.97, -0.17, 0.50], [0.97, 0.17, 0.50]],
    "crossed in front of the chest": [[0.78, 0.10, 0.78], [0.78, -0.10, 0.80]],
    "above the head": [[0.95, -0.15, 1.50], [0.95, 0.15, 1.50]],
    "behind the back": [[1.15, -0.08, 0.62], [1.15, 0.08, 0.62]],
    "clapping at the chest": [[0.80, 0.0, 0.85], [0.80, 0.0, 0.85]],
}


@pytest.fixture(scope="module")
def collision() -> SelfCollision:
    return SelfCollision()


@pytest.mark.parametrize("name", sorted(PERSON))
def test_a_persons_posture_maps_to_a_clear_posture_near_it(name, collision):
    mapping = MirrorMapping(UserBody())
    hands = np.array([PERSON[name]])
    targets = mapping.robot_hand_targets(hands)
    plain = inverse_kinematics(targets)
    result = mapping.retarget(hands)
    q = result.joints[0]
    assert collision.clearance(q) >= RETARGET_CLEARANCE - 1e-6
    assert np.all((q >= JOINT_LIMITS[:, 0]) & (q <= JOINT_LIMITS[:, 1]))
    reached, _ = forward_kinematics(q)
    np.testing.assert_allclose(result.residual[0], np.linalg.norm(reached - targets[0], axis=-1))
    if collision.clearance(plain.joints[0]) >= RETARGET_CLEARANCE:
        np.testing.assert_array_equal(q, plain.joints[0])  # safe already: left alone
    else:
        assert result.adjusted[0] and not result.held[0]
        # Close to the request: each hand within 5 cm of its target (the robot's arm is 21 cm).
        assert np.all(result.residual[0] < 0.05), result.residual[0]


def test_hands_inside_the_chest_give_a_collision_free_posture_close_to_them(collision):
    # The robot's own hand targets placed inside its chest box (x 0±0.05, y 0±0.075, z
    # 0.24-0.42): the plain inverse kinematics reaches them, through the torso.
    targets = np.array([[[0.02, 0.03, 0.33], [0.02, -0.03, 0.33]]])
    plain = inverse_kinematics(targets)
    assert collision.collides(plain.joints[0])
    result = retarget(targets)
    assert not collision.collides(result.joints[0])
    assert collision.clearance(result.joints[0]) >= RETARGET_CLEARANCE - 1e-6
    # The closest clear place is in front of the chest: within 10 cm of the centre inside it.
    assert np.all(result.residual[0] < 0.10), result.residual[0]


def test_a_request_past_the_joint_limits_is_clamped():
    # Far above and behind the shoulders: no posture reaches it inside the limits.
    targets = np.array([[[-0.4, 0.2, 0.9], [-0.4, -0.2, 0.9]]])
    result = retarget(targets)
    q = result.joints[0]
    assert np.all((q >= JOINT_LIMITS[:, 0]) & (q <= JOINT_LIMITS[:, 1]))
    assert np.all(result.residual[0] > 0.1)


def test_no_step_is_faster_than_the_servo_and_the_path_stays_clear(collision):
    # A person's hands jumping between the hips and crossed in front of the chest, at dt 0.1:
    # the servo limit per step is 0.62 rad, less than the jumps ask for.
    mapping = MirrorMapping(UserBody(), dt=0.1)
    poses = [PERSON["hips"], PERSON["crossed in front of the chest"], PERSON["above the head"]]
    hands = np.array([poses[i % 3] for i in range(12)], dtype=float)
    result = mapping.retarget(hands)
    step = np.abs(np.diff(result.joints, axis=0))
    assert np.all(step <= joint_step_limit(0.1) + 1e-9)
    for a, b in zip(result.joints[:-1], result.joints[1:], strict=True):
        for w in (0.25, 0.5, 0.75, 1.0):
            assert not collision.collides(a + w * (b - a))
    # The same request at dt 0.4 moves further per step: the limit is the servo's, not fixed.
    wide = MirrorMapping(UserBody(), dt=0.4).retarget(hands)
    assert np.abs(np.diff(wide.joints, axis=0)).max() > joint_step_limit(0.1)


def test_a_previous_posture_limits_the_first_step():
    previous = np.array([0.2, 0.35, 0.0, 0.6, 0.2, 0.35, 0.0, 0.6])
    targets = MirrorMapping().robot_hand_targets(np.array([PERSON["above the head"]]))
    result = retarget(targets, dt=0.05, previous=previous)
    assert np.all(np.abs(result.joints[0] - previous) <= joint_step_limit(0.05) + 1e-9)


def test_lost_hands_give_nan_and_the_stream_goes_on(collision):
    hands = np.array([PERSON["hips"], PERSON["hips"], PERSON["crossed in front of the chest"]])
    hands[1] = np.nan
    result = MirrorMapping().retarget(hands)
    assert np.isnan(result.joints[1]).all() and np.isnan(result.residual[1]).all()
    assert np.isfinite(result.joints[[0, 2]]).all()
    assert not collision.collides(result.joints[2])


def test_the_demonstrators_postures_are_left_exactly_as_the_paper_maps_them():
    for sequence in learning_set(1, seed=3):
        plain = inverse_kinematics(MirrorMapping().robot_hand_targets(sequence.meta["measured"]))
        np.testing.assert_array_equal(sequence.motor, plain.joints)


def test_bad_input_is_one_line():
    with pytest.raises(ConfigError, match="shape"):
        retarget(np.zeros((3, 3)))
    with pytest.raises(ConfigError, match="dt"):
        retarget(np.zeros((1, 2, 3)), dt=0.0)
    with pytest.raises(ConfigError, match="previous"):
        retarget(np.zeros((1, 2, 3)), previous=np.full(8, np.nan))
