"""The simulated humanoid robot: arm kinematics, joint limits, the robot interface and its
kinematic and MuJoCo implementations, and rendering (see docs/robot-and-demonstrator.md)."""

from rnnpb.robot._interface import KinematicRobot, Robot
from rnnpb.robot._kinematics import (
    ARM_SIDES,
    ELBOW_AT_ZERO_PITCH,
    ELBOW_PER_PITCH,
    FOREARM_LENGTH,
    JOINT_LIMITS,
    SHOULDERS,
    UPPER_ARM_LENGTH,
    IKResult,
    clip_to_limits,
    coupled_elbow,
    coupled_pitch_range,
    forward_kinematics,
    inverse_kinematics,
)
from rnnpb.robot.camera import RobotCamera

__all__ = [
    "ARM_SIDES",
    "ELBOW_AT_ZERO_PITCH",
    "ELBOW_PER_PITCH",
    "FOREARM_LENGTH",
    "JOINT_LIMITS",
    "SHOULDERS",
    "UPPER_ARM_LENGTH",
    "IKResult",
    "KinematicRobot",
    "CAMERAS",
    "MujocoRobot",
    "RobotRenderer",
    "load_model",
    "render_pose",
    "write_video",
    "Robot",
    "RobotCamera",
    "clip_to_limits",
    "coupled_elbow",
    "coupled_pitch_range",
    "forward_kinematics",
    "inverse_kinematics",
]


def __getattr__(name: str):
    # The MuJoCo parts import mujoco; load them only when asked for, so kinematics stay light.
    if name in ("MujocoRobot", "load_model"):
        from rnnpb.robot import _mujoco

        return getattr(_mujoco, name)
    if name in ("CAMERAS", "RobotRenderer", "render_pose", "write_video"):
        from rnnpb.robot import _render

        return getattr(_render, name)
    raise AttributeError(f"module 'rnnpb.robot' has no attribute {name!r}")
