"""ROS 2: JointState and JointTrajectory in CDR, a ROS 2 robot reached through
zenoh-bridge-ros2dds's key convention, and rclpy's absence said in one line."""

from __future__ import annotations

import importlib.util
import threading
import time

import numpy as np
import pytest

from rnnpb.bridge import BusConfig, MessageError
from rnnpb.bridge._ros2 import (
    decode_joint_state,
    decode_joint_trajectory,
    encode_joint_state,
    encode_joint_trajectory,
)
from rnnpb.commands.robot import open_robot
from rnnpb.errors import ConfigError
from rnnpb.robot import JOINT_LIMITS, joint_step_limit
from rnnpb.vectors import MOTOR_NAMES

from ._robot_process import free_port, wait_until

# Written by rosbags 0.11.9's ROS 2 Humble serializer (`serialize_cdr`) for these values.
NAMES = ("lshp", "l", "shoulder_pitch_joint", "x")
POSITION = np.array([0.1, -2.5, 3.0, 1e-9])
JOINT_STATE = bytes.fromhex(
    "00010000f863306940597307010000000000000004000000050000006c73687000000000020000006c00000015"
    "00000073686f756c6465725f70697463685f6a6f696e74000000000200000078000000040000009a9999999999"
    "b93f00000000000004c0000000000000084095d626e80b2e113e0000000000000000"
)
JOINT_TRAJECTORY = bytes.fromhex(
    "000100000000000000000000010000000000000004000000050000006c73687000000000020000006c00000015"
    "00000073686f756c6465725f70697463685f6a6f696e740000000002000000780000000100000004000000000000"
    "009a9999999999b93f00000000000004c0000000000000084095d626e80b2e113e0000000000000000000000000000"
    "00000084d717"
)


def test_cdr_matches_ros2s_own_serialization():
    assert encode_joint_state(NAMES, POSITION, 1764779000.125) == JOINT_STATE
    assert encode_joint_trajectory(NAMES, POSITION, 0.0, 0.4) == JOINT_TRAJECTORY
    state = decode_joint_state(JOINT_STATE)
    assert state.names == NAMES and state.stamp == pytest.approx(1764779000.125)
    np.testing.assert_array_equal(state.position, POSITION)
    names, points, time_from_start = decode_joint_trajectory(JOINT_TRAJECTORY)
    assert names == NAMES and time_from_start == pytest.approx(0.4)
    np.testing.assert_array_equal(points[0], POSITION)


@pytest.mark.parametrize(
    "payload", [b"", b"\x00\x00\x00\x00", JOINT_STATE[:40], b"\x00\x01\x00\x00" + b"\xff" * 12]
)
def test_malformed_cdr_is_refused(payload):
    with pytest.raises(MessageError):
        decode_joint_state(payload)


class FakeRos2Arm:
    """What zenoh-bridge-ros2dds shows of a ROS 2 arm: CDR joint states on `joint_states` at
    50 Hz, and the trajectories its controller receives."""

    def __init__(self, endpoint: str, controller: str) -> None:
        self.session = BusConfig(listen=(endpoint,)).open()
        self.names = tuple(f"arm_{n}" for n in MOTOR_NAMES)
        self.position = np.zeros(8)
        self.received: list[tuple[tuple[str, ...], np.ndarray, float]] = []
        self.session.declare_subscriber(f"{controller}/joint_trajectory", self._on_trajectory)
        self.publisher = self.session.declare_publisher("joint_states")
        self.running = True
        self.thread = threading.Thread(target=self._broadcast, daemon=True)
        self.thread.start()

    def _on_trajectory(self, sample) -> None:
        names, points, reach = decode_joint_trajectory(bytes(sample.payload.to_bytes()))
        self.received.append((names, points[0], reach))
        order = {n: i for i, n in enumerate(names)}
        self.position = np.array([points[0][order[n]] for n in self.names])

    def _broadcast(self) -> None:
        while self.running:
            self.publisher.put(encode_joint_state(self.names, self.position, time.time()))
            time.sleep(0.02)

    def close(self) -> None:
        self.running = False
        self.thread.join()
        self.session.close()


def test_a_ros2_arm_through_the_ros2dds_bridge_keys(tmp_path):
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    arm = FakeRos2Arm(endpoint, "arm_controller")
    (tmp_path / "arm.toml").write_text(
        "\n".join(f'[joints.{n}]\nname = "arm_{n}"\n' for n in MOTOR_NAMES)
    )
    dt = 0.1
    try:
        robot = open_robot(f"ros2dds:arm_controller@{endpoint}", dt, str(tmp_path / "arm.toml"))
        with robot:
            target = np.clip(np.full(8, 0.3), JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1])
            np.testing.assert_array_equal(robot.send(target), target)
            assert wait_until(lambda: len(arm.received) == 1)
            names, position, reach = arm.received[0]
            assert names == arm.names and reach == pytest.approx(dt)
            np.testing.assert_array_equal(position, target)
            assert wait_until(lambda: np.array_equal(robot.observe(), target))
            # Limits and speed are enforced on this side: the controller knows nothing of them.
            sent = robot.send(JOINT_LIMITS[:, 1] + 1.0)
            step = joint_step_limit(dt)
            np.testing.assert_allclose(sent, np.minimum(target + step, JOINT_LIMITS[:, 1]))
    finally:
        arm.close()


def test_without_ros2_rclpy_is_one_line_naming_what_to_install():
    if importlib.util.find_spec("rclpy") is not None:
        pytest.skip("ROS 2 is installed here")
    with pytest.raises(ConfigError) as error:
        open_robot("rclpy:arm_controller", 0.4).connect()
    message = str(error.value)
    assert "\n" not in message and "rclpy" in message and "install ROS 2" in message
