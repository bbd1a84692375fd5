"""How a new model version takes over the running robot without the arm jumping.

The new version's mirror system goes on from the running one's interaction (its window, PB
and what it has seen: :meth:`rnnpb.model.MirrorSystem.continue_from`), but it is another
network: over the same past it may regress another PB (the pattern just learned) and command
another posture — a person saw the right shoulder jump from 39 to 6 degrees and the elbow from
110 to 84 in one step. So for :data:`HANDOVER_STEPS` steps both systems step on what is seen,
and the command sent moves from the old system's to the new one's by equal shares (a
cross-fade: each system's command is smooth in its own dynamics, and the first command is
almost the old one's), never further in a step than the servo can move
(:func:`rnnpb.robot.joint_step_limit`); then the new system drives alone.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

HANDOVER_STEPS = 6
"""Steps over which the command passes from the old version to the new: half a cycle of the
taught patterns (12 steps), long enough that the new system's first steps, which regress over
a past its network did not generate, weigh little, and short enough that the new pattern
drives within half a cycle (2.4 s at the paper's 0.4 s)."""
MAX_CATCH_UP = 4 * HANDOVER_STEPS
"""Steps after which the new system drives alone even if the servo limit still holds the
command back (its own movement faster than the servo: the command filter slows that)."""


class Handover:
    """A mirror system that hands over from ``old`` to ``new`` (both stepped each step until
    the hand-over ends; everything else is ``new``'s).

    Parameters
    ----------
    old, new : MirrorSystem
        ``new`` has gone on from ``old``'s interaction already.
    previous : array, shape (8,), or None
        The command sent last (radians); None: the first command is not limited.
    max_step : float
        The most a joint may move in one step (radians): the servo's step at the loop's dt.
    steps : int
    """

    def __init__(
        self, old, new, previous: np.ndarray | None, max_step: float, steps: int = HANDOVER_STEPS
    ) -> None:
        self.old = old
        self.new = new
        self.previous = None if previous is None else np.asarray(previous, dtype=np.float64)
        self.max_step = float(max_step)
        self.steps = int(steps)
        self.taken = 0  # steps since the swap
        self.done = False

    def __getattr__(self, name: str) -> Any:
        # Only what this object does not have itself: the new system's attributes.
        return getattr(self.new, name)

    def weight(self) -> float:
        """The new system's share of the command on this step (1: its command alone)."""
        return min(1.0, self.taken / self.steps)

    def step(self, observed_hands: np.ndarray, prior_pb: np.ndarray | None = None):
        result = self.new.step(observed_hands, prior_pb)
        if self.done:
            return result
        before = self.old.step(observed_hands)
        self.taken += 1
        target = np.asarray(result.motor, dtype=np.float64)
        weight = self.weight()
        command = (1.0 - weight) * np.asarray(before.motor, dtype=np.float64) + weight * target
        if self.previous is not None:
            move = np.clip(command - self.previous, -self.max_step, self.max_step)
            command = self.previous + move
        caught_up = weight >= 1.0 and np.allclose(command, target, atol=1e-9)
        if caught_up or self.taken >= self.steps + MAX_CATCH_UP:
            self.done = True
            command = target
        self.previous = command
        return dataclasses.replace(result, motor=command)
