"""What unsafe means for the humanoid, step by step (docs/safety.md).

A motor command (8 joint angles, radians) is unsafe at a step when

- ``collision``: it puts an arm through the torso, the head or the other arm (at the target
  pose or on the straight joint-space path to it from the step before, the path the servos'
  ramp takes; :class:`rnnpb.robot.SelfCollision`);
- ``speed``: a joint would move further in the step than its servo can
  (:func:`rnnpb.robot.joint_step_limit`);
- ``limit``: a joint is pressed against its limit (within ``limit_margin`` of it);
- ``unsettled``: the motion of the last ``settle_window`` steps neither rests nor repeats
  (incoherent dynamics, the paper's section 4.1 concern).

The first three are physical: they are what the command filter stops and what the targets
count. ``unsettled`` is reported beside them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.robot import JOINT_LIMITS, SelfCollision, joint_step_limit
from rnnpb.vectors import MOTOR_NAMES, MOTOR_SIZE

PHYSICAL = ("collision", "speed", "limit")


@dataclass(frozen=True)
class SafetyLimits:
    """How strict the checks are. ``dt``: seconds per step (the speed limit per step is the
    servo's speed times ``dt``); ``path_points``: poses checked on the way from one command to
    the next; ``limit_margin``: radians from a joint limit that count as pressed against it;
    ``settle_window``/``settle_tolerance``: steps over which a motion must rest or repeat, and
    the RMS mismatch (radians) it may keep."""

    dt: float = 0.4
    path_points: int = 3
    limit_margin: float = 0.01
    settle_window: int = 40
    settle_tolerance: float = 0.05

    def __post_init__(self) -> None:
        if not self.dt > 0:
            raise ConfigError(f"dt must be > 0, got {self.dt}")
        if self.path_points < 0:
            raise ConfigError(f"path_points must be >= 0, got {self.path_points}")
        if self.limit_margin < 0 or self.settle_tolerance < 0:
            raise ConfigError("limit_margin and settle_tolerance must be >= 0")
        if self.settle_window < 4:
            raise ConfigError(f"settle_window must be >= 4 steps, got {self.settle_window}")

    @property
    def step_limit(self) -> float:
        """Largest joint change per step, radians."""
        return joint_step_limit(self.dt)


@dataclass(frozen=True)
class SequenceSafety:
    """Which steps of a motor sequence are unsafe, and why.

    ``reasons[t]`` is empty when step ``t`` is safe, else words such as
    ``"collision:lhand_geom-chest speed:lshp"``; ``kinds`` (T, 4) bool marks ``collision``,
    ``speed``, ``limit``, ``unsettled`` per step.
    """

    reasons: tuple[str, ...]
    kinds: np.ndarray = field(repr=False)

    KINDS = ("collision", "speed", "limit", "unsettled")

    @property
    def unsafe(self) -> np.ndarray:
        """(T,) bool: a physical reason (collision, speed, limit) at the step."""
        return self.kinds[:, :3].any(axis=1)

    def count(self, kind: str) -> int:
        return int(self.kinds[:, self.KINDS.index(kind)].sum())


class SafetyChecker:
    """Checks motor commands; holds the self-collision model (made once)."""

    def __init__(
        self, limits: SafetyLimits | None = None, collision: SelfCollision | None = None
    ) -> None:
        self.limits = limits or SafetyLimits()
        self.collision = collision or SelfCollision()

    def path_contact(self, start: np.ndarray | None, target: np.ndarray) -> str:
        """The first collision on the way from ``start`` to ``target`` (or at ``target``), as
        ``"part-other"``; ``""`` when the way is clear."""
        if start is None:
            return self.collision.first_contact(target)
        n = self.limits.path_points
        for w in (*(np.arange(1, n + 1) / (n + 1)), 1.0):
            hit = self.collision.first_contact(start + w * (target - start))
            if hit:
                return hit
        return ""

    def command_reasons(self, previous: np.ndarray | None, command: np.ndarray) -> list[str]:
        """The physical reasons a command is unsafe after ``previous`` (None: the first)."""
        reasons = []
        hit = self.path_contact(previous, command)
        if hit:
            reasons.append(f"collision:{hit}")
        if previous is not None:
            fast = np.abs(command - previous) > self.limits.step_limit
            reasons += [f"speed:{MOTOR_NAMES[j]}" for j in np.flatnonzero(fast)]
        margin = self.limits.limit_margin
        pressed = (command <= JOINT_LIMITS[:, 0] + margin) | (
            command >= JOINT_LIMITS[:, 1] - margin
        )
        reasons += [f"limit:{MOTOR_NAMES[j]}" for j in np.flatnonzero(pressed)]
        return reasons

    def check(self, motor: np.ndarray, previous: np.ndarray | None = None) -> SequenceSafety:
        """Which steps of ``motor`` (T, 8) radians are unsafe and why; ``previous`` (8,) is
        the pose before the first step (None: the first step has no speed or path check)."""
        motor = np.asarray(motor, dtype=np.float64)
        if motor.ndim != 2 or motor.shape[1] != MOTOR_SIZE:
            raise ConfigError(
                f"motor sequence must have shape (T, {MOTOR_SIZE}), got {motor.shape}"
            )
        if not np.all(np.isfinite(motor)):
            raise ConfigError("motor sequence must be finite")
        kinds = np.zeros((len(motor), 4), bool)
        reasons: list[str] = []
        unsettled = unsettled_steps(motor, self.limits)
        before = previous
        for t, command in enumerate(motor):
            words = self.command_reasons(before, command)
            if unsettled[t]:
                words.append("unsettled")
            for k, kind in enumerate(SequenceSafety.KINDS):
                kinds[t, k] = any(w.split(":")[0] == kind for w in words)
            reasons.append(" ".join(words))
            before = command
        return SequenceSafety(tuple(reasons), kinds)


def unsettled_steps(motor: np.ndarray, limits: SafetyLimits) -> np.ndarray:
    """(T,) bool: the last ``settle_window`` steps up to ``t`` neither rest nor repeat with a
    period of at most half the window (RMS mismatch above ``settle_tolerance`` at every
    period); False for the first ``settle_window - 1`` steps."""
    motor = np.asarray(motor, dtype=np.float64)
    w = limits.settle_window
    out = np.zeros(len(motor), bool)
    if len(motor) < w:
        return out
    windows = np.lib.stride_tricks.sliding_window_view(motor, w, axis=0)  # (T-w+1, 8, w)
    windows = np.moveaxis(windows, -1, 1)  # (n, w, 8)
    half = w // 2
    best = np.full(len(windows), np.inf)
    for lag in range(1, half + 1):
        late = windows[:, w - half :]
        early = windows[:, w - half - lag : w - lag]
        best = np.minimum(best, np.sqrt(np.mean((late - early) ** 2, axis=(1, 2))))
    out[w - 1 :] = best > limits.settle_tolerance
    return out
