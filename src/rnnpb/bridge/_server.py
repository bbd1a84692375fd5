"""The robot's end of the bridge: a robot (simulated here, any :class:`~rnnpb.robot.Robot`)
served on the bus, with the robot-side safeguards.

:class:`RobotServer` takes joint commands from ``PREFIX/joint_commands`` and publishes joint
states on ``PREFIX/joint_states``: one after every command it applies (``ack`` = the command's
``seq``) and one every half step while no command comes (the heartbeat that tells the loop
the robot is there). Before a command is applied:

- a message that is not a joint command naming exactly the robot's joints with finite radians
  is refused (counted as ``malformed``);
- a command older than one step (its ``stamp``), or not newer than the last one applied from
  the same sender (its ``seq``), is dropped (counted as ``stale``): a late command would move the
  robot to where the loop wanted it a step ago;
- the joint limits and the servo speed are enforced (:class:`~rnnpb.robot.Safeguard`);

and when commands stop for more than two steps the watchdog holds the pose
(:class:`~rnnpb.robot.Watchdog`; the state's ``holding`` says so).
"""

from __future__ import annotations

import queue
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from rnnpb.bridge._bus import BusConfig
from rnnpb.bridge._messages import (
    DEFAULT_PREFIX,
    JOINT_COMMANDS,
    JOINT_STATES,
    JointCommand,
    JointState,
    MessageError,
    decode_command,
    encode_state,
)
from rnnpb.robot import WATCHDOG_STEPS, Robot, RobotMap, Safeguard, Watchdog

MAX_AGE_STEPS = 1.0
"""A command older than this many steps (by its stamp) is dropped: the loop has moved on."""
QUEUE_LENGTH = 1024
"""Commands waiting to be applied; beyond it a flood is dropped (and counted) unread."""


class RobotServer:
    """Serves ``robot`` on the bus under ``prefix`` until :meth:`stop`.

    Parameters
    ----------
    robot : Robot
        Connected by :meth:`run`. It takes network angles; ``robot_map`` says how the bus's
        joint names and angles become those.
    prefix : str
    dt : float
        Seconds per step (the watchdog, the stale limit and the heartbeat count in steps).
    robot_map : RobotMap, optional
        The joints as they appear on the bus (default: the simulated humanoid's).
    bus : BusConfig, optional
    watchdog_steps : int
    max_age_steps : float
    on_event : callable(str), optional
        Told when the watchdog holds the pose and when commands come back.
    """

    def __init__(
        self,
        robot: Robot,
        prefix: str = DEFAULT_PREFIX,
        dt: float = 0.4,
        robot_map: RobotMap | None = None,
        bus: BusConfig | None = None,
        watchdog_steps: int = WATCHDOG_STEPS,
        max_age_steps: float = MAX_AGE_STEPS,
        on_event: Callable[[str], None] | None = None,
    ) -> None:
        self.robot = robot
        self.prefix = prefix.strip("/")
        self.dt = float(dt)
        self.map = robot_map or RobotMap.humanoid()
        self.bus = bus or BusConfig()
        self.safeguard = Safeguard(self.map.limits, self.dt)
        self.watchdog = Watchdog(self.dt, watchdog_steps)
        self.max_age_s = max_age_steps * self.dt
        self.on_event = on_event or (lambda text: print(text, flush=True))
        self.refused = {"malformed": 0, "stale": 0, "overflow": 0}
        self.applied = 0
        self.holding = False
        self._inbox: queue.Queue[bytes] = queue.Queue(maxsize=QUEUE_LENGTH)
        self._stop = threading.Event()
        self._seq = 0
        self._ack: int | None = None
        self._target: np.ndarray | None = None
        self._last_sender = ""
        self._last_command_seq = -1
        self._publisher: Any = None
        self.ready = threading.Event()
        """Set once the robot is connected and the server subscribed."""

    def stop(self) -> None:
        self._stop.set()

    def _on_command(self, sample: Any) -> None:
        try:
            self._inbox.put_nowait(bytes(sample.payload.to_bytes()))
        except queue.Full:
            self.refused["overflow"] += 1

    def run(self) -> None:
        """Connect the robot, serve until :meth:`stop`, disconnect."""
        with self.robot, self.bus.open() as session:
            self._publisher = session.declare_publisher(f"{self.prefix}/{JOINT_STATES}")
            subscriber = session.declare_subscriber(
                f"{self.prefix}/{JOINT_COMMANDS}", self._on_command
            )
            self.safeguard.reset(self.map.to_robot(self.robot.observe()))
            self._publish()
            last_published = last_moved = time.monotonic()
            self.ready.set()
            tick = min(self.dt / 20, 0.005)  # the watchdog's resolution
            heartbeat = self.dt / 2  # the loop says the robot is gone after 1.5 steps
            try:
                while not self._stop.is_set():
                    try:
                        payload = self._inbox.get(timeout=tick)
                    except queue.Empty:
                        payload = None
                    now = time.monotonic()
                    if payload is not None and self._apply(payload, now):
                        self._publish()
                        last_published = last_moved = now
                        continue
                    if self.watchdog.expired(now) and not self.holding:
                        self._hold()
                        self._publish()
                        last_published = now
                    held = self.safeguard.set_point
                    if self.holding and held is not None and now - last_moved >= self.dt:
                        # The robot keeps holding its pose, one step at a time.
                        self.robot.send(self.map.to_network(held))
                        last_moved = now
                    if time.monotonic() - last_published >= heartbeat:
                        self._publish()
                        last_published = time.monotonic()
            finally:
                subscriber.undeclare()
                self._publisher = None

    def _apply(self, payload: bytes, now: float) -> bool:
        try:
            command = decode_command(payload)
            robot_angles = self._in_map_order(command)
        except MessageError:
            self.refused["malformed"] += 1
            return False
        if self._stale(command):
            self.refused["stale"] += 1
            return False
        safe = self.safeguard.apply(robot_angles)
        sent = self.robot.send(self.map.to_network(safe))
        # What the robot itself did with it (a simulator clips to its own limits too).
        self._target = self.map.to_robot(sent)
        self.safeguard.set_point = self._target.copy()
        self._ack = command.seq
        self._last_sender, self._last_command_seq = command.sender, command.seq
        self.applied += 1
        self.watchdog.fed(now)
        if self.holding:
            self.holding = False
            self.on_event(f"commands again on {self.prefix}: the robot follows them")
        return True

    def _in_map_order(self, command: JointCommand) -> np.ndarray:
        if set(command.names) != set(self.map.names):
            missing = sorted(set(self.map.names) - set(command.names))
            raise MessageError(f"names: not this robot's joints (missing {missing})")
        order = {name: i for i, name in enumerate(command.names)}
        return np.array([command.position[order[name]] for name in self.map.names])

    def _stale(self, command: JointCommand) -> bool:
        if time.time() - command.stamp > self.max_age_s:
            return True
        return command.sender == self._last_sender and command.seq <= self._last_command_seq

    def _hold(self) -> None:
        pose = self.map.clip(self.map.to_robot(self.robot.observe()))
        self.safeguard.reset(pose)
        self._target = pose.copy()
        self.holding = True
        self.on_event(
            f"no commands on {self.prefix} for {self.watchdog.timeout:.2f} s: holding the pose"
        )

    def _publish(self) -> None:
        self._seq += 1
        state = JointState(
            seq=self._seq,
            stamp=time.time(),
            names=self.map.names,
            position=self.map.to_robot(self.robot.observe()),
            ack=self._ack,
            target=self._target,
            holding=self.holding,
            refused=dict(self.refused),
            clipped=self.safeguard.clipped,
            slowed=self.safeguard.slowed,
        )
        self._publisher.put(encode_state(state))
