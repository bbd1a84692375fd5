"""Motion capture in: BVH files read strictly, the hands found on any skeleton and put on the
standard user's body, several takes joined and resampled to a model's step
(docs/motion-capture.md)."""

from rnnpb.mocap._body import UNITS, UP_AXES, BodyScale, body_hands, find_hands
from rnnpb.mocap._bvh import Bvh, Joint, read_bvh
from rnnpb.mocap._stream import (
    CROSSFADE_S,
    MIN_STEPS_PER_PERIOD,
    Capture,
    CaptureStream,
    Take,
    capture_stream,
    capture_takes,
    check_sampling,
    movement_period,
)

__all__ = [
    "CROSSFADE_S",
    "MIN_STEPS_PER_PERIOD",
    "UNITS",
    "UP_AXES",
    "BodyScale",
    "Bvh",
    "Capture",
    "CaptureStream",
    "Joint",
    "Take",
    "body_hands",
    "capture_stream",
    "capture_takes",
    "check_sampling",
    "find_hands",
    "movement_period",
    "read_bvh",
]
