"""What drives the robot: a source of observations of the user, one per network step.

Every source — the synthetic demonstrator, a sensory CSV, a camera with the colour-ball
tracker, the mouse in the dashboard — implements :class:`UserSource`: a context manager with
``connect`` / ``read`` / ``close``. ``read`` returns the next :class:`Observation`, or ``None``
when the stream has ended.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

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
        return ~np.isnan(self.sensory.reshape(2, 2)).any(axis=1)


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
