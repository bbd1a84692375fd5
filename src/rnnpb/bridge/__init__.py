"""A robot on the other end of a Zenoh bus (docs/bridge.md).

:class:`ZenohRobot` is the loop's end: a :class:`rnnpb.robot.Robot` whose joints are on the
bus; :class:`Ros2BridgeRobot` and :class:`RclpyRobot` are a ROS 2 robot's (through
zenoh-bridge-ros2dds, or rclpy when ROS 2 is installed). :class:`RobotServer` is the robot's
end (``rnnpb robot serve``): a robot served on the bus behind the robot-side safeguards.
:class:`ZenohHandsSource` takes the person's hands from a camera node on the bus. The messages
are JSON (:mod:`rnnpb.bridge._messages`), so a robot-side node can be written in any language.
Zenoh (``eclipse-zenoh``) is imported when a session is opened.
"""

from rnnpb.bridge._bus import BusConfig, import_zenoh, parse_bus_spec
from rnnpb.bridge._client import LOST_AFTER_STEPS, RobotUnreachable, ZenohRobot
from rnnpb.bridge._hands import ZenohHandsSource
from rnnpb.bridge._messages import (
    DEFAULT_PREFIX,
    JOINT_COMMANDS,
    JOINT_STATES,
    HandsMessage,
    JointCommand,
    JointState,
    MessageError,
    decode_command,
    decode_hands,
    decode_state,
    encode_command,
    encode_hands,
    encode_state,
)
from rnnpb.bridge._ros2 import (
    DEFAULT_CONTROLLER,
    RclpyRobot,
    Ros2BridgeRobot,
    decode_joint_state,
    decode_joint_trajectory,
    encode_joint_state,
    encode_joint_trajectory,
)
from rnnpb.bridge._server import MAX_AGE_STEPS, RobotServer

__all__ = [
    "DEFAULT_CONTROLLER",
    "DEFAULT_PREFIX",
    "JOINT_COMMANDS",
    "JOINT_STATES",
    "LOST_AFTER_STEPS",
    "MAX_AGE_STEPS",
    "BusConfig",
    "HandsMessage",
    "JointCommand",
    "JointState",
    "MessageError",
    "RclpyRobot",
    "Ros2BridgeRobot",
    "RobotServer",
    "RobotUnreachable",
    "ZenohHandsSource",
    "ZenohRobot",
    "decode_command",
    "decode_hands",
    "decode_joint_state",
    "decode_joint_trajectory",
    "decode_state",
    "encode_command",
    "encode_hands",
    "encode_joint_state",
    "encode_joint_trajectory",
    "encode_state",
    "import_zenoh",
    "parse_bus_spec",
]
