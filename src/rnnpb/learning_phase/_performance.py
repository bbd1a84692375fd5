"""A person's movement as a source gives it, before the learning phase: timed samples of the
hands, and the resampling to the network's step.

Every source becomes a :class:`Performance`: the times of its samples (seconds of the
recording), the hands in 3-D and, for a source that knows the person's body, those hands on the
standard body (:mod:`._framing`); a source that does not (coloured balls, a sensory file, the
mouse) also gives the sensory values it measured. :func:`resampled` then plays the recording
``time_scale`` times slower and averages it over each step of ``dt`` (a box one step wide, so
that nothing faster than the step folds back into it), for every source alike.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from rnnpb.errors import ConfigError, RnnpbError
from rnnpb.learning_phase._framing import placed_body, projected
from rnnpb.robot.camera import RobotCamera


@dataclass(frozen=True)
class Performance:
    """Timed samples of a person's movement.

    Attributes
    ----------
    times : array, shape (n,)
        Seconds of the recording, increasing.
    hands : array, shape (n, 2, 3)
        The hands in the robot frame, metres (on the standard body at 1 m when ``body``); NaN
        where not known.
    sensory : array, shape (n, 4), or None
        What the camera measured, for a source framed by the camera (``body`` False).
    offsets : array, shape (n, 2, 2), or None
        The pose model's wrists relative to the shoulder centre, in shoulder spans (column,
        row): the values a framing places on the standard body.
    body : bool
        The hands are relative to the person's own body (framing applies).
    depth : str
        Where the hands' depth came from: ``3-d`` (motion capture), ``pose``, ``size`` (the
        balls' size) or ``plane`` (a fixed plane).
    source : str
    capture : dict or None
        What motion capture reports of its takes and bodies.
    """

    times: np.ndarray
    hands: np.ndarray
    sensory: np.ndarray | None
    offsets: np.ndarray | None
    body: bool
    depth: str
    source: str
    capture: dict | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        if len(self.times) < 2:
            raise RnnpbError(
                f"{self.source}: gave {len(self.times)} samples; a demonstration needs at least 2"
            )
        if np.any(np.diff(self.times) <= 0):
            raise ConfigError(f"{self.source}: sample times must increase")

    @property
    def duration(self) -> float:
        return float(self.times[-1] - self.times[0])


@dataclass(frozen=True)
class Steps:
    """A performance at the network's step: per step the hands, the measured sensory values
    (camera-framed sources) and the pose offsets, averaged over the step."""

    hands: np.ndarray
    sensory: np.ndarray | None
    offsets: np.ndarray | None

    def __len__(self) -> int:
        return len(self.hands)


def _box_average(
    times: np.ndarray, values: np.ndarray, centres: np.ndarray, width: float
) -> np.ndarray:
    """Per centre, the mean of the samples within ``width / 2`` of it (at least the nearest
    sample), NaN-aware per value; values (n, ...) → (m, ...)."""
    flat = values.reshape(len(values), -1)
    out = np.full((len(centres), flat.shape[1]), np.nan)
    lo = np.searchsorted(times, centres - width / 2, side="left")
    hi = np.searchsorted(times, centres + width / 2, side="left")
    nearest = np.clip(np.searchsorted(times, centres), 1, len(times) - 1)
    nearest = np.where(
        np.abs(times[nearest - 1] - centres) <= np.abs(times[nearest] - centres),
        nearest - 1,
        nearest,
    )
    for j in range(len(centres)):
        chunk = flat[lo[j] : hi[j]] if hi[j] > lo[j] else flat[nearest[j] : nearest[j] + 1]
        seen = np.isfinite(chunk).all(axis=1)
        # A hand seen on fewer than half of its step's samples is not seen at that step.
        if seen.sum() * 2 >= len(chunk):
            out[j] = chunk[seen].mean(axis=0)
    return out.reshape(len(centres), *values.shape[1:])


def resampled(performance: Performance, dt: float, time_scale: float = 1.0) -> Steps:
    """The performance played ``time_scale`` times slower, one row per step of ``dt``."""
    if not (math.isfinite(dt) and dt > 0):
        raise ConfigError(f"dt must be a positive number of seconds, got {dt}")
    if not (math.isfinite(time_scale) and 0.01 <= time_scale <= 100):
        raise ConfigError(f"--time-scale must be from 0.01 to 100, got {time_scale}")
    recorded = dt / time_scale  # seconds of the recording per step
    start = performance.times[0]
    count = int(math.floor(performance.duration / recorded + 1e-6)) + 1
    centres = start + np.arange(count) * recorded
    times = performance.times

    def each(values: np.ndarray | None) -> np.ndarray | None:
        if values is None:
            return None
        # Each hand on its own: one lost hand does not hide the other.
        halves = [_box_average(times, values[:, i], centres, recorded) for i in range(2)]
        return np.stack(halves, axis=1)

    hands = each(performance.hands)
    assert hands is not None
    sensory = None
    if performance.sensory is not None:
        pairs = each(performance.sensory.reshape(-1, 2, 2))
        assert pairs is not None
        sensory = pairs.reshape(-1, 4)
    return Steps(hands, sensory, each(performance.offsets))


def sensory_at(
    steps: Steps, performance: Performance, distance: float, camera: RobotCamera
) -> np.ndarray:
    """What the robot's camera sees of a body-framed performance (n, 4) with the standard
    body ``distance`` metres away: the pose model's offsets placed on it (as the pose tracker
    does), or the 3-D hands projected; outside [0, 1] where out of view."""
    if steps.offsets is not None:
        from rnnpb.perception import PoseConfig, standard_shoulders_px

        centre, span = standard_shoulders_px(PoseConfig(body=placed_body(distance), camera=camera))
        pixels = centre + steps.offsets * span
        return camera.normalize_pixels(pixels).reshape(-1, 4)
    return projected(steps.hands, distance, camera)


def from_capture(
    files: list[str],
    *,
    hands: tuple[str, str] | None = None,
    units: str | None = None,
    up_axis: str | None = None,
) -> Performance:
    """Motion capture (BVH takes played in order, each cross-fading into the next): the hands
    on the standard body at the capture's own frame rate."""
    from rnnpb.mocap import capture_takes

    capture = capture_takes(files, hands=hands, units=units, up_axis=up_axis)
    return Performance(
        capture.times,
        capture.hands,
        None,
        None,
        True,
        "3-d",
        "bvh:" + ",".join(files),
        capture=capture.to_json(),
    )


def from_source(
    source,
    *,
    steps: int | None = None,
    frame_time: float | None = None,
    step_time: float = 0.4,
    plane_x: float | None = None,
    depth=None,
    live: bool = False,
    clock: Callable[[], float] = time.monotonic,
) -> Performance:
    """Read a connected user source to its end (or ``steps`` samples).

    ``frame_time``: seconds between the source's samples (a video's frame time); else a live
    source (``live``: a webcam) is timed by ``clock`` as it is read, and any other gives one
    sample per ``step_time``. A camera tracked with the pose model gives the hands on the
    standard body; with the coloured balls, the hands from their size and the values they were
    seen at; every other source puts the hands on the plane ``x = plane_x``.
    """
    from rnnpb.perception import (
        MOUSE_PLANE_X,
        PoseResult,
        TrackedUserSource,
        hands_from_balls,
        hands_from_pose,
        hands_on_plane,
    )
    from rnnpb.sources import FrameStepSource

    # A camera sampled every N-th frame drops the others itself, untracked: its reads are the
    # frames kept, each paired with its own tracking result.
    reader = source
    if isinstance(source, FrameStepSource) and isinstance(source.inner, TrackedUserSource):
        reader = source.inner
    tracked = isinstance(reader, TrackedUserSource)
    posed = tracked and reader.perception == "pose"
    sensory, stamps, centers, radii, pose_hands, offsets = [], [], [], [], [], []
    frame_size = None
    index = -1
    while steps is None or len(sensory) < steps:
        observation = reader.read()
        if observation is None:
            break
        index += 1
        stamps.append(
            index * frame_time if frame_time else (clock() if live else index * step_time)
        )
        sensory.append(observation.sensory)
        if tracked:
            result = reader.last_result
            assert result is not None
            if observation.frame is not None:
                frame_size = (observation.frame.shape[1], observation.frame.shape[0])
            if isinstance(result, PoseResult):
                pose_hands.append(result.hands_3d)
                offsets.append(_pose_offsets(result))
            else:
                centers.append([ball.center_px for ball in result.balls])
                radii.append([ball.radius_px for ball in result.balls])
    description = str(getattr(source, "description", "") or type(source).__name__)
    if len(sensory) < 2:
        raise RnnpbError(
            f"{description}: gave {len(sensory)} steps; a demonstration needs at least 2"
        )
    times = np.asarray(stamps, dtype=np.float64)
    times = times - times[0]
    measured = np.array(sensory)
    if posed:
        return Performance(
            times,
            hands_from_pose(np.array(pose_hands)),
            None,
            np.array(offsets),
            True,
            "pose",
            description,
        )
    if tracked:
        hands = hands_from_balls(
            np.array(centers), np.array(radii), RobotCamera(), depth, image_size=frame_size
        )
        return Performance(times, hands, measured, None, False, "size", description)
    hands = hands_on_plane(measured, RobotCamera(), MOUSE_PLANE_X if plane_x is None else plane_x)
    return Performance(times, hands, measured, None, False, "plane", description)


def _pose_offsets(result) -> np.ndarray:
    """(2, 2) each wrist relative to the shoulder centre in shoulder spans; NaN where lost."""
    offsets = np.full((2, 2), np.nan)
    span = result.shoulder_span_px
    if not np.isfinite(span) or span <= 0:
        return offsets
    centre = np.asarray(result.shoulders_px).mean(axis=0)
    for i, ball in enumerate(result.balls):
        if np.isfinite(result.sensory[2 * i : 2 * i + 2]).all():
            offsets[i] = (np.asarray(ball.center_px) - centre) / span
    return offsets
