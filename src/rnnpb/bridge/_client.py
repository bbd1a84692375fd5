"""The loop's end of the bridge: :class:`ZenohRobot`, a robot on the bus behind the contract.

Each :meth:`ZenohRobot.send` maps the network's eight angles to the robot's joints (its
:class:`~rnnpb.robot.RobotMap`: names, sign, offset, limits), publishes one joint command and
waits for the joint state that acknowledges it; it returns the set point the robot applied
(after its own safeguards), in network angles.

When no joint state arrives for ``lost_after_steps`` steps (1.5, and at least 0.25 s) the
robot is gone (killed, cable
out, network down): :meth:`send` says so (``on_event``), and waits for the robot's joint states
to come back, and says so again; the loop stops meanwhile, since ``send`` is inside its step,
and carries on with its next step, so that no recorded step is lost. The command of the step
that waited is not applied late (the robot drops a command older than one step): the step
records the pose the robot reported on its return.
"""

from __future__ import annotations

import secrets
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
    decode_state,
    encode_command,
)
from rnnpb.errors import RnnpbError
from rnnpb.robot import Robot, RobotMap, clip_to_limits
from rnnpb.robot._interface import as_joint_vector

LOST_AFTER_STEPS = 1.5
"""Steps without a joint state after which the loop says the robot is gone and waits: the
robot publishes one at least every half step, so this is three missed in a row (not jitter),
and the loop says so within two steps of the robot's end."""
LOST_AFTER_S = 0.25
"""...and never sooner than this (seconds): at a short step a robot process on a busy computer
can be held up that long by the scheduler without being gone."""
CONNECT_TIMEOUT_S = 10.0
"""How long :meth:`ZenohRobot.connect` waits for the robot's first joint state: a robot process
started at the same moment needs a few seconds to come up."""


class RobotUnreachable(RnnpbError):
    """No robot answers on the bus."""


class BusRobot(Robot):
    """What every robot reached over a bus shares: the joint states arriving on a subscriber
    thread (the newest position, when it came, how many), the condition the loop waits on,
    the last position it observed, and closing the session."""

    def __init__(
        self,
        dt: float,
        robot_map: RobotMap | None,
        bus: BusConfig | None,
        on_event: Callable[[str], None] | None,
        waiting: Callable[[], None] | None,
        connect_timeout_s: float,
    ) -> None:
        self.dt = float(dt)
        self.map = robot_map or RobotMap.humanoid()
        self.bus = bus or BusConfig()
        self.on_event = on_event or (lambda text: print(text, flush=True))
        self.waiting = waiting
        self.connect_timeout_s = float(connect_timeout_s)
        self._session: Any = None
        self._publisher: Any = None
        self._subscriber: Any = None
        self._position: np.ndarray | None = None
        self._received_at = 0.0
        self._states = 0
        self._changed = threading.Condition()
        self.malformed_states = 0
        self.outages = 0
        """How many times the robot went silent."""

    state_key: str

    def _arrived(self, position: np.ndarray) -> None:
        """A joint state's position (network order) arrived: keep it and wake the waiters."""
        with self._changed:
            self._position = position
            self._received_at = time.monotonic()
            self._states += 1
            self._changed.notify_all()

    def observe(self) -> np.ndarray:
        with self._changed:
            if self._position is None:
                raise RobotUnreachable(f"no joint state received on {self.state_key} yet")
            return self._position.copy()

    def disconnect(self) -> None:
        session, self._session = self._session, None
        self._publisher = self._subscriber = None
        if session is not None:
            session.close()


class ZenohRobot(BusRobot):
    """A robot process on a Zenoh bus (``rnnpb robot serve``, or any node that speaks the
    messages of :mod:`rnnpb.bridge._messages`).

    Parameters
    ----------
    prefix : str
        Key prefix: states on ``PREFIX/joint_states``, commands on ``PREFIX/joint_commands``.
    dt : float
        Seconds per network step.
    robot_map : RobotMap, optional
        The robot's joints (default: the simulated humanoid's).
    bus : BusConfig, optional
        Endpoints (default: Zenoh's discovery).
    on_event : callable(str), optional
        Told when the robot goes and comes back (default: print).
    waiting : callable(), optional
        Called about every 50 ms while the robot is gone (a place to check for Ctrl-C).
    connect_timeout_s : float
        Seconds :meth:`connect` waits for the first joint state.
    """

    def __init__(
        self,
        prefix: str = DEFAULT_PREFIX,
        dt: float = 0.4,
        robot_map: RobotMap | None = None,
        bus: BusConfig | None = None,
        on_event: Callable[[str], None] | None = None,
        waiting: Callable[[], None] | None = None,
        connect_timeout_s: float = CONNECT_TIMEOUT_S,
        lost_after_steps: float = LOST_AFTER_STEPS,
    ) -> None:
        super().__init__(dt, robot_map, bus, on_event, waiting, connect_timeout_s)
        self.prefix = prefix.strip("/")
        self.lost_after_steps = float(lost_after_steps)
        self.sender = secrets.token_hex(8)
        self._state: JointState | None = None
        self._seq = 0
        self.unanswered = 0
        """Commands the robot did not acknowledge while its states kept coming (refused)."""

    @property
    def is_connected(self) -> bool:
        return self._session is not None

    @property
    def commands_sent(self) -> int:
        return self._seq

    @property
    def state_key(self) -> str:
        return f"{self.prefix}/{JOINT_STATES}"

    @property
    def command_key(self) -> str:
        return f"{self.prefix}/{JOINT_COMMANDS}"

    def connect(self) -> None:
        session = self.bus.open()
        self._session = session
        self._publisher = session.declare_publisher(self.command_key)
        self._subscriber = session.declare_subscriber(self.state_key, self._on_state)
        if self._wait_for_state(lambda: self._states > 0, self.connect_timeout_s) is None:
            self.disconnect()
            raise RobotUnreachable(
                f"no joint states on {self.state_key} within {self.connect_timeout_s:g} s: "
                "is the robot process (`rnnpb robot serve`) running on the same bus?"
            )

    def _on_state(self, sample: Any) -> None:
        try:
            state = decode_state(bytes(sample.payload.to_bytes()))
            position = self._to_network(state, state.position)
        except MessageError:
            self.malformed_states += 1
            return
        with self._changed:  # reentrant: _arrived takes it again
            self._state = state
            self._arrived(position)

    def _to_network(self, state: JointState, values: np.ndarray) -> np.ndarray:
        order = {name: i for i, name in enumerate(state.names)}
        try:
            robot = np.array([values[order[name]] for name in self.map.names])
        except KeyError as error:
            raise MessageError(f"joint state without joint {error}") from None
        return self.map.to_network(robot)

    def _wait_for_state(self, ready: Callable[[], bool], timeout_s: float) -> JointState | None:
        """Wait until ``ready()`` (under the lock; checked on every state and every 10 ms) or
        the timeout; the latest state or None."""
        deadline = time.monotonic() + timeout_s
        with self._changed:
            while not ready():
                left = deadline - time.monotonic()
                if left <= 0:
                    return None
                self._changed.wait(min(left, 0.01))
            return self._state

    def send(self, joint_targets: np.ndarray) -> np.ndarray:
        if self._publisher is None:
            raise RobotUnreachable("ZenohRobot: send() before connect()")
        network = clip_to_limits(as_joint_vector(joint_targets))
        robot = self.map.clip(self.map.to_robot(network))
        self._seq += 1
        seq = self._seq
        command = JointCommand(seq, time.time(), self.map.names, robot, self.sender)
        self._publisher.put(encode_command(command))
        timeout = max(self.lost_after_steps * self.dt, LOST_AFTER_S)

        def silent() -> bool:
            return time.monotonic() - self._received_at > timeout

        self._wait_for_state(lambda: self._acknowledged(seq) or silent(), timeout)
        with self._changed:
            state = self._state if self._acknowledged(seq) else None
        if state is not None:
            return self._to_network(state, state.target if state.target is not None else robot)
        if not silent():
            # States keep coming but none acknowledges this command: the robot refused it.
            self.unanswered += 1
            if self.unanswered == 1:
                self.on_event(
                    f"robot on {self.prefix}: command {seq} not applied (the robot refused it; "
                    "its joint states count why)"
                )
            return self.observe()
        return self._wait_for_return(time.monotonic() - self._received_at)

    def _acknowledged(self, seq: int) -> bool:
        state = self._state
        return state is not None and state.ack is not None and state.ack >= seq

    def _wait_for_return(self, silent_s: float) -> np.ndarray:
        self.outages += 1
        lost_at = time.monotonic()
        count = self._states
        self.on_event(
            f"robot on {self.prefix}: no joint states for {silent_s:.2f} s "
            f"({silent_s / self.dt:.1f} steps); the loop waits for the robot"
        )
        while self._wait_for_state(lambda: self._states > count, 0.05) is None:
            if self._session is None:
                raise RobotUnreachable(f"robot on {self.prefix}: disconnected while waiting")
            if self.waiting is not None:
                self.waiting()
        self.on_event(
            f"robot on {self.prefix}: back after {time.monotonic() - lost_at:.1f} s; "
            "the loop resumes"
        )
        return self.observe()
