"""A camera and the tracker as a :class:`rnnpb.sources.UserSource`, opened from the parts of a
source spec.

The spec strings themselves (``webcam:0``, ``video:clip.mp4`` …) are parsed in one place,
:func:`rnnpb.interaction.parse_source_spec`; the functions here take what it gives, a kind
and its argument:

    "webcam", INDEX        a camera device, e.g. ("webcam", 0)
    "video", PATH          a video file
    "images", DIR          a folder of images, in natural order of their names
    "synthetic", PATTERN   the synthetic camera rendering the synthetic user performing
                           PATTERN (1…4 or an alias such as rotation-in-phase)
"""

from __future__ import annotations

import os
from dataclasses import replace
from typing import Any

import numpy as np

from rnnpb.errors import ConfigError, RnnpbError
from rnnpb.perception._colors import BallColors, load_ball_colors
from rnnpb.perception._pose import PERCEPTIONS, PoseConfig, PoseTracker
from rnnpb.perception._sources import (
    FrameSource,
    ImageFolderSource,
    LimitedSource,
    VideoFileSource,
    WebcamSource,
)
from rnnpb.perception._synthetic import SceneConfig, SyntheticCamera
from rnnpb.perception._tracker import BallTracker, TrackerConfig, TrackingResult
from rnnpb.robot.camera import RobotCamera
from rnnpb.sources import Observation, UserSource

DEFAULT_SYNTHETIC_STEPS = 200


class TrackedUserSource(UserSource):
    """A camera source with a tracker: one :class:`Observation` per frame.

    The tracker is the colour-ball tracker (default) or the pose tracker
    (:class:`rnnpb.perception.PoseTracker`, bare hands).
    ``Observation.sensory`` is the tracker's ``lhy lhz rhy rhz`` (NaN for a lost hand),
    ``Observation.frame`` the camera frame, ``Observation.truth`` the source's ground truth
    (the synthetic camera's; empty for real cameras). The last :class:`TrackingResult` (status,
    radius, depth, 3-D position per ball) is kept in ``last_result``; ``lost_frames`` counts the
    frames each ball (left, right) was lost.
    """

    def __init__(
        self, frames: FrameSource, tracker: BallTracker | PoseTracker | None = None
    ) -> None:
        self.frames = frames
        self.tracker = tracker or BallTracker()
        self.last_result: TrackingResult | None = None
        self.lost_frames = np.zeros(2, dtype=int)
        self.n_frames = 0

    @property
    def description(self) -> str:
        return self.frames.description

    def connect(self) -> None:
        self.frames.connect()
        self.tracker.reset()

    def read(self) -> Observation | None:
        frame = self.frames.read()
        if frame is None:
            return None
        result = self.tracker.track(frame)
        self.last_result = result
        self.n_frames += 1
        self.lost_frames += [not b.tracked for b in result.balls]
        return Observation(result.sensory, frame, dict(self.frames.last_truth))

    @property
    def perception(self) -> str:
        """``"pose"`` for the pose tracker, ``"balls"`` for the colour balls."""
        return "pose" if isinstance(self.tracker, PoseTracker) else "balls"

    def close(self) -> None:
        self.frames.close()


def synthetic_user_hands(pattern: str, steps: int, seed: int = 0) -> np.ndarray:
    """The synthetic user's hands performing ``pattern`` for ``steps`` steps, (steps, 2, 3)."""
    try:
        from rnnpb.demonstrator import PatternConfig, perform
    except ImportError as error:
        raise RnnpbError(
            f"synthetic camera: the synthetic user (rnnpb.demonstrator) is not available: {error}"
        ) from None
    motion = perform([(pattern, steps)], PatternConfig(), np.random.default_rng(seed))
    return motion.hands


def open_frame_source(
    kind: str,
    argument: str | int | os.PathLike[str],
    *,
    steps: int | None = None,
    seed: int = 0,
    scene: SceneConfig | None = None,
    camera: RobotCamera | None = None,
    hands: np.ndarray | None = None,
) -> FrameSource:
    """The camera source of ``kind`` (not yet connected).

    Parameters
    ----------
    kind : str
        ``webcam``, ``video``, ``images`` or ``synthetic``.
    argument : int, str or path
        The device index (an int) for ``webcam``, the path for ``video`` and ``images``, the
        pattern for ``synthetic`` — as :func:`rnnpb.interaction.parse_source_spec` gives them.
    steps : int, optional
        At most this many frames (the synthetic camera renders this many; default 200).
    seed : int
        Seed of the synthetic user and scene (the scene's own seed when ``scene`` is given).
    scene, camera : optional
        The synthetic camera's scene and camera model.
    hands : array, shape (n_steps, 2, 3), optional
        For ``synthetic``, render these hand positions instead of the synthetic user's
        (the pattern is then only a label).
    """
    if steps is not None and steps < 1:
        raise ConfigError(f"steps must be >= 1, got {steps}")
    source: FrameSource
    if kind == "webcam":
        if isinstance(argument, bool) or not isinstance(argument, int):
            raise ConfigError(f"webcam: the device index must be an integer, got {argument!r}")
        source = WebcamSource(argument)
    elif kind == "video":
        source = VideoFileSource(argument)
    elif kind == "images":
        source = ImageFolderSource(argument)
    elif kind == "synthetic":
        pattern = str(argument)
        if hands is None:
            hands = synthetic_user_hands(pattern, steps or DEFAULT_SYNTHETIC_STEPS, seed)
        scene = scene or SceneConfig(seed=seed)
        return SyntheticCamera(
            hands[:steps] if steps else hands, camera, scene, truth={"pattern": pattern}
        )
    else:
        raise ConfigError(f"no camera source of kind {kind!r} (webcam, video, images, synthetic)")
    return LimitedSource(source, steps) if steps else source


def open_camera_source(
    kind: str,
    argument: str | int | os.PathLike[str],
    *,
    colors: BallColors | str | os.PathLike[str] | None = None,
    tracker_config: TrackerConfig | None = None,
    steps: int | None = None,
    seed: int = 0,
    perception: str = "balls",
    pose_config: PoseConfig | None = None,
    **synthetic: Any,
) -> TrackedUserSource:
    """A :class:`UserSource` that tracks the hands in the frames of a camera source.

    Parameters
    ----------
    kind, argument
        The camera source (see :func:`open_frame_source`).
    colors : BallColors or path of a colour file, optional
        Overrides the colours in ``tracker_config``.
    tracker_config : TrackerConfig, optional
    perception : str
        ``"balls"`` (the colour-ball tracker) or ``"pose"`` (bare hands through the pose
        model of the ``rnnpb[hands]`` extra; ``colors`` and ``tracker_config`` do not apply).
    pose_config : PoseConfig, optional
        The pose tracker's settings.
    steps, seed, **synthetic
        See :func:`open_frame_source`.

    Examples
    --------
    >>> with open_camera_source("synthetic", "1", steps=50) as source:   # doctest: +SKIP
    ...     while (observation := source.read()) is not None:
    ...         print(observation.sensory)
    """
    if perception not in PERCEPTIONS:
        raise ConfigError(f"perception must be one of {', '.join(PERCEPTIONS)}, got {perception!r}")
    if perception == "pose":
        tracker = PoseTracker(pose_config)  # raises before a camera is opened
        frames = open_frame_source(kind, argument, steps=steps, seed=seed, **synthetic)
        return TrackedUserSource(frames, tracker)
    config = tracker_config or TrackerConfig()
    if colors is not None:
        if not isinstance(colors, BallColors):
            colors = load_ball_colors(colors)
        config = replace(config, colors=colors)
    frames = open_frame_source(kind, argument, steps=steps, seed=seed, **synthetic)
    return TrackedUserSource(frames, BallTracker(config))
