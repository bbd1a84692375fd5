"""The robot contract: what the interaction loop drives, simulated or real.

A robot is a context manager over ``connect`` / ``observe`` / ``send`` / ``disconnect``, the
shape of LeRobot's ``Robot`` (``connect``, ``get_observation``, ``send_action`` returning the
action actually sent, ``disconnect``):

- ``connect()`` opens the robot (starts the simulation, opens the connection to the hardware or
  the bus) and raises an :class:`rnnpb.errors.RnnpbError` subclass when it cannot be reached;
- ``observe()`` returns the joint state now: the eight joint angles, radians, shape (8,), in
  ``MOTOR_NAMES`` order;
- ``send(joint_targets)`` commands the eight joint targets (radians, ``MOTOR_NAMES`` order) for
  one network step and returns the targets actually sent, after the robot's own safeguards
  (joint limits, and on a real robot its speed limit); a simulator runs the step's physics
  inside ``send``;
- ``disconnect()`` stops the motors and releases the robot; safe to call twice.

``read()`` and ``close()`` are the earlier names of ``observe()`` and ``disconnect()`` and stay
as aliases.

Implementations: :class:`KinematicRobot` (no dynamics), :class:`rnnpb.robot.MujocoRobot` (the
simulated humanoid) and :class:`rnnpb.bridge.ZenohRobot` (a robot process on a Zenoh bus, any
robot whose joints a :class:`rnnpb.robot.RobotMap` names). Position control is what the paper
used; ``send`` should not block longer than one step (``dt``).
"""

from __future__ import annotations

from collections import deque
from typing import Self

import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.robot._kinematics import JOINT_LIMITS, clip_to_limits
from rnnpb.vectors import MOTOR_NAMES, MOTOR_SIZE


def as_joint_vector(joints: np.ndarray, what: str = "joint targets") -> np.ndarray:
    """Validate an (8,) joint vector of finite radians."""
    joints = np.asarray(joints, dtype=np.float64)
    if joints.shape != (MOTOR_SIZE,):
        raise ConfigError(f"{what} must have shape ({MOTOR_SIZE},), got {joints.shape}")
    if not np.all(np.isfinite(joints)):
        raise ConfigError(f"{what} must be finite, got {joints}")
    return joints


class Robot:
    """Base class of robots: a context manager over ``connect`` / ``observe`` / ``send`` /
    ``disconnect`` (see the module doc)."""

    dt: float = 0.4
    joint_names: tuple[str, ...] = MOTOR_NAMES
    """The joints ``observe`` and ``send`` take, in order (the network's eight)."""

    def connect(self) -> None:
        """Open the robot (start the simulation, connect to the hardware or the bus)."""

    def observe(self) -> np.ndarray:
        """The joint state now: eight joint angles (radians), shape (8,)."""
        raise NotImplementedError

    def send(self, joint_targets: np.ndarray) -> np.ndarray:
        """Command the eight joint angles (radians) for one step; returns what was sent,
        shape (8,), after the robot's safeguards (at least the joint limits)."""
        raise NotImplementedError

    def disconnect(self) -> None:
        """Release the robot. Safe to call twice."""

    def read(self) -> np.ndarray:
        """The earlier name of :meth:`observe`."""
        return self.observe()

    def close(self) -> None:
        """The earlier name of :meth:`disconnect`."""
        self.disconnect()

    def __enter__(self) -> Self:
        self.connect()
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.disconnect()


class KinematicRobot(Robot):
    """A robot without dynamics: each command is reached at once (clipped to the limits).

    For tests and fast runs. ``history`` holds the joint states sent, shape (n, 8): the last
    ``history_length`` of them, so that a long-running loop keeps a bounded footprint.
    """

    def __init__(
        self, initial: np.ndarray | None = None, dt: float = 0.4, history_length: int = 10_000
    ) -> None:
        if dt <= 0:
            raise ConfigError(f"dt must be > 0, got {dt}")
        if history_length < 0:
            raise ConfigError(f"history_length must be >= 0, got {history_length}")
        self.dt = float(dt)
        start = np.zeros(MOTOR_SIZE) if initial is None else as_joint_vector(initial, "initial")
        self._joints = clip_to_limits(start)
        self._history: deque[np.ndarray] = deque(maxlen=history_length)
        self._connected = False

    def connect(self) -> None:
        self._connected = True

    @property
    def is_connected(self) -> bool:
        return self._connected

    def send(self, joint_targets: np.ndarray) -> np.ndarray:
        if not self._connected:
            raise ConfigError("KinematicRobot: send() before connect()")
        self._joints = clip_to_limits(as_joint_vector(joint_targets))
        self._history.append(self._joints.copy())
        return self._joints.copy()

    def observe(self) -> np.ndarray:
        return self._joints.copy()

    def disconnect(self) -> None:
        self._connected = False

    @property
    def history(self) -> np.ndarray:
        return np.array(self._history).reshape(-1, MOTOR_SIZE)

    @property
    def limits(self) -> np.ndarray:
        return JOINT_LIMITS
