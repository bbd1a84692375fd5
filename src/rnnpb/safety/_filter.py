"""The last line of defence: every motor command is checked before it is sent.

A command that asks a joint to move faster than its servo can is slowed (each joint's change
clipped to the per-step limit); a command whose way from the pose before (the servo ramp's
straight joint-space path) or whose target would put an arm through the body or the other arm
is cut short to the furthest safe point on that way (halving), or held (the pose before is
sent again). The filter says what it did: ``unsafe`` (why the command as generated was
unsafe, empty when safe) and ``filtered`` (``""``, ``"slowed"``, ``"shortened"`` or
``"held"``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rnnpb.robot import clip_to_limits
from rnnpb.safety._check import SafetyChecker


@dataclass(frozen=True)
class FilterDecision:
    """``command`` (8,) radians to send; ``unsafe``: why the generated command was unsafe
    (empty when safe); ``filtered``: what the filter did (empty when it sent it as it was)."""

    command: np.ndarray
    unsafe: str
    filtered: str


class CommandFilter:
    """Holds or slows unsafe commands. Call it with each generated command, in order.

    Parameters
    ----------
    checker : SafetyChecker, optional
    initial : array, shape (8,), optional
        The robot's pose before the first command (None: the first command is checked at its
        target only).
    """

    def __init__(
        self, checker: SafetyChecker | None = None, initial: np.ndarray | None = None
    ) -> None:
        self.checker = checker or SafetyChecker()
        self.previous = None if initial is None else clip_to_limits(np.asarray(initial, float))
        self.prevented = 0
        self.steps = 0

    def reset(self, initial: np.ndarray | None = None) -> None:
        self.previous = None if initial is None else clip_to_limits(np.asarray(initial, float))

    def __call__(self, command: np.ndarray) -> FilterDecision:
        command = clip_to_limits(np.asarray(command, dtype=np.float64))
        reasons = self.checker.command_reasons(self.previous, command)
        unsafe = " ".join(reasons)
        filtered = ""
        target = command
        if self.previous is not None:
            limit = self.checker.limits.step_limit
            step = np.clip(command - self.previous, -limit, limit)
            if np.any(step != command - self.previous):
                target, filtered = self.previous + step, "slowed"
            if self.checker.path_contact(self.previous, target):
                filtered = "held"
                for fraction in (0.5, 0.25, 0.125):
                    shorter = self.previous + fraction * (target - self.previous)
                    if not self.checker.path_contact(self.previous, shorter):
                        target, filtered = shorter, "shortened"
                        break
                else:
                    target = self.previous
        elif self.checker.path_contact(None, target):
            # No pose before to fall back to: stay where the robot is by sending nothing new
            # would be unknown, so the first command is only recorded as unsafe.
            filtered = ""
        self.steps += 1
        self.prevented += int(bool(filtered))
        self.previous = target
        return FilterDecision(target.copy(), unsafe, filtered)
