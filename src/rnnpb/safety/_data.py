"""Is a dataset safe to learn? The robot's own checker (:class:`SafetyChecker`) over every step
of every training sequence, before a network learns to command them.

A step is refused when it would put an arm through the body or the other arm (at its pose or
on the way from the step before) or move a joint further than the servo can in one step: the
network would learn to command exactly that. A joint pressed against its limit is counted
but not refused: the inverse kinematics clamps unreachable targets to the limits, which is a
posture the robot can take.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from rnnpb.errors import ConfigError
from rnnpb.safety._check import SafetyChecker, SafetyLimits
from rnnpb.sequences import Sequence

REFUSED = ("collision", "speed")


@dataclass(frozen=True)
class DataSafety:
    """The unsafe steps of a dataset, by kind, and the first refused one.

    ``first`` is ``"SOURCE, step K: REASONS"`` of the first step with a collision or a speed
    beyond the servo's (steps count from 0 within each sequence), or ``""``.
    """

    steps: int
    collision: int
    speed: int
    limit: int
    unsafe: int
    first: str
    dt: float

    def describe(self) -> str:
        return (
            f"{self.steps} steps checked at dt {self.dt:g} s: {self.collision} colliding, "
            f"{self.speed} faster than the servos, {self.limit} against a joint limit"
        )


def check_data(
    sequences: Iterable[Sequence], dt: float = 0.4, checker: SafetyChecker | None = None
) -> DataSafety:
    """Check every step of ``sequences`` (their motor values, radians) at step time ``dt``."""
    if not dt > 0:
        raise ConfigError(f"dt must be > 0, got {dt}")
    checker = checker or SafetyChecker(SafetyLimits(dt=dt))
    if checker.limits.dt != dt:
        checker = SafetyChecker(SafetyLimits(dt=dt), checker.collision)
    steps = collision = speed = limit = unsafe = 0
    first = ""
    for sequence in sequences:
        result = checker.check(sequence.motor)
        kinds = result.kinds
        refused = kinds[:, 0] | kinds[:, 1]
        steps += len(kinds)
        collision += int(kinds[:, 0].sum())
        speed += int(kinds[:, 1].sum())
        limit += int(kinds[:, 2].sum())
        unsafe += int(refused.sum())
        if not first and refused.any():
            k = int(refused.argmax())
            words = [w for w in result.reasons[k].split() if w.split(":")[0] in REFUSED]
            first = f"{sequence.source or sequence.pattern}, step {k}: {' '.join(words)}"
    return DataSafety(steps, collision, speed, limit, unsafe, first, float(dt))
