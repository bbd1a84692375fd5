"""The Zenoh bridge between two processes on loopback: the loop's end here, ``rnnpb robot serve``
(the kinematic humanoid) in a subprocess."""

from __future__ import annotations

import json
import threading
import time

import numpy as np
import pytest

from rnnpb.bridge import (
    JointCommand,
    ZenohRobot,
    decode_state,
    encode_command,
)
from rnnpb.robot import JOINT_LIMITS, RobotMap, joint_step_limit
from rnnpb.vectors import MOTOR_NAMES

from ._robot_process import REST, RobotProcess, wait_until

DT = 0.1


@pytest.fixture
def robot_process():
    process = RobotProcess(dt=DT).start()
    yield process
    process.kill()


class Tap:
    """A second peer on the bus: publishes raw commands and keeps every joint state."""

    def __init__(self, process: RobotProcess) -> None:
        self.session = process.bus().open()
        self.states = []
        self.command_key = f"{process.prefix}/joint_commands"
        self.session.declare_subscriber(
            f"{process.prefix}/joint_states",
            lambda s: self.states.append(decode_state(bytes(s.payload.to_bytes()))),
        )
        import zenoh

        # Blocking, not dropping, under congestion: every message the tests send arrives.
        self.publisher = self.session.declare_publisher(
            self.command_key, congestion_control=zenoh.CongestionControl.BLOCK
        )
        assert wait_until(lambda: self.states), "the robot process publishes no joint states"

    def put(self, payload: bytes) -> None:
        self.publisher.put(payload)

    def command(self, position, seq: int, stamp: float | None = None, sender: str = "tap"):
        stamp = time.time() if stamp is None else stamp
        self.put(
            encode_command(JointCommand(seq, stamp, MOTOR_NAMES, np.asarray(position), sender))
        )

    def last(self):
        return self.states[-1]

    def close(self) -> None:
        self.session.close()


def _walk(n: int) -> np.ndarray:
    """n targets inside the limits from the rest pose, each within the servo's reach of the
    one before."""
    phase = np.linspace(0, 2 * np.pi, n)[:, None]
    return np.clip(0.3 * np.sin(phase + np.arange(8)), JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1])


def test_commands_arrive_in_order_and_the_robot_answers_each(robot_process):
    tap = Tap(robot_process)
    try:
        with ZenohRobot(robot_process.prefix, dt=DT, bus=robot_process.bus()) as robot:
            first = robot.send(REST)
            for target in _walk(40):
                sent = robot.send(target)
                np.testing.assert_array_equal(sent, target)  # JSON keeps every float exact
                np.testing.assert_array_equal(robot.observe(), target)
            assert wait_until(lambda: tap.states and tap.last().ack == 41)
        np.testing.assert_array_equal(first, REST)
        acks = [s.ack for s in tap.states if s.ack is not None]
        assert acks == sorted(acks) and acks[-1] == 41
        assert tap.last().refused == {"malformed": 0, "stale": 0, "overflow": 0}
    finally:
        tap.close()


def test_limits_clamp_on_both_ends(robot_process):
    tap = Tap(robot_process)
    try:
        with ZenohRobot(robot_process.prefix, dt=DT, bus=robot_process.bus()) as robot:
            step = joint_step_limit(DT)
            first = robot.send(JOINT_LIMITS[:, 1])  # too far for one step: slowed
            np.testing.assert_allclose(first, np.minimum(REST + step, JOINT_LIMITS[:, 1]))
            for _ in range(8):
                robot.send(JOINT_LIMITS[:, 1])
            # The loop's end clips to the map's limits before publishing.
            np.testing.assert_array_equal(robot.send(JOINT_LIMITS[:, 1] + 5.0), JOINT_LIMITS[:, 1])
        assert wait_until(lambda: tap.states and tap.last().ack == 10)
        slowed = tap.last().slowed
        assert tap.last().clipped == 0 and slowed > 0
        # The robot's end clips what arrives beyond its limits, and slows what is too fast.
        tap.command(JOINT_LIMITS[:, 1] + 5.0, seq=1)
        assert wait_until(lambda: tap.last().ack == 1 and tap.last().clipped == 1)
        np.testing.assert_array_equal(tap.last().target, JOINT_LIMITS[:, 1])
        tap.command(JOINT_LIMITS[:, 0], seq=2)
        assert wait_until(lambda: tap.last().ack == 2)
        expected = np.maximum(JOINT_LIMITS[:, 1] - step, JOINT_LIMITS[:, 0])
        np.testing.assert_allclose(tap.last().target, expected)
        np.testing.assert_allclose(tap.last().position, expected)
        assert tap.last().slowed == slowed + 1
    finally:
        tap.close()


def test_malformed_and_stale_commands_are_refused_and_counted(robot_process):
    tap = Tap(robot_process)
    try:
        tap.command(REST, seq=5)
        assert wait_until(lambda: tap.states and tap.last().ack == 5)
        good = dict(seq=9, stamp=time.time(), names=list(MOTOR_NAMES), position=[0.5] * 8)
        malformed = [
            b"\xff\xfe not utf-8",
            b"{not json",
            b"[1, 2, 3]",
            json.dumps({**good, "names": list(MOTOR_NAMES[:7])}).encode(),
            json.dumps({**good, "names": ["elbow"] + list(MOTOR_NAMES[1:])}).encode(),
            json.dumps({**good, "position": [0.5] * 7 + ["x"]}).encode(),
            json.dumps({**good, "seq": -1}).encode(),
            b'{"seq": 9, "stamp": 1e999, "names": [], "position": []}',
            b"x" * 70_000,
        ]
        # One at a time, each counted before the next.
        for count, payload in enumerate(malformed, start=1):
            tap.put(payload)
            counted = wait_until(lambda n=count: tap.last().refused["malformed"] == n)
            assert counted, (payload[:40], tap.last().refused, tap.last().ack)
        stale = [
            dict(seq=11, stamp=time.time() - 10 * DT),  # a late one
            dict(seq=4),  # older than the last applied
            dict(seq=5),  # the same again
        ]
        for count, late in enumerate(stale, start=1):
            tap.command(np.full(8, 0.5), **late)
            counted = wait_until(lambda n=count: tap.last().refused["stale"] == n)
            assert counted, (late, tap.last().refused, tap.last().ack)
        assert tap.last().refused["malformed"] == len(malformed)
        assert tap.last().ack == 5  # none applied
        np.testing.assert_array_equal(tap.last().position, REST)
    finally:
        tap.close()
    # Stopped, the robot says what it did.
    words = robot_process.stop()
    assert f"1 commands applied; refused {len(malformed)} malformed, 3 stale, 0 overflow" in words


def test_the_watchdog_holds_the_pose_when_commands_stop(robot_process):
    tap = Tap(robot_process)
    try:
        for seq, target in enumerate(_walk(5), start=1):
            tap.command(target, seq=seq)
            assert wait_until(lambda seq=seq: tap.states and tap.last().ack == seq)
        last_command = time.monotonic()
        assert not tap.last().holding
        assert wait_until(lambda: tap.last().holding, timeout_s=2.0)
        held_after = time.monotonic() - last_command
        # (measured from when this process saw the last answer, a few ms after the robot did)
        assert 2 * DT - 0.03 < held_after <= 2 * DT + 0.1
        pose = tap.last().position
        time.sleep(3 * DT)
        np.testing.assert_array_equal(tap.last().position, pose)
        tap.command(REST, seq=6)  # commands again: the robot follows
        assert wait_until(lambda: tap.last().ack == 6 and not tap.last().holding)
    finally:
        tap.close()


def test_the_loop_says_when_the_robot_is_gone_and_resumes_when_it_returns():
    process = RobotProcess(dt=DT).start()
    events: list[str] = []
    try:
        with ZenohRobot(process.prefix, dt=DT, bus=process.bus(), on_event=events.append) as robot:
            robot.send(REST)
            process.kill()
            restarted = RobotProcess(dt=DT)
            restarted.prefix, restarted.endpoint = process.prefix, process.endpoint
            threading.Timer(0.5, restarted.start).start()
            started = time.monotonic()
            sent = robot.send(np.full(8, 0.3))
            waited = time.monotonic() - started
            # The restarted robot is at its own rest pose: the late command was not applied.
            np.testing.assert_array_equal(sent, robot.observe())
            assert robot.outages == 1
            assert "no joint states" in events[0] and "steps); the loop waits" in events[0]
            assert "back after" in events[1]
            assert waited >= 0.5
            np.testing.assert_array_equal(robot.send(REST), REST)  # and it drives it again
            process = restarted
    finally:
        process.kill()


def test_a_robot_map_renames_and_turns_the_joints(robot_process, tmp_path):
    text = "\n".join(
        f'[joints.{name}]\nname = "j{i}"\nsign = {-1 if i % 2 else 1}\noffset = {0.1 * i}\n'
        for i, name in enumerate(MOTOR_NAMES)
    )
    (tmp_path / "arm.toml").write_text(text)
    robot_map = RobotMap.load(tmp_path / "arm.toml")
    process = RobotProcess(dt=DT, robot_map=tmp_path / "arm.toml").start()
    tap = Tap(process)
    try:
        with ZenohRobot(process.prefix, dt=DT, robot_map=robot_map, bus=process.bus()) as robot:
            for target in _walk(5):
                np.testing.assert_allclose(robot.send(target), target, atol=1e-12)
            assert wait_until(lambda: tap.states and tap.last().ack == 5)
        assert tap.last().names == tuple(f"j{i}" for i in range(8))
        np.testing.assert_allclose(tap.last().position, robot_map.to_robot(_walk(5)[-1]))
    finally:
        tap.close()
        process.kill()


def test_no_robot_on_the_bus_is_one_clear_error():
    from rnnpb.bridge import BusConfig, RobotUnreachable

    from ._robot_process import free_port

    bus = BusConfig(connect=(f"tcp/127.0.0.1:{free_port()}",))
    with pytest.raises(RobotUnreachable, match="no joint states on nobody/joint_states"):
        ZenohRobot("nobody", dt=DT, bus=bus, connect_timeout_s=0.3).connect()
