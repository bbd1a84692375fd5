"""Motion capture played to a model: ``rnnpb interact --source bvh:FILE[,FILE…]``.

The takes are read as the learning phase reads them (:func:`._performance.from_capture`: the
hands on the standard body, the takes joined), played ``time_scale`` times slower, averaged over
each step of the model's ``dt`` and framed at the model's framing: what the robot's camera would
see of that person standing there. A hand outside the view is not seen (NaN), as with a camera.
"""

from __future__ import annotations

import numpy as np

from rnnpb.learning_phase._framing import hands_at, placed_body, projected
from rnnpb.learning_phase._performance import from_capture, resampled
from rnnpb.sources import Observation, UserSource


class CaptureSource(UserSource):
    """A user source playing BVH takes (module doc).

    Parameters
    ----------
    files : list of str
    dt : float
        Seconds per step (the model's).
    framing : float
        Metres from the robot at which the person's body stands (the model's framing).
    time_scale : float
        Play the capture this many times slower.

    ``last_hands`` is the 3-D hands (2, 3) of the step just read (robot frame, the body at the
    framing), for teaching.
    """

    def __init__(
        self, files: list[str], dt: float, framing: float, time_scale: float = 1.0, **capture
    ) -> None:
        placed_body(framing)  # checks the range
        steps = resampled(from_capture(files, **capture), dt, time_scale)
        self.hands = hands_at(steps.hands, framing)
        sensory = projected(steps.hands, framing)
        with np.errstate(invalid="ignore"):
            sensory[((sensory < 0) | (sensory > 1)).reshape(-1, 2, 2).any(axis=2).repeat(2, 1)] = (
                np.nan
            )
        self.sensory = sensory
        self.description = "bvh:" + ",".join(files)
        self.position = 0
        self.last_hands: np.ndarray | None = None

    def connect(self) -> None:
        self.position = 0

    def read(self) -> Observation | None:
        if self.position >= len(self.sensory):
            return None
        t = self.position
        self.position += 1
        self.last_hands = self.hands[t].copy()
        return Observation(self.sensory[t])
