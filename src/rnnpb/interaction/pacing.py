"""The pacing of a real-time run: one step every ``dt`` seconds, as a robot would.

Every paced run — the interaction loop (:class:`rnnpb.interaction.InteractionLoop`) and two
coupled agents (:class:`rnnpb.interaction.dyad.Dyad`) — is paced by a :class:`Pacer`. Each step
starts at its deadline. A step that took longer than ``dt`` counts as a missed deadline, and
the next one starts at once: missed steps are not made up, so a late step is never followed by
a burst of steps to catch up. Unpaced, steps follow each other as fast as they run and the
pacer only counts.

While it waits for a step, the pacer calls the run's controller, ``between_steps(wait_s)``;
there the controller applies its commands (a new ``dt``, a stop). ``dt`` is passed with each
call, so a new one applies from the next step on and the current wait keeps its deadline.
"""

from __future__ import annotations

import time
from collections.abc import Callable


class Pacer:
    """The deadlines of a run's steps and the count of those missed.

    Parameters
    ----------
    clock : callable() -> float
        Seconds, monotonic (:func:`time.perf_counter`).
    sleep : callable(float)
        Waits that many seconds (:func:`time.sleep`).
    """

    def __init__(
        self,
        clock: Callable[[], float] = time.perf_counter,
        sleep: Callable[[float], None] = time.sleep,
    ) -> None:
        self.clock = clock
        self.sleep = sleep
        self.missed_deadlines = 0
        self._deadline = clock()

    def start(self) -> None:
        """A run begins: its first step is due now."""
        self._deadline = self.clock()

    def wait(
        self,
        paced: bool,
        between_steps: Callable[[float], None] | None = None,
        stopped: Callable[[], bool] | None = None,
    ) -> None:
        """Return when the next step is due (paced) or at once (not paced), or when
        ``stopped()`` says the run should stop.

        ``between_steps(wait_s)`` is called with the seconds left until the step is due (0
        when not paced or late), again until it is due: it may block for up to ``wait_s``.
        Without it a paced wait sleeps.
        """
        while True:
            wait_s = max(0.0, self._deadline - self.clock()) if paced else 0.0
            if between_steps is not None:
                between_steps(wait_s)
            elif wait_s > 0:
                self.sleep(wait_s)
            if (stopped is not None and stopped()) or wait_s == 0.0:
                return
            if self.clock() >= self._deadline:
                return

    def took(self, seconds: float, dt: float) -> bool:
        """A step took ``seconds``: longer than ``dt`` is a missed deadline (counted in
        :attr:`missed_deadlines`). Returns whether it missed."""
        missed = seconds > dt
        self.missed_deadlines += int(missed)
        return missed

    def stepped(self, dt: float) -> None:
        """A step has run: the next is due ``dt`` after this one's deadline, or now if that
        has passed (missed steps are not made up)."""
        self._deadline = max(self._deadline + dt, self.clock())
