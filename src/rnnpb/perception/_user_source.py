"""A camera and the tracker as a :class:`rnnpb.interaction.source.UserSource`, and the source
spec strings the command line and the interaction loop take.

Spec strings::

    webcam:INDEX      a camera device, e.g. webcam:0
    video:PATH        a video file
    images:DIR        a folder of images, in natural order of their names
    synthetic:PATTERN the synthetic camera rendering the synthetic user performing PATTERN
                      (1…4 or an alias such as rotation-in-phase)
"""

from __future__ import annotations

import os
from dataclasses import replace
from typing import Any

import numpy as np

from rnnpb.errors import ConfigError, RnnpbError
from rnnpb.interaction.source import Observation, UserSource
from rnnpb.perception._colors import BallColors, load_ball_colors
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

SOURCE_KINDS = ("webcam", "video", "images", "synthetic")
DEFAULT_SYNTHETIC_STEPS = 200


class TrackedUserSource(UserSource):
    """A camera source with the colour-ball tracker: one :class:`Observation` per frame.

    ``Observation.sensory`` is the tracker's ``lhy lhz rhy rhz`` (NaN for a lost ball),
    ``Observation.frame`` the camera frame, ``Observation.truth`` the source's ground truth
    (the synthetic camera's; empty for real cameras). The last :class:`TrackingResult` (status,
    radius, depth, 3-D position per ball) is kept in ``last_result``; ``lost_frames`` counts the
    frames each ball (left, right) was lost.
    """

    def __init__(self, frames: FrameSource, tracker: BallTracker | None = None) -> None:
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

    def close(self) -> None:
        self.frames.close()


def parse_source_spec(spec: str) -> tuple[str, str]:
    """``"video:clip.mp4"`` → ``("video", "clip.mp4")``; raises :class:`ConfigError`."""
    kind, sep, arg = str(spec).partition(":")
    kind = kind.strip().lower()
    if not sep or kind not in SOURCE_KINDS or not arg:
        raise ConfigError(f"camera source {spec!r}: expected one of webcam:INDEX, video:PATH, "
                          "images:DIR, synthetic:PATTERN")
    return kind, arg


def synthetic_user_hands(pattern: str, steps: int, seed: int = 0) -> np.ndarray:
    """The synthetic user's hands performing ``pattern`` for ``steps`` steps, (steps, 2, 3)."""
    try:
        from rnnpb.demonstrator import PatternConfig, perform
    except ImportError as error:
        raise RnnpbError("synthetic camera: the synthetic user (rnnpb.demonstrator) is not "
                         f"available: {error}") from None
    motion = perform([(pattern, steps)], PatternConfig(), np.random.default_rng(seed))
    return motion.hands


def open_frame_source(spec: str, *, steps: int | None = None, seed: int = 0,
                      scene: SceneConfig | None = None, camera: RobotCamera | None = None,
                      hands: np.ndarray | None = None) -> FrameSource:
    """The camera source a spec string names (not yet connected).

    Parameters
    ----------
    spec : str
        ``webcam:INDEX``, ``video:PATH``, ``images:DIR`` or ``synthetic:PATTERN``.
    steps : int, optional
        At most this many frames (the synthetic camera renders this many; default 200).
    seed : int
        Seed of the synthetic user and scene (the scene's own seed when ``scene`` is given).
    scene, camera : optional
        The synthetic camera's scene and camera model.
    hands : array, shape (n_steps, 2, 3), optional
        For ``synthetic:``, render these hand positions instead of the synthetic user's
        (the pattern in the spec is then only a label).
    """
    kind, arg = parse_source_spec(spec)
    if steps is not None and steps < 1:
        raise ConfigError(f"steps must be >= 1, got {steps}")
    source: FrameSource
    if kind == "webcam":
        try:
            index = int(arg)
        except ValueError:
            raise ConfigError(f"camera source {spec!r}: webcam index must be an integer") from None
        source = WebcamSource(index)
    elif kind == "video":
        source = VideoFileSource(arg)
    elif kind == "images":
        source = ImageFolderSource(arg)
    else:
        if hands is None:
            hands = synthetic_user_hands(arg, steps or DEFAULT_SYNTHETIC_STEPS, seed)
        scene = scene or SceneConfig(seed=seed)
        return SyntheticCamera(hands[:steps] if steps else hands, camera, scene,
                               truth={"pattern": arg})
    return LimitedSource(source, steps) if steps else source


def open_camera_source(spec: str, *, colors: BallColors | str | os.PathLike[str] | None = None,
                       tracker_config: TrackerConfig | None = None, steps: int | None = None,
                       seed: int = 0, **synthetic: Any) -> TrackedUserSource:
    """A :class:`UserSource` that tracks the balls in the frames of the source ``spec`` names.

    Parameters
    ----------
    spec : str
        ``webcam:INDEX``, ``video:PATH``, ``images:DIR`` or ``synthetic:PATTERN``.
    colors : BallColors or path of a colour file, optional
        Overrides the colours in ``tracker_config``.
    tracker_config : TrackerConfig, optional
    steps, seed, **synthetic
        See :func:`open_frame_source`.

    Examples
    --------
    >>> with open_camera_source("synthetic:1", steps=50) as source:   # doctest: +SKIP
    ...     while (observation := source.read()) is not None:
    ...         print(observation.sensory)
    """
    config = tracker_config or TrackerConfig()
    if colors is not None:
        if not isinstance(colors, BallColors):
            colors = load_ball_colors(colors)
        config = replace(config, colors=colors)
    frames = open_frame_source(spec, steps=steps, seed=seed, **synthetic)
    return TrackedUserSource(frames, BallTracker(config))
