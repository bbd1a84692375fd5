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

A tracker as slow as the pose model runs in a worker thread (``in_worker``): a paced loop gives
each read a deadline (:meth:`TrackedUserSource.perceive_by`) and gets, when the frame's
perception is not finished by then, the latest observation again, marked
:attr:`PerceivedObservation.reused`, instead of waiting past its step.
"""

from __future__ import annotations

import os
import time
from concurrent.futures import Future, ThreadPoolExecutor, wait
from dataclasses import dataclass, replace
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
from rnnpb.vectors import SENSORY_SIZE

DEFAULT_SYNTHETIC_STEPS = 200


@dataclass
class PerceivedObservation(Observation):
    """An :class:`Observation` of a source that perceives in a worker thread.

    Attributes
    ----------
    reused : bool
        The perception of this read's frame had not finished by the read's deadline (a paced
        step's share, :meth:`TrackedUserSource.perceive_by`), and no earlier frame's had
        finished since: these are the latest observation's values, frame and truth again
        (all NaN, no frame, before the first frame's perception finished).
    """

    reused: bool = False


_Perceived = tuple[np.ndarray, TrackingResult, dict[str, Any]]
"""One frame, what the tracker found in it and the source's ground truth for it."""


class TrackedUserSource(UserSource):
    """A camera source with a tracker: one :class:`Observation` per frame.

    The tracker is the colour-ball tracker (default) or the pose tracker
    (:class:`rnnpb.perception.PoseTracker`, bare hands).
    ``Observation.sensory`` is the tracker's ``lhy lhz rhy rhz`` (NaN for a lost hand),
    ``Observation.frame`` the camera frame, ``Observation.truth`` the source's ground truth
    (the synthetic camera's; empty for real cameras). The last :class:`TrackingResult` (status,
    radius, depth, 3-D position per ball) is kept in ``last_result``; ``lost_frames`` counts the
    frames each ball (left, right) was lost.

    Parameters
    ----------
    frames : FrameSource
    tracker : BallTracker or PoseTracker, optional
    in_worker : bool
        Read and track each frame in a worker thread, so that a paced loop's step waits for
        it only until its deadline (:meth:`perceive_by`). Without a deadline a read waits until
        its frame is perceived, and the observations are those of the direct call.

    Attributes
    ----------
    skip_frames : int
        Frames read and dropped, untracked, after each frame tracked (a video sampled every
        N-th frame: :class:`rnnpb.sources.FrameStepSource` sets it to N - 1), so that the
        tracker's time goes only to the frames used.
    reused_reads : int
        Reads that returned the latest observation again (:attr:`PerceivedObservation.reused`).
    late_frames : int
        Frames whose perception finished after their read's deadline; each is used by a later
        read, unless that read's own frame is perceived in time.
    """

    def __init__(
        self,
        frames: FrameSource,
        tracker: BallTracker | PoseTracker | None = None,
        *,
        in_worker: bool = False,
    ) -> None:
        self.frames = frames
        self.tracker = tracker or BallTracker()
        self.in_worker = in_worker
        self.skip_frames = 0
        self.last_result: TrackingResult | None = None
        self.lost_frames = np.zeros(2, dtype=int)
        self.n_frames = 0
        self.reused_reads = 0
        self.late_frames = 0
        self._worker: ThreadPoolExecutor | None = None
        self._pending: Future[_Perceived | None] | None = None
        self._latest: Observation | None = None
        self._deadline: float | None = None

    @property
    def description(self) -> str:
        return self.frames.description

    def connect(self) -> None:
        self.frames.connect()
        self.tracker.reset()
        if self.in_worker and self._worker is None:
            # One thread: frames are read and tracked in order, one at a time.
            self._worker = ThreadPoolExecutor(1, thread_name_prefix="rnnpb-perceive")

    def perceive_by(self, deadline: float | None) -> None:
        """Until when (a :func:`time.perf_counter` time) the next reads wait for their frame's
        perception; ``None``: for as long as it takes. A paced loop sets it every step; it
        applies to a source reading in a worker (``in_worker``) only."""
        self._deadline = deadline

    def read(self) -> Observation | None:
        if not self.in_worker:
            return self._observe(self._perceive())
        if self._worker is None:
            raise RnnpbError(f"{self.description}: read before connect")
        late: Observation | None = None
        if self._pending is not None and self._pending.done():
            # A frame that missed an earlier read's deadline, perceived since.
            late = self._observe(self._take())
            if late is None:
                return None
        submitted = self._pending is None
        if submitted:
            self._pending = self._worker.submit(self._perceive)
        deadline = self._deadline
        timeout = None if deadline is None else max(0.0, deadline - time.perf_counter())
        if wait((self._pending,), timeout=timeout).done:
            return self._observe(self._take())
        self.late_frames += submitted  # a frame still in perception from a read before counted
        if late is not None:
            return late
        self.reused_reads += 1
        return self._again()

    def _perceive(self) -> _Perceived | None:
        frame = self.frames.read()
        if frame is None:
            return None
        perceived = frame, self.tracker.track(frame), dict(self.frames.last_truth)
        for _ in range(self.skip_frames):
            if self.frames.read() is None:
                break
        return perceived

    def _take(self) -> _Perceived | None:
        job, self._pending = self._pending, None
        assert job is not None
        return job.result()  # a camera's error is raised here, in the reading thread

    def _observe(self, perceived: _Perceived | None) -> Observation | None:
        if perceived is None:
            return None
        frame, result, truth = perceived
        self.last_result = result
        self.n_frames += 1
        self.lost_frames += [not b.tracked for b in result.balls]
        kind = PerceivedObservation if self.in_worker else Observation
        self._latest = kind(result.sensory, frame, truth)
        return self._latest

    def _again(self) -> PerceivedObservation:
        latest = self._latest
        if latest is None:
            return PerceivedObservation(np.full(SENSORY_SIZE, np.nan), reused=True)
        return PerceivedObservation(
            latest.sensory.copy(), latest.frame, dict(latest.truth), reused=True
        )

    @property
    def perception(self) -> str:
        """``"pose"`` for the pose tracker, ``"balls"`` for the colour balls."""
        return "pose" if isinstance(self.tracker, PoseTracker) else "balls"

    def close(self) -> None:
        if self._worker is not None:
            # Waits for a frame in perception: the camera is released only after its read.
            self._worker.shutdown(wait=True, cancel_futures=True)
            self._worker = None
        self._pending = None
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
    in_worker: bool | None = None,
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
    in_worker : bool, optional
        Perceive in a worker thread (:class:`TrackedUserSource`); by default the pose tracker
        does (17 ms a frame and more on a busy machine, a paced step's deadline matters) and
        the colour-ball tracker does not (2 ms a frame: it cannot hold a step up).
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
        return TrackedUserSource(frames, tracker, in_worker=in_worker is not False)
    config = tracker_config or TrackerConfig()
    if colors is not None:
        if not isinstance(colors, BallColors):
            colors = load_ball_colors(colors)
        config = replace(config, colors=colors)
    frames = open_frame_source(kind, argument, steps=steps, seed=seed, **synthetic)
    return TrackedUserSource(frames, BallTracker(config), in_worker=bool(in_worker))
