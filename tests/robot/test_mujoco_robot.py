"""The MuJoCo model and the position-controlled simulated robot."""

import numpy as np
import pytest

from rnnpb.demonstrator import learning_set
from rnnpb.errors import ConfigError
from rnnpb.robot import (
    JOINT_LIMITS,
    ROBOT_EYE,
    MujocoRobot,
    RobotCamera,
    forward_kinematics,
    load_model,
)
from rnnpb.vectors import MOTOR_NAMES


def test_model_joints_limits_and_camera_agree_with_the_python_side():
    model = load_model()
    for i, name in enumerate(MOTOR_NAMES):
        joint = model.joint(name)
        np.testing.assert_allclose(joint.range, JOINT_LIMITS[i])
        np.testing.assert_allclose(model.actuator(name).ctrlrange, JOINT_LIMITS[i])
    camera = RobotCamera()
    eye = model.camera(ROBOT_EYE)
    np.testing.assert_allclose(model.cam_pos[eye.id], camera.position, atol=1e-9)
    np.testing.assert_allclose(model.cam_fovy[eye.id], camera.fovy_deg)
    # Total mass of a QRIO-sized robot (QRIO: about 7 kg).
    assert 4.0 < model.body_mass.sum() < 9.0
    # About 0.6 m tall: the top of the head.
    assert 0.55 < camera.position[2] + 0.06 < 0.65


def test_simulated_hands_match_forward_kinematics():
    rng = np.random.default_rng(2)
    with MujocoRobot(n_substeps=20) as robot:
        for _ in range(5):
            robot.send(rng.uniform(JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1]))
            hands, _ = forward_kinematics(robot.read())
            np.testing.assert_allclose(robot.hand_positions(), hands, atol=1e-6)


def test_mujoco_robot_tracks_a_demonstrated_joint_trajectory():
    trajectory = np.concatenate([s.motor for s in learning_set("full", seed=0)[::2]])
    with MujocoRobot() as robot:
        assert robot.n_substeps == 200 and robot.dt == 0.4
        errors = []
        for target in trajectory:
            robot.send(target)
            errors.append(np.abs(robot.read() - target))
    errors = np.array(errors)[1:]  # the first command starts from the rest pose
    # Stated tracking error at the end of each 0.4 s step: below 0.02 rad (measured ~0.006).
    assert errors.max() < 0.02
    assert np.median(errors) < 0.01


def test_mujoco_robot_clips_targets_to_the_limits():
    with MujocoRobot(n_substeps=400, dt=0.8) as robot:
        robot.send(JOINT_LIMITS[:, 1] + 1.0)
        state = robot.read()
    assert np.all(state <= JOINT_LIMITS[:, 1] + 0.02)
    assert np.all(np.abs(state - JOINT_LIMITS[:, 1]) < 0.05)


def test_mujoco_robot_needs_connect():
    with pytest.raises(ConfigError, match="connect"):
        MujocoRobot().read()
    with pytest.raises(ConfigError, match="dt"):
        MujocoRobot(dt=0)
