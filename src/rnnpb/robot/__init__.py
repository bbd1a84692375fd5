"""The simulated humanoid robot: arm kinematics, joint limits, the robot contract and its
kinematic and MuJoCo implementations, the robot map and safeguards a real robot needs, and
rendering (see docs/robot-and-demonstrator.md and docs/bridge.md).

MuJoCo is imported, and its OpenGL chosen, only when a model is first loaded (a
:class:`MujocoRobot` connects, a :class:`RobotRenderer` is made).
"""

from rnnpb.robot._collision import (
    COLLISION_DEPTH,
    SERVO_NAME,
    SERVO_NO_LOAD_SPEED,
    Contact,
    SelfCollision,
    collision_pairs,
    joint_step_limit,
)
from rnnpb.robot._gl import choose_gl
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
from rnnpb.robot._map import RobotMap
from rnnpb.robot._mujoco import ROBOT_EYE, MujocoRobot, load_model
from rnnpb.robot._render import CAMERAS, RobotRenderer, render_pose, write_video
from rnnpb.robot._retarget import RETARGET_CLEARANCE, Retargeted, Retargeter, retarget
from rnnpb.robot._safeguard import WATCHDOG_STEPS, Safeguard, Watchdog
from rnnpb.robot.camera import RobotCamera

__all__ = [
    "ARM_SIDES",
    "COLLISION_DEPTH",
    "SERVO_NAME",
    "SERVO_NO_LOAD_SPEED",
    "Contact",
    "SelfCollision",
    "collision_pairs",
    "joint_step_limit",
    "ELBOW_AT_ZERO_PITCH",
    "ELBOW_PER_PITCH",
    "FOREARM_LENGTH",
    "JOINT_LIMITS",
    "SHOULDERS",
    "UPPER_ARM_LENGTH",
    "IKResult",
    "KinematicRobot",
    "CAMERAS",
    "ROBOT_EYE",
    "MujocoRobot",
    "RETARGET_CLEARANCE",
    "Retargeted",
    "Retargeter",
    "retarget",
    "RobotRenderer",
    "load_model",
    "render_pose",
    "write_video",
    "Robot",
    "RobotCamera",
    "RobotMap",
    "Safeguard",
    "WATCHDOG_STEPS",
    "Watchdog",
    "choose_gl",
    "clip_to_limits",
    "coupled_elbow",
    "coupled_pitch_range",
    "forward_kinematics",
    "inverse_kinematics",
]
