"""The robot interface: what the interaction loop drives, simulated or real.

A robot is a context manager over ``connect`` / ``send`` / ``read`` / ``close``. ``send`` takes
the eight joint targets (radians, MOTOR_NAMES order) for one network step and returns when the
step's motion has been commanded (a simulator runs the step's physics inside ``send``);
``read`` returns the joint angles the robot has now.

Adding a real robot: subclass :class:`Robot`, open the connection in ``connect`` (raise an
:class:`rnnpb.errors.RnnpbError` subclass when the robot cannot be reached), map the eight
angles to the robot's own joint names, signs and zero offsets in ``send`` (clip them to the
robot's limits first: :func:`rnnpb.robot.clip_to_limits` or the robot's own table), read the
encoders in ``read``, and make ``close`` stop the motors and be safe to call twice. Position
control is what the paper used; ``send`` should not block longer than one step (``dt``).
"""

from __future__ import annotations

from collections import deque

import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.robot._kinematics import JOINT_LIMITS, clip_to_limits
from rnnpb.vectors import MOTOR_SIZE


def as_joint_vector(joints: np.ndarray, what: str = "joint targets") -> np.ndarray:
    """Validate an (8,) joint vector of finite radians."""
    joints = np.asarray(joints, dtype=np.float64)
    if joints.shape != (MOTOR_SIZE,):
        raise ConfigError(f"{what} must have shape ({MOTOR_SIZE},), got {joints.shape}")
    if not np.all(np.isfinite(joints)):
        raise ConfigError(f"{what} must be finite, got {joints}")
    return joints


class Robot:
    """Base class of robots: a context manager over ``connect``/``send``/``read``/``close``."""

    dt: float = 0.4

    def connect(self) -> None:
        """Open the robot (start the simulation, connect to the hardware)."""

    def send(self, joint_targets: np.ndarray) -> None:
        """Command the eight joint angles (radians) for one step; clipped to the limits."""
        raise NotImplementedError

    def read(self) -> np.ndarray:
        """The eight joint angles (radians) now, shape (8,)."""
        raise NotImplementedError

    def close(self) -> None:
        """Release the robot. Safe to call twice."""

    def __enter__(self) -> Robot:
        self.connect()
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()


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

    def send(self, joint_targets: np.ndarray) -> None:
        if not self._connected:
            raise ConfigError("KinematicRobot: send() before connect()")
        self._joints = clip_to_limits(as_joint_vector(joint_targets))
        self._history.append(self._joints.copy())

    def read(self) -> np.ndarray:
        return self._joints.copy()

    def close(self) -> None:
        self._connected = False

    @property
    def history(self) -> np.ndarray:
        return np.array(self._history).reshape(-1, MOTOR_SIZE)

    @property
    def limits(self) -> np.ndarray:
        return JOINT_LIMITS
