"""The one pacing of every real-time run (the interaction loop, two coupled agents): each step
at its deadline; a slow step counts a missed deadline and the next starts at once; missed steps
are not made up. On a clock of its own, so that the times are exact."""

from __future__ import annotations

import time

import numpy as np
import pytest

from rnnpb.demonstrator import UserBody
from rnnpb.interaction.dyad import AgentStep, Dyad
from rnnpb.interaction.pacing import Pacer


class Clock:
    """Seconds that pass only when slept or spent."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        self.now += seconds


def paced_run(durations, dt=1.0, paced=True, between_steps=None):
    """Steps that take ``durations`` seconds; when each started, and the pacer."""
    clock = Clock()
    pacer = Pacer(clock, clock.sleep)
    pacer.start()
    starts = []
    for seconds in durations:
        pacer.wait(paced, between_steps(clock) if between_steps else None)
        starts.append(clock.now)
        clock.now += seconds
        pacer.took(seconds, dt)
        pacer.stepped(dt)
    return starts, pacer


def test_a_slow_step_misses_its_deadline_and_the_next_starts_at_once():
    starts, pacer = paced_run([0.2, 2.5, 0.2, 0.2])
    # Step 1 ends at 3.5, past the deadlines at 2 and 3: step 2 starts then, and step 3 one
    # dt later; the steps due at 2 and 3 are not made up with a burst of steps.
    assert starts == pytest.approx([0.0, 1.0, 3.5, 4.5])
    assert pacer.missed_deadlines == 1


def test_a_step_of_exactly_dt_keeps_its_deadline():
    starts, pacer = paced_run([1.0, 1.0, 1.0])
    assert starts == pytest.approx([0.0, 1.0, 2.0])
    assert pacer.missed_deadlines == 0


def test_unpaced_steps_follow_at_once_and_are_still_counted():
    starts, pacer = paced_run([0.2, 2.5, 0.2], paced=False)
    assert starts == pytest.approx([0.0, 0.2, 2.7])
    assert pacer.missed_deadlines == 1


def test_the_controller_is_called_until_the_step_is_due():
    calls = []

    def controller(clock):
        def between_steps(wait_s):
            calls.append(wait_s)
            clock.sleep(min(wait_s, 0.25))  # returns early, as a controller with a timeout does

        return between_steps

    starts, _ = paced_run([0.25, 0.25], between_steps=controller)
    assert starts == [0.0, 1.0]
    # Due at once (0), then waiting from 0.25 to 1.0 in slices of 0.25.
    assert calls == [0.0, 0.75, 0.5, 0.25]


def test_a_stop_ends_the_wait():
    clock = Clock()
    pacer = Pacer(clock, clock.sleep)
    pacer.start()
    pacer.stepped(1.0)
    pacer.wait(True, lambda wait_s: clock.sleep(0.1), stopped=lambda: clock.now >= 0.3)
    assert clock.now == pytest.approx(0.3)


class Still:
    """An agent that holds its hands still; ``slow`` steps take ``seconds``."""

    def __init__(self, name: str, slow: set[int] | None = None, seconds: float = 0.0) -> None:
        self.name = name
        self.hands = UserBody().hand_centres.copy()
        self.slow, self.seconds, self.steps = slow or set(), seconds, 0

    def act(self, view: np.ndarray) -> AgentStep:
        if self.steps in self.slow:
            time.sleep(self.seconds)
        self.steps += 1
        return AgentStep(hands=self.hands, view=view)


def test_a_paced_dyad_counts_its_slow_step_as_the_loop_does():
    dyad = Dyad(Still("a", slow={2}, seconds=0.2), Still("b"))
    run = dyad.run(5, dt=0.05, paced=True)
    assert len(run) == 5
    assert run["seconds"][2] > 0.05
    assert dyad.missed_deadlines >= 1
