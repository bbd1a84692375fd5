"""Forward and inverse kinematics of the arms, joint limits and the kinematic robot."""

import numpy as np
import pytest

from rnnpb.errors import ConfigError
from rnnpb.robot import (
    JOINT_LIMITS,
    SHOULDERS,
    KinematicRobot,
    coupled_elbow,
    coupled_pitch_range,
    forward_kinematics,
    inverse_kinematics,
)
from rnnpb.vectors import MOTOR_NAMES


def within_limits(joints):
    return bool(np.all(joints >= JOINT_LIMITS[:, 0]) and np.all(joints <= JOINT_LIMITS[:, 1]))


def coupled_postures(n, rng):
    lo, hi = coupled_pitch_range()
    q = np.empty((n, 8))
    for a in (0, 4):
        q[:, a] = rng.uniform(lo, hi, n)
        q[:, a + 1] = rng.uniform(*JOINT_LIMITS[a + 1], n)
        q[:, a + 2] = rng.uniform(*JOINT_LIMITS[a + 2], n)
        q[:, a + 3] = coupled_elbow(q[:, a])
    return q


def test_joint_limits_table():
    assert JOINT_LIMITS.shape == (len(MOTOR_NAMES), 2)
    assert np.all(JOINT_LIMITS[:, 0] < JOINT_LIMITS[:, 1])
    # Both arms have the same ranges (mirror-symmetric joint senses).
    np.testing.assert_array_equal(JOINT_LIMITS[:4], JOINT_LIMITS[4:])
    lo, hi = coupled_pitch_range()
    assert JOINT_LIMITS[3, 0] <= coupled_elbow(lo) and coupled_elbow(hi) <= JOINT_LIMITS[3, 1]


def test_forward_kinematics_known_poses():
    hands, elbows = forward_kinematics(np.zeros(8))
    # Arms hanging straight down from the shoulders.
    np.testing.assert_allclose(hands, SHOULDERS - [0, 0, 0.21], atol=1e-12)
    np.testing.assert_allclose(elbows, SHOULDERS - [0, 0, 0.10], atol=1e-12)
    # Shoulder pitch +90 deg: both arms point forward, towards the user.
    hands, _ = forward_kinematics(np.array([np.pi / 2, 0, 0, 0] * 2))
    np.testing.assert_allclose(hands, SHOULDERS + [0.21, 0, 0], atol=1e-12)
    # Positive roll lifts each arm sideways, away from the body (mirror senses).
    hands, _ = forward_kinematics(np.array([0, np.pi / 2, 0, 0] * 2))
    np.testing.assert_allclose(hands, SHOULDERS + [[0, 0.21, 0], [0, -0.21, 0]], atol=1e-12)
    # Elbow pitch bends the forearm forward.
    hands, _ = forward_kinematics(np.array([0, 0, 0, np.pi / 2] * 2))
    np.testing.assert_allclose(hands, SHOULDERS + [0.11, 0, -0.10], atol=1e-12)


def test_symmetric_angles_give_mirror_image_poses():
    q = coupled_postures(50, np.random.default_rng(3))
    q[:, 4:] = q[:, :4]
    hands, elbows = forward_kinematics(q)
    np.testing.assert_allclose(hands[:, 1], hands[:, 0] * [1, -1, 1], atol=1e-12)
    np.testing.assert_allclose(elbows[:, 1], elbows[:, 0] * [1, -1, 1], atol=1e-12)


def test_ik_returns_to_the_target_over_the_reachable_workspace():
    rng = np.random.default_rng(0)
    q = coupled_postures(5000, rng)
    targets, _ = forward_kinematics(q)
    result = inverse_kinematics(targets)
    reached, _ = forward_kinematics(result.joints)
    error = np.linalg.norm(reached - targets, axis=-1)
    assert error.max() < 1e-3  # stated: < 1 mm; measured ~1e-15 m (closed form)
    assert result.all_reachable
    assert np.all(result.residual < 1e-4)
    assert within_limits(result.joints)
    # The coupling holds exactly.
    np.testing.assert_allclose(result.joints[:, [3, 7]], coupled_elbow(result.joints[:, [0, 4]]))


def test_ik_unreachable_target_gives_the_nearest_reachable_posture_and_says_so():
    far = SHOULDERS + [[0.5, 0.1, 0.0], [0.0, -0.1, 0.6]]  # beyond the 0.21 m reach
    result = inverse_kinematics(far)
    assert not result.reachable.any()
    assert within_limits(result.joints)
    reached, _ = forward_kinematics(result.joints)
    # The residual is what it says, and no random coupled posture gets closer.
    np.testing.assert_allclose(np.linalg.norm(reached - far, axis=-1), result.residual, atol=1e-9)
    others, _ = forward_kinematics(coupled_postures(20000, np.random.default_rng(1)))
    best_sampled = np.linalg.norm(others - far, axis=-1).min(axis=0)
    assert np.all(result.residual <= best_sampled + 1e-3)


def test_ik_random_targets_always_respect_limits():
    rng = np.random.default_rng(5)
    targets = SHOULDERS + rng.uniform(-0.25, 0.25, size=(300, 2, 3))
    result = inverse_kinematics(targets)
    assert within_limits(result.joints)
    reached, _ = forward_kinematics(result.joints)
    np.testing.assert_allclose(
        np.linalg.norm(reached - targets, axis=-1), result.residual, atol=1e-9
    )
    # Whatever is reported reachable is reached to 0.1 mm.
    assert np.all(result.residual[result.reachable] < 1e-4)
    assert 0.005 < result.reachable.mean() < 0.5  # the coupled workspace is a thin shell


def test_ik_rejects_bad_shapes():
    with pytest.raises(ValueError, match=r"\(\.\.\., 2, 3\)"):
        inverse_kinematics(np.zeros((3, 3)))


def test_kinematic_robot_reaches_commands_at_once_and_clips():
    with KinematicRobot() as robot:
        target = np.array([0.3, 0.2, -0.1, 1.5, 0.4, 0.1, 0.2, 1.6])
        robot.send(target)
        np.testing.assert_array_equal(robot.read(), target)
        robot.send(np.full(8, 10.0))
        np.testing.assert_array_equal(robot.read(), JOINT_LIMITS[:, 1])
        assert robot.history.shape == (2, 8)
    with KinematicRobot() as robot, pytest.raises(ConfigError, match="shape"):
        robot.send(np.zeros(7))
    with pytest.raises(ConfigError, match="connect"):
        KinematicRobot().send(np.zeros(8))
