"""User sources the dashboard controls: the browser's pointer, a steerable demonstrator, and
the switch between them and the webcam.

All are :class:`~rnnpb.sources.UserSource` subclasses, so the interaction loop reads them
exactly as it reads a scripted scenario or a camera.
"""

from __future__ import annotations

import math
import threading

import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.sources import Observation, UserSource
from rnnpb.vectors import SENSORY_SIZE

PAUSE = "pause"


class PointerSource(UserSource):
    """The hands are where the person last put the two markers in the browser.

    :meth:`set_hands` is called from the server's event loop whenever a position arrives;
    :meth:`read` (the loop thread) returns the latest one. A marker that was never placed
    reads as not seen (NaN); a marker that stays put is a hand held still.
    """

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._hands = np.full(SENSORY_SIZE, math.nan)
        self.updates = 0

    def set_hands(self, hands: np.ndarray) -> None:
        """``hands`` (4,): ``lhy lhz rhy rhz`` in [0, 1], NaN for a hand not on the panel."""
        hands = np.asarray(hands, dtype=np.float64).reshape(SENSORY_SIZE)
        with self._lock:
            self._hands = hands.copy()
            self.updates += 1

    def read(self) -> Observation:
        with self._lock:
            hands = self._hands.copy()
        return Observation(hands, truth={"pattern": "pointer"})


class DemonstratorSource(UserSource):
    """The synthetic demonstrator, steered while it runs: perform pattern 1-4, one of the new
    shapes (:data:`rnnpb.demonstrator.NEW_SHAPES`: a movement to teach) or pause.

    Each pattern is pre-performed as one long stream (with the demonstrator's human
    imperfection) starting at the same phase; switching pattern continues the new stream at
    the current phase (nearest step with that phase), and a pause holds the hands where they
    are. The streams loop, so the demonstrator never ends.

    Parameters
    ----------
    patterns : tuple of str, optional
        The movements it can perform (default :data:`rnnpb.demonstrator.SHAPES`: the paper's
        four patterns and the new shapes).
    n_steps : int
        Length of each pre-performed stream before it loops.
    seed : int
    """

    def __init__(
        self, patterns: tuple[str, ...] | None = None, n_steps: int = 600, seed: int = 0
    ) -> None:
        from rnnpb.demonstrator import SHAPES, PatternConfig, perform
        from rnnpb.robot.camera import RobotCamera

        config = PatternConfig()
        camera = RobotCamera()
        self.patterns = tuple(SHAPES if patterns is None else patterns)
        self._sensory: dict[str, np.ndarray] = {}
        self._phase: dict[str, np.ndarray] = {}
        for index, pattern in enumerate(self.patterns):
            rng = np.random.default_rng([seed, index])
            motion = perform([(pattern, n_steps)], config, rng, phase=0.0)
            self._sensory[pattern] = camera.sensory_from_hands(motion.measured)
            self._phase[pattern] = np.mod(motion.phase, 2 * np.pi)
        self._lock = threading.Lock()
        self._pattern = self.patterns[0]
        self._paused = False
        self._position = 0
        self._last = self._sensory[self._pattern][0].copy()

    @property
    def pattern(self) -> str:
        return self._pattern

    @property
    def paused(self) -> bool:
        return self._paused

    def perform(self, pattern: str) -> None:
        """Switch to ``pattern`` (keeping the phase) or to ``"pause"``."""
        with self._lock:
            if pattern == PAUSE:
                self._paused = True
                return
            if pattern not in self._sensory:
                raise ConfigError(
                    f"the demonstrator has no pattern {pattern!r} "
                    f"(known: {', '.join(self.patterns)})"
                )
            if pattern != self._pattern:
                phase = self._phase[self._pattern][self._position % len(self._phase[self._pattern])]
                gap = np.abs(np.angle(np.exp(1j * (self._phase[pattern] - phase))))
                # The nearest phase after the current position keeps the stream's slow
                # drift of period and size going forward, not back to its start.
                order = np.argsort(gap + 1e-9 * np.arange(len(gap)))
                self._position = int(order[0])
                self._pattern = pattern
            self._paused = False

    def read(self) -> Observation:
        with self._lock:
            if self._paused:
                return Observation(self._last.copy(), truth={"pattern": PAUSE, "pause": True})
            stream = self._sensory[self._pattern]
            hands = stream[self._position % len(stream)].copy()
            self._position += 1
            self._last = hands
            return Observation(hands.copy(), truth={"pattern": self._pattern, "pause": False})


class SwitchableSource(UserSource):
    """Reads whichever source drives the robot now (``inner``: the pointer, the demonstrator
    or the webcam), so that a change of driver keeps the loop — its step count, recording and
    regression window — going. Whoever switches ``inner`` opens and closes the sources."""

    def __init__(self, inner: UserSource) -> None:
        self.inner = inner

    def read(self) -> Observation | None:
        return self.inner.read()
