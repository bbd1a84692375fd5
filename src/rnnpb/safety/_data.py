"""Can a dataset be learned? The one check that ``rnnpb record`` writes by, ``rnnpb train``
learns by, and teaching and the dashboard keep a movement by (:func:`check_data`).

A step is refused when

- a hand position lies outside the view ([0, 1]) or a joint angle outside the robot's joint
  limits (the network's inputs are normalized by them), or
- the robot's own checker (:class:`SafetyChecker`) finds that it would put an arm through the
  body or the other arm (at its pose or on the way from the step before) or move a joint
  further than the servo can in one step: the network would learn to command exactly that.

A joint pressed against its limit is counted but not refused: the inverse kinematics clamps
unreachable targets to the limits, which is a posture the robot can take. Data are checked as
they are written (:func:`as_written`: six decimals), so that what ``record`` checked is what
``train`` reads.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.robot import JOINT_LIMITS
from rnnpb.safety._check import SafetyChecker, SafetyLimits
from rnnpb.sequences import Sequence
from rnnpb.vectors import MOTOR_NAMES, SENSORY_NAMES

REFUSED = ("collision", "speed")
RANGE_TOLERANCE = 1e-9
"""How far (normalized units) a value may lie outside its range: the learning's own check."""


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
    outside: int = 0

    def describe(self) -> str:
        words = (
            f"{self.steps} steps checked at dt {self.dt:g} s: {self.collision} colliding, "
            f"{self.speed} faster than the servos, {self.limit} against a joint limit"
        )
        if self.outside:
            words += f", {self.outside} with a value outside its range"
        return words

    def to_json(self) -> dict:
        return {
            "steps": self.steps,
            "collision": self.collision,
            "speed": self.speed,
            "limit": self.limit,
            "outside": self.outside,
            "refused": self.unsafe,
            "dt": self.dt,
        }


def as_written(sequence: Sequence) -> Sequence:
    """``sequence`` with its values rounded as a sequence file holds them (six decimals)."""
    return Sequence(
        np.round(sequence.sensory, 6),
        np.round(sequence.motor, 6),
        sequence.pattern,
        sequence.source,
        meta=sequence.meta,
    )


def _outside(sequence: Sequence) -> tuple[np.ndarray, str]:
    """(n,) steps with a value outside its range, and the first one described."""
    lower = np.concatenate([np.zeros(len(SENSORY_NAMES)), JOINT_LIMITS[:, 0]])
    upper = np.concatenate([np.ones(len(SENSORY_NAMES)), JOINT_LIMITS[:, 1]])
    raw = np.concatenate([sequence.sensory, sequence.motor], axis=1)
    x = (raw - lower) / (upper - lower)
    bad = (x < -RANGE_TOLERANCE) | (x > 1 + RANGE_TOLERANCE)
    steps = bad.any(axis=1)
    if not steps.any():
        return steps, ""
    t, column = (int(v) for v in np.argwhere(bad)[0])
    name = (*SENSORY_NAMES, *MOTOR_NAMES)[column]
    kind = "hands in [0, 1]" if column < len(SENSORY_NAMES) else "joints within the robot's limits"
    return steps, (
        f"step {t}: {name} = {raw[t, column]:.4g} is outside its range [{lower[column]:.4g}, "
        f"{upper[column]:.4g}] ({kind})"
    )


def check_data(
    sequences: Iterable[Sequence], dt: float = 0.4, checker: SafetyChecker | None = None
) -> DataSafety:
    """Check every step of ``sequences`` at step time ``dt`` (module doc): the ranges of their
    values, and their motor values (radians) by the robot's checker."""
    if not dt > 0:
        raise ConfigError(f"dt must be > 0, got {dt}")
    checker = checker or SafetyChecker(SafetyLimits(dt=dt))
    if checker.limits.dt != dt:
        checker = SafetyChecker(SafetyLimits(dt=dt), checker.collision)
    steps = collision = speed = limit = unsafe = outside = 0
    first = ""
    for sequence in sequences:
        where = sequence.source or sequence.pattern
        out_of_range, described = _outside(sequence)
        result = checker.check(sequence.motor)
        kinds = result.kinds
        refused = kinds[:, 0] | kinds[:, 1]
        steps += len(kinds)
        collision += int(kinds[:, 0].sum())
        speed += int(kinds[:, 1].sum())
        limit += int(kinds[:, 2].sum())
        outside += int(out_of_range.sum())
        unsafe += int((refused | out_of_range).sum())
        if not first and out_of_range.any():
            first = f"{where}, {described}"
        elif not first and refused.any():
            k = int(refused.argmax())
            words = [w for w in result.reasons[k].split() if w.split(":")[0] in REFUSED]
            first = f"{where}, step {k}: {' '.join(words)}"
    return DataSafety(steps, collision, speed, limit, unsafe, first, float(dt), outside)
