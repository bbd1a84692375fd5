"""ROS 2: the robot's joints as ``sensor_msgs/msg/JointState`` in and
``trajectory_msgs/msg/JointTrajectory`` out (a joint trajectory controller's input).

Two ways to a ROS 2 robot:

- **Over Zenoh through zenoh-bridge-ros2dds** (:class:`Ros2BridgeRobot`, ``--robot
  ros2dds[:CONTROLLER][@ENDPOINT]``): that bridge routes each ROS 2 topic to the Zenoh key of
  the topic's name without its leading ``/`` (``/joint_states`` ↔ ``joint_states``), the payload
  being the message in CDR, ROS 2's own serialization. This module encodes and decodes the two
  messages in CDR itself (little-endian XCDR1, the encapsulation ROS 2's DDS middlewares use), so
  no ROS 2 installation is needed on the loop's computer.
- **Through rclpy** (:class:`RclpyRobot`, ``--robot rclpy[:CONTROLLER]``) on a computer with
  ROS 2 installed and sourced; rclpy is not on the Python package index, so it is imported only
  then, with a one-line error naming what to install.

Either way the loop's end applies the robot-side safeguards itself before publishing (joint
limits from the robot map, the servo's speed), since a ROS 2 controller knows nothing of rnnpb's:
each command is a one-point trajectory reached in one step (``time_from_start = dt``), so a
controller whose commands stop simply holds the last point.
"""

from __future__ import annotations

import math
import struct
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from rnnpb.bridge._bus import BusConfig
from rnnpb.bridge._client import BusRobot
from rnnpb.bridge._messages import MessageError
from rnnpb.errors import ConfigError, RnnpbError
from rnnpb.robot import Robot, RobotMap, Safeguard, clip_to_limits
from rnnpb.robot._interface import as_joint_vector

DEFAULT_CONTROLLER = "joint_trajectory_controller"
"""ros2_control's usual name for an arm's joint trajectory controller."""
JOINT_STATES_TOPIC = "joint_states"
"""The joint state broadcaster's topic (``/joint_states``)."""
LOST_AFTER_STEPS = 1.5
"""Steps without a joint state after which the robot is gone (a joint state broadcaster
publishes far more often than once a step)."""
LOST_AFTER_S = 0.25
"""...and never sooner than this (seconds): a busy computer's scheduler is not a lost robot."""
_ENCAPSULATION = b"\x00\x01\x00\x00"  # CDR, little-endian, no options


@dataclass(frozen=True)
class Ros2JointState:
    """A decoded ``sensor_msgs/msg/JointState`` (velocity and effort are not used)."""

    stamp: float
    names: tuple[str, ...]
    position: np.ndarray


class _Writer:
    def __init__(self) -> None:
        self.body = bytearray()

    def _align(self, size: int) -> None:
        self.body += b"\x00" * (-len(self.body) % size)

    def u32(self, value: int) -> None:
        self._align(4)
        self.body += struct.pack("<I", value)

    def i32(self, value: int) -> None:
        self._align(4)
        self.body += struct.pack("<i", value)

    def string(self, text: str) -> None:
        data = text.encode("utf-8") + b"\x00"
        self.u32(len(data))
        self.body += data

    def strings(self, texts: tuple[str, ...] | list[str]) -> None:
        self.u32(len(texts))
        for text in texts:
            self.string(text)

    def doubles(self, values: np.ndarray | list[float]) -> None:
        self.u32(len(values))
        if len(values):
            self._align(8)
            self.body += struct.pack(f"<{len(values)}d", *values)

    def time(self, seconds: float) -> None:
        sec = math.floor(seconds)
        self.i32(sec)
        self.u32(min(999_999_999, round((seconds - sec) * 1e9)))

    def payload(self) -> bytes:
        return _ENCAPSULATION + bytes(self.body)


class _Reader:
    def __init__(self, payload: bytes) -> None:
        if len(payload) < 4 or payload[:2] != b"\x00\x01":
            raise MessageError("not little-endian CDR (encapsulation 0x0001)")
        self.body = memoryview(payload)[4:]
        self.at = 0

    def _take(self, size: int, align: int) -> memoryview:
        self.at += -self.at % align
        if self.at + size > len(self.body):
            raise MessageError("CDR message ends early")
        view = self.body[self.at : self.at + size]
        self.at += size
        return view

    def u32(self) -> int:
        return struct.unpack("<I", self._take(4, 4))[0]

    def i32(self) -> int:
        return struct.unpack("<i", self._take(4, 4))[0]

    def string(self) -> str:
        size = self.u32()
        if size == 0:
            raise MessageError("CDR string without its terminating NUL")
        data = bytes(self._take(size, 1))
        try:
            return data[:-1].decode("utf-8")
        except UnicodeDecodeError:
            raise MessageError("CDR string is not UTF-8") from None

    def strings(self) -> tuple[str, ...]:
        return tuple(self.string() for _ in range(self._count()))

    def doubles(self) -> np.ndarray:
        n = self._count()
        if n == 0:
            return np.zeros(0)
        return np.frombuffer(bytes(self._take(8 * n, 8)), dtype="<f8").astype(np.float64)

    def _count(self) -> int:
        n = self.u32()
        if n > len(self.body):
            raise MessageError("CDR sequence longer than the message")
        return n

    def time(self) -> float:
        return self.i32() + self.u32() * 1e-9


def encode_joint_state(names: tuple[str, ...], position: np.ndarray, stamp: float) -> bytes:
    """``sensor_msgs/msg/JointState`` in CDR (empty velocity and effort, empty frame_id)."""
    out = _Writer()
    out.time(stamp)
    out.string("")
    out.strings(names)
    out.doubles(np.asarray(position, dtype=np.float64))
    out.doubles([])
    out.doubles([])
    return out.payload()


def decode_joint_state(payload: bytes) -> Ros2JointState:
    reader = _Reader(payload)
    stamp = reader.time()
    reader.string()  # frame_id
    names = reader.strings()
    position = reader.doubles()
    if len(position) != len(names) or not np.all(np.isfinite(position)):
        raise MessageError("JointState: position must hold one finite angle per name")
    return Ros2JointState(stamp, names, position)


def encode_joint_trajectory(
    names: tuple[str, ...], position: np.ndarray, stamp: float, time_from_start: float
) -> bytes:
    """``trajectory_msgs/msg/JointTrajectory`` in CDR: one point, reached ``time_from_start``
    seconds after ``stamp`` (a stamp of 0 means "on receipt" to a joint trajectory
    controller; rnnpb sends 0, so that clocks need not agree)."""
    out = _Writer()
    out.time(stamp)
    out.string("")
    out.strings(names)
    out.u32(1)  # one point
    out.doubles(np.asarray(position, dtype=np.float64))
    out.doubles([])  # velocities
    out.doubles([])  # accelerations
    out.doubles([])  # effort
    out.time(time_from_start)
    return out.payload()


def decode_joint_trajectory(payload: bytes) -> tuple[tuple[str, ...], list[np.ndarray], float]:
    """The joint names, each point's positions, and the last point's time from start."""
    reader = _Reader(payload)
    reader.time()
    reader.string()
    names = reader.strings()
    points, last = [], 0.0
    for _ in range(reader._count()):
        points.append(reader.doubles())
        for _ in range(3):
            reader.doubles()
        last = reader.time()
    return names, points, last


class Ros2BridgeRobot(BusRobot):
    """A ROS 2 robot reached over Zenoh through zenoh-bridge-ros2dds (see the module doc).

    Joint states from Zenoh key ``joint_states``; commands to ``CONTROLLER/joint_trajectory``.
    """

    def __init__(
        self,
        controller: str = DEFAULT_CONTROLLER,
        dt: float = 0.4,
        robot_map: RobotMap | None = None,
        bus: BusConfig | None = None,
        on_event: Callable[[str], None] | None = None,
        waiting: Callable[[], None] | None = None,
        connect_timeout_s: float = 10.0,
        states_key: str = JOINT_STATES_TOPIC,
    ) -> None:
        super().__init__(dt, robot_map, bus, on_event, waiting, connect_timeout_s)
        self.controller = controller.strip("/")
        self.state_key = states_key.strip("/")
        self.command_key = f"{self.controller}/joint_trajectory"
        self.safeguard = Safeguard(self.map.limits, self.dt)

    def connect(self) -> None:
        self._session = self.bus.open()
        self._publisher = self._session.declare_publisher(self.command_key)
        self._session.declare_subscriber(self.state_key, self._on_state)
        with self._changed:
            if not self._changed.wait_for(lambda: self._states > 0, self.connect_timeout_s):
                self.disconnect()
                raise RnnpbError(
                    f"no sensor_msgs/JointState on Zenoh key {self.state_key} within "
                    f"{self.connect_timeout_s:g} s: is zenoh-bridge-ros2dds running beside the "
                    "robot's joint state broadcaster?"
                )
        self.safeguard.reset(self.map.to_robot(self.observe()))

    def _on_state(self, sample: Any) -> None:
        try:
            state = decode_joint_state(bytes(sample.payload.to_bytes()))
            order = {name: i for i, name in enumerate(state.names)}
            robot = np.array([state.position[order[name]] for name in self.map.names])
        except (MessageError, KeyError):
            # A broadcaster may also publish joints the map does not name, or other robots'.
            self.malformed_states += 1
            return
        self._arrived(self.map.to_network(robot))

    def send(self, joint_targets: np.ndarray) -> np.ndarray:
        if self._publisher is None:
            raise RnnpbError("Ros2BridgeRobot: send() before connect()")
        silent_s = time.monotonic() - self._received_at
        if silent_s > max(LOST_AFTER_STEPS * self.dt, LOST_AFTER_S):
            self._wait_for_return(silent_s)
            return self.observe()  # the late command is not sent
        robot = self.safeguard.apply(
            self.map.to_robot(clip_to_limits(as_joint_vector(joint_targets)))
        )
        self._publisher.put(encode_joint_trajectory(self.map.names, robot, 0.0, self.dt))
        return self.map.to_network(robot)

    def _wait_for_return(self, silent_s: float) -> None:
        self.outages += 1
        self.on_event(
            f"ROS 2 robot: no joint states on {self.state_key} for {silent_s:.2f} s; "
            "the loop waits for the robot"
        )
        count = self._states
        with self._changed:
            while not self._changed.wait_for(lambda: self._states > count, 0.05):
                if self._session is None:
                    raise RnnpbError("ROS 2 robot: disconnected while waiting")
                if self.waiting is not None:
                    self.waiting()
        self.safeguard.reset(self.map.to_robot(self.observe()))
        self.on_event("ROS 2 robot: joint states again; the loop resumes")


def import_rclpy() -> Any:
    """rclpy, its executor and the message types; one line naming what to install when
    missing."""
    from importlib import import_module

    try:
        rclpy = import_module("rclpy")
        executors = import_module("rclpy.executors")
        sensor_msgs = import_module("sensor_msgs.msg")
        trajectory_msgs = import_module("trajectory_msgs.msg")
    except ImportError:
        raise ConfigError(
            "--robot rclpy needs ROS 2's rclpy, sensor_msgs and trajectory_msgs, which are not "
            "on the Python package index: install ROS 2 (Humble or newer) and `source "
            "/opt/ros/<distro>/setup.bash` before running rnnpb, or use --robot ros2dds with "
            "zenoh-bridge-ros2dds (docs/bridge.md)"
        ) from None
    return (
        rclpy,
        executors.SingleThreadedExecutor,
        sensor_msgs.JointState,
        trajectory_msgs.JointTrajectory,
        trajectory_msgs.JointTrajectoryPoint,
    )


class RclpyRobot(Robot):
    """A ROS 2 robot through rclpy (ROS 2 installed and sourced): subscribes ``/joint_states``,
    publishes one-point trajectories to ``/CONTROLLER/joint_trajectory``."""

    def __init__(
        self,
        controller: str = DEFAULT_CONTROLLER,
        dt: float = 0.4,
        robot_map: RobotMap | None = None,
        connect_timeout_s: float = 10.0,
    ) -> None:
        self.controller = controller.strip("/")
        self.dt = float(dt)
        self.map = robot_map or RobotMap.humanoid()
        self.connect_timeout_s = float(connect_timeout_s)
        self.safeguard = Safeguard(self.map.limits, self.dt)
        self._position: np.ndarray | None = None
        self._node: Any = None
        self._executor: Any = None
        self._spin: threading.Thread | None = None
        self._arrived = threading.Event()

    def connect(self) -> None:
        rclpy, executor, joint_state, self._trajectory, self._point = import_rclpy()
        if not rclpy.ok():
            rclpy.init()
        self._node = rclpy.create_node("rnnpb_mirror")
        self._node.create_subscription(joint_state, f"/{JOINT_STATES_TOPIC}", self._on_state, 10)
        self._publisher = self._node.create_publisher(
            self._trajectory, f"/{self.controller}/joint_trajectory", 10
        )
        self._executor = executor()
        self._executor.add_node(self._node)
        self._spin = threading.Thread(target=self._executor.spin, daemon=True)
        self._spin.start()
        if not self._arrived.wait(self.connect_timeout_s):
            self.disconnect()
            raise RnnpbError(f"no /{JOINT_STATES_TOPIC} within {self.connect_timeout_s:g} s")
        self.safeguard.reset(self.map.to_robot(self.observe()))

    def _on_state(self, message: Any) -> None:
        order = {name: i for i, name in enumerate(message.name)}
        try:
            robot = np.array([message.position[order[name]] for name in self.map.names])
        except (KeyError, IndexError):
            return
        self._position = self.map.to_network(robot)
        self._arrived.set()

    def observe(self) -> np.ndarray:
        if self._position is None:
            raise RnnpbError(f"no /{JOINT_STATES_TOPIC} received yet")
        return self._position.copy()

    def send(self, joint_targets: np.ndarray) -> np.ndarray:
        robot = self.safeguard.apply(
            self.map.to_robot(clip_to_limits(as_joint_vector(joint_targets)))
        )
        point = self._point()
        point.positions = [float(x) for x in robot]
        point.time_from_start.sec = int(self.dt)
        point.time_from_start.nanosec = round((self.dt % 1) * 1e9)
        message = self._trajectory()
        message.joint_names = list(self.map.names)
        message.points = [point]
        self._publisher.publish(message)
        return self.map.to_network(robot)

    def disconnect(self) -> None:
        node, self._node = self._node, None
        if node is not None:
            self._executor.shutdown()
            node.destroy_node()
