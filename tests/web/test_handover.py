"""A new model version takes over the running robot over a few steps: the first command is
almost the old system's, the new one's share grows by equal steps, no joint moves further in a
step than the servo, and then the new system drives alone (rnnpb.web._handover)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from rnnpb.web._handover import HANDOVER_STEPS, MAX_CATCH_UP, Handover


@dataclass(frozen=True)
class _Result:
    motor: np.ndarray
    pb: np.ndarray


class _Still:
    """A mirror system that commands one posture and remembers what it saw."""

    def __init__(self, posture: float, pb: float) -> None:
        self.posture, self.pb_value = posture, pb
        self.seen: list[np.ndarray] = []
        self.recognition = "its own"

    def step(self, observed, prior_pb=None):
        self.seen.append(np.asarray(observed))
        return _Result(np.full(8, self.posture), np.full(4, self.pb_value))


def test_the_command_passes_from_the_old_system_to_the_new_by_equal_shares():
    old, new = _Still(0.0, 0.1), _Still(0.6, 0.9)
    handover = Handover(old, new, previous=np.zeros(8), max_step=1.0)
    commands, pbs = [], []
    for _ in range(HANDOVER_STEPS + 3):
        result = handover.step(np.full(4, 0.5))
        commands.append(result.motor[0])
        pbs.append(result.pb[0])
    shares = np.arange(1, HANDOVER_STEPS + 1) / HANDOVER_STEPS
    np.testing.assert_allclose(commands[:HANDOVER_STEPS], 0.6 * shares)
    assert commands[HANDOVER_STEPS:] == [0.6] * 3 and handover.done
    # Both saw every step of the hand-over; then only the new one steps.
    assert len(old.seen) == HANDOVER_STEPS and len(new.seen) == HANDOVER_STEPS + 3
    # All else is the new system's: its PB, its recognition.
    assert pbs == [0.9] * len(pbs) and handover.recognition == "its own"


def test_no_joint_moves_further_in_a_step_than_the_servo_and_the_new_system_is_reached():
    old, new = _Still(0.0, 0.1), _Still(1.2, 0.9)
    handover = Handover(old, new, previous=np.zeros(8), max_step=0.1)
    commands = [0.0]
    while not handover.done:
        commands.append(float(handover.step(np.full(4, 0.5)).motor[0]))
        assert len(commands) <= HANDOVER_STEPS + MAX_CATCH_UP + 1
    assert max(np.abs(np.diff(commands))) <= 0.1 + 1e-12
    assert commands[-1] == pytest.approx(1.2)
