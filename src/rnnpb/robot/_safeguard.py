"""The robot's own safeguards, applied where a command reaches the joints.

Whatever sends the commands (the loop in this process, a loop on the bus, a stray node), the
robot side checks each command before it is applied:

- **joint limits**: each angle is clipped to the robot's limits (its :class:`RobotMap`);
- **speed**: no joint moves further in one step than its servo can (:func:`joint_step_limit`:
  the AX-12A's no-load speed times ``dt``) from the set point it holds;
- **watchdog**: when no command has come for more than ``watchdog_steps`` steps, the robot
  holds the pose it has (the sender is gone or stuck; a servo left at an old set point is not
  what anyone is watching any more).
"""

from __future__ import annotations

import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.robot._collision import joint_step_limit

WATCHDOG_STEPS = 2
"""Steps without a command after which the robot holds its pose: one late step is jitter, two
in a row is a sender that stopped."""


class Safeguard:
    """Joint limits and servo speed, applied to each command before the robot moves.

    Parameters
    ----------
    limits : array, shape (8, 2)
        (lower, upper) radians of each joint, in the robot's own angles.
    dt : float
        Seconds per step.
    max_step : float, optional
        Largest change of one joint per step, radians (default :func:`joint_step_limit`).
    """

    def __init__(self, limits: np.ndarray, dt: float, max_step: float | None = None) -> None:
        if not dt > 0:
            raise ConfigError(f"dt must be > 0, got {dt}")
        self.limits = np.asarray(limits, dtype=np.float64).reshape(-1, 2)
        self.max_step = joint_step_limit(dt) if max_step is None else float(max_step)
        if not self.max_step > 0:
            raise ConfigError(f"max_step must be > 0, got {self.max_step}")
        self.set_point: np.ndarray | None = None
        self.clipped = 0
        """Commands that asked for an angle beyond a joint limit."""
        self.slowed = 0
        """Commands that asked a joint to move faster than its servo."""

    def reset(self, set_point: np.ndarray) -> None:
        """The pose the robot holds now (where the next command's speed is measured from)."""
        self.set_point = np.asarray(set_point, dtype=np.float64).copy()

    def apply(self, command: np.ndarray) -> np.ndarray:
        """The command the robot may apply (clipped, then slowed); it becomes the set point."""
        command = np.asarray(command, dtype=np.float64)
        safe = np.clip(command, self.limits[:, 0], self.limits[:, 1])
        self.clipped += int(not np.array_equal(safe, command))
        if self.set_point is not None:
            delta = safe - self.set_point
            fast = np.abs(delta) > self.max_step
            if fast.any():  # only those joints change: a command within reach stays exact
                self.slowed += 1
                reach = self.set_point + np.sign(delta) * self.max_step
                safe = np.where(fast, np.clip(reach, self.limits[:, 0], self.limits[:, 1]), safe)
        self.set_point = safe.copy()
        return safe


class Watchdog:
    """Says when commands have stopped for more than ``steps`` steps of ``dt`` seconds."""

    def __init__(self, dt: float, steps: int = WATCHDOG_STEPS) -> None:
        if not dt > 0 or steps < 1:
            raise ConfigError(f"a watchdog needs dt > 0 and steps >= 1, got {dt}, {steps}")
        self.timeout = float(dt) * steps
        self.last: float | None = None

    def fed(self, now: float) -> None:
        """A command was applied at ``now`` (seconds, any monotonic clock)."""
        self.last = now

    def expired(self, now: float) -> bool:
        """No command for more than the timeout (never before the first command)."""
        return self.last is not None and now - self.last > self.timeout
