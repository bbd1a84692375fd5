"""What drives the robot: a source of observations of the user, one per network step.

Every source — the synthetic demonstrator (:class:`rnnpb.demonstrator.ScenarioSource`), a
camera with the colour-ball tracker (:class:`rnnpb.perception.TrackedUserSource`), the pointer
and the steerable demonstrator of the dashboard (:mod:`rnnpb.web`), the in-memory and CSV
streams below — implements :class:`UserSource`: a context manager with ``connect`` / ``read`` /
``close``. ``read`` returns the next :class:`Observation`, or ``None`` when the stream has ended.

This module is the contract, at the bottom of the package beside :mod:`rnnpb.vectors`: each
implementation lives next to what it wraps and imports it from here. The sources here wrap
only :mod:`rnnpb.sequences`. Spec strings (``scenario:held:1``, ``csv:FILE``, ``webcam:0`` …)
are parsed in one place, :func:`rnnpb.interaction.open_source`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.sequences import read_sensory_stream
from rnnpb.vectors import SENSORY_SIZE


@dataclass
class Observation:
    """One step of what the robot perceives of the user.

    Attributes
    ----------
    sensory : array, shape (4,)
        ``lhy lhz rhy rhz`` in [0, 1]; NaN for a hand that was not seen this step.
    frame : array, shape (height, width, 3), optional
        The camera image (BGR, uint8) the values came from, if any.
    truth : dict
        Ground truth when the source knows it (e.g. ``{"pattern": "1", "phase": 0.3}``).
    """

    sensory: np.ndarray
    frame: np.ndarray | None = None
    truth: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.sensory = np.asarray(self.sensory, dtype=np.float64).reshape(SENSORY_SIZE)

    @property
    def seen(self) -> np.ndarray:
        """Per hand (left, right): whether its position was observed this step."""
        # NumPy's stub allows a scalar from any(axis=1); on a (2, 2) array it is (2,).
        return cast(np.ndarray, ~np.isnan(self.sensory.reshape(2, 2)).any(axis=1))


class UserSource:
    """Base class of user sources: a context manager over ``connect``/``read``/``close``."""

    def connect(self) -> None:
        """Acquire the device or file. Raise an :class:`rnnpb.errors.RnnpbError` if missing."""

    def read(self) -> Observation | None:
        """The next observation, or ``None`` when the stream has ended."""
        raise NotImplementedError

    def close(self) -> None:
        """Release the device or file. Safe to call twice."""

    def __enter__(self) -> UserSource:
        self.connect()
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()


class ArraySensorySource(UserSource):
    """A sensory stream held in memory, one row per step.

    Parameters
    ----------
    sensory : array, shape (n_steps, 4)
        ``lhy lhz rhy rhz`` per step; NaN where a hand was not seen.
    truth : list of dict, optional
        Ground truth per step (length n_steps).
    name : str
        What the stream is (for messages).
    """

    def __init__(
        self, sensory: np.ndarray, truth: list[dict[str, Any]] | None = None, name: str = "stream"
    ) -> None:
        sensory = np.asarray(sensory, dtype=np.float64)
        if sensory.ndim != 2 or sensory.shape[1] != SENSORY_SIZE:
            raise ConfigError(
                f"{name}: sensory stream must have shape (n_steps, "
                f"{SENSORY_SIZE}), got {sensory.shape}"
            )
        self.sensory = sensory
        self.truth = truth
        self.name = name
        self.position = 0

    def connect(self) -> None:
        self.position = 0

    def read(self) -> Observation | None:
        if self.position >= len(self.sensory):
            return None
        truth = self.truth[self.position] if self.truth else {}
        observation = Observation(self.sensory[self.position], truth=truth)
        self.position += 1
        return observation


class CsvSensorySource(ArraySensorySource):
    """A sensory stream file (``step lhy lhz rhy rhz``; an empty cell is a hand not seen)."""

    def __init__(self, path: str) -> None:
        super().__init__(read_sensory_stream(path), name=path)


class FrameStepSource(UserSource):
    """Keeps every ``frame_step``-th observation of a camera source (the others are read and
    dropped), so that a video recorded at camera rate drives the network at its own step. A
    source that can drop frames itself, untracked (``skip_frames``: a camera with a tracker),
    is told to: the tracker then sees only the frames kept."""

    def __init__(self, inner: UserSource, frame_step: int) -> None:
        if frame_step < 1:
            raise ConfigError(f"frame step must be >= 1, got {frame_step}")
        self.inner = inner
        self.frame_step = frame_step
        self._skips = hasattr(inner, "skip_frames")
        if self._skips:
            cast(Any, inner).skip_frames = frame_step - 1

    def connect(self) -> None:
        self.inner.connect()

    def read(self) -> Observation | None:
        observation = self.inner.read()
        if not self._skips:
            for _ in range(self.frame_step - 1):
                if self.inner.read() is None:
                    break
        return observation

    def close(self) -> None:
        self.inner.close()
