"""The colour-ball tracker (paper section 2.1): the user wears a coloured ball on each hand; the
robot finds each ball in its camera image by colour, and the ball's centre gives the sensory
values ``(Y, Z)`` of that hand, its apparent size an estimate of its depth.

Per frame and per ball:

1. threshold the frame in HSV with the ball's colour range (two ranges for red, whose hue
   wraps through 0) — ``cv2.inRange``;
2. clean the mask with a morphological opening (drops isolated noisy pixels and thin
   structures) — ``cv2.morphologyEx``;
3. find the blobs — ``cv2.findContours`` — and keep those at least ``min_radius_px`` in
   equivalent radius and round enough (``min_circularity``);
4. pick the blob with the best score: large, round, and near where the ball was last seen
   (a Gaussian gate of width ``search_radius_px`` around the previous centre, extrapolated by
   the last velocity);
5. centre = the centroid of the chosen blob's pixels (``cv2.moments``, sub-pixel),
   radius = ``sqrt(area / pi)``, depth = ``focal_px * ball_radius_m / radius``.

Pixel convention: pixel ``(i, j)`` covers columns ``[i, i + 1)`` and rows ``[j, j + 1)``, so a
centroid of pixel indices is shifted by +0.5 to continuous image coordinates, the coordinates
:class:`rnnpb.robot.camera.RobotCamera` projects to. ``Y = column / width``,
``Z = 1 - row / height`` with the frame's own size.

A ball that is not found gives NaN for its hand and status ``"lost"``; the tracker keeps its
last position for a while to prefer blobs near it when the ball reappears.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.perception._colors import BallColor, BallColors
from rnnpb.robot.camera import RobotCamera

TRACKED = "tracked"
LOST = "lost"
HAND_NAMES = ("left", "right")
_DISK_FILL = math.pi / 4.0  # area of a disk over the area of its bounding square


@dataclass(frozen=True)
class TrackerConfig:
    """Parameters of the colour-ball tracker.

    Attributes
    ----------
    colors : BallColors
        HSV ranges of the left-hand and right-hand balls (default red and blue).
    ball_radius_m : float
        Physical radius of the balls, metres (for the depth estimate).
    min_radius_px : float
        Blobs with a smaller equivalent radius ``sqrt(area / pi)`` are ignored.
    min_circularity : float
        In [0, 1]; blobs less round than this are ignored (1 = a perfect disk; measured from
        the bounding box's aspect ratio and how much of it the blob fills).
    opening_px : int
        Size of the square structuring element of the morphological opening; 0 or 1 disables.
    search_radius_px : float
        Width of the proximity preference around the ball's previous position.
    lost_memory_frames : int
        How many frames a lost ball's last position keeps steering the choice of blob.
    smoothing : float
        In [0, 1): exponential smoothing of the centre, ``c = (1 - s) * measured + s * c_prev``;
        0 (default) disables it. Reset whenever a ball is lost.
    camera : RobotCamera
        The camera model (focal length for depth and 3-D positions); frames of another size
        are treated as the same camera scaled.
    """

    colors: BallColors = field(default_factory=BallColors)
    ball_radius_m: float = 0.04
    min_radius_px: float = 3.0
    min_circularity: float = 0.35
    opening_px: int = 3
    search_radius_px: float = 120.0
    lost_memory_frames: int = 15
    smoothing: float = 0.0
    camera: RobotCamera = field(default_factory=RobotCamera)

    def __post_init__(self) -> None:
        if not isinstance(self.colors, BallColors):
            raise ConfigError("tracker colors must be a BallColors")
        if not self.ball_radius_m > 0:
            raise ConfigError(f"tracker ball_radius_m must be > 0, got {self.ball_radius_m}")
        if not self.min_radius_px >= 0:
            raise ConfigError(f"tracker min_radius_px must be >= 0, got {self.min_radius_px}")
        if not 0.0 <= self.min_circularity <= 1.0:
            raise ConfigError(f"tracker min_circularity must be in [0, 1], got "
                              f"{self.min_circularity}")
        if not (isinstance(self.opening_px, int) and 0 <= self.opening_px <= 31):
            raise ConfigError(f"tracker opening_px must be an integer in [0, 31], got "
                              f"{self.opening_px}")
        if not self.search_radius_px > 0:
            raise ConfigError(f"tracker search_radius_px must be > 0, got "
                              f"{self.search_radius_px}")
        if self.lost_memory_frames < 0:
            raise ConfigError(f"tracker lost_memory_frames must be >= 0, got "
                              f"{self.lost_memory_frames}")
        if not 0.0 <= self.smoothing < 1.0:
            raise ConfigError(f"tracker smoothing must be in [0, 1), got {self.smoothing}")


@dataclass(frozen=True)
class BallMeasurement:
    """What the tracker found of one ball in one frame.

    Attributes
    ----------
    status : str
        ``"tracked"`` or ``"lost"``.
    center_px : array, shape (2,)
        (column, row) in continuous image coordinates; NaN when lost.
    radius_px : float
        Equivalent radius ``sqrt(area / pi)`` of the blob; NaN when lost.
    depth_m : float
        Depth along the optical axis from the apparent size; NaN when lost.
    position : array, shape (3,)
        The ball's centre in the robot frame (back-projected at ``depth_m``); NaN when lost.
    """

    status: str
    center_px: np.ndarray
    radius_px: float = math.nan
    depth_m: float = math.nan
    position: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))

    @property
    def tracked(self) -> bool:
        return self.status == TRACKED


@dataclass(frozen=True)
class TrackingResult:
    """The tracker's output for one frame.

    Attributes
    ----------
    balls : (BallMeasurement, BallMeasurement)
        The user's left-hand and right-hand balls.
    sensory : array, shape (4,)
        ``lhy lhz rhy rhz`` in [0, 1]; NaN for a lost ball.
    """

    balls: tuple[BallMeasurement, BallMeasurement]
    sensory: np.ndarray

    @property
    def status(self) -> tuple[str, str]:
        return self.balls[0].status, self.balls[1].status

    @property
    def hands_3d(self) -> np.ndarray:
        """Both balls' robot-frame positions, shape (2, 3), NaN rows for lost balls."""
        return np.stack([b.position for b in self.balls])


_LOST = BallMeasurement(LOST, np.full(2, np.nan))


class _BallState:
    """What the tracker remembers of one ball between frames."""

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        self.center: np.ndarray | None = None
        self.velocity = np.zeros(2)
        self.frames_lost = 0
        self.smoothed: np.ndarray | None = None

    def predicted(self, memory: int) -> np.ndarray | None:
        if self.center is None or self.frames_lost > memory:
            return None
        if self.frames_lost:
            return self.center
        return self.center + self.velocity


class BallTracker:
    """Finds the two coloured balls in BGR frames, one frame after another.

    Parameters
    ----------
    config : TrackerConfig, optional

    Examples
    --------
    >>> tracker = BallTracker()
    >>> result = tracker.track(frame)          # doctest: +SKIP
    >>> result.sensory                          # lhy lhz rhy rhz, NaN where lost
    """

    def __init__(self, config: TrackerConfig | None = None) -> None:
        self.config = config or TrackerConfig()
        k = self.config.opening_px
        self._kernel = (cv2.getStructuringElement(cv2.MORPH_RECT, (k, k)) if k > 1 else None)
        self._min_area = math.pi * self.config.min_radius_px ** 2
        self._states = (_BallState(), _BallState())

    def reset(self) -> None:
        """Forget the previous positions (start of a new stream)."""
        for state in self._states:
            state.reset()

    def mask(self, hsv: np.ndarray, color: BallColor) -> np.ndarray:
        """The cleaned binary mask (uint8, 0/255) of one colour in an HSV frame."""
        bounds = color.bounds()
        mask = cv2.inRange(hsv, bounds[0][0], bounds[0][1])
        for low, high in bounds[1:]:
            mask = cv2.bitwise_or(mask, cv2.inRange(hsv, low, high))
        if self._kernel is not None:
            mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, self._kernel)
        return mask

    def masks(self, frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The (left, right) ball masks of a BGR frame."""
        hsv = cv2.cvtColor(_check_frame(frame), cv2.COLOR_BGR2HSV)
        return tuple(self.mask(hsv, c) for c in self.config.colors.balls)  # type: ignore[return-value]

    def track(self, frame: np.ndarray) -> TrackingResult:
        """Track both balls in one BGR frame, shape (height, width, 3), uint8."""
        frame = _check_frame(frame)
        height, width = frame.shape[:2]
        hsv = cv2.cvtColor(frame, cv2.COLOR_BGR2HSV)
        balls = []
        for color, state in zip(self.config.colors.balls, self._states, strict=True):
            balls.append(self._track_ball(self.mask(hsv, color), state, width, height))
        sensory = np.full(4, np.nan)
        for i, ball in enumerate(balls):
            if ball.tracked:
                sensory[2 * i] = ball.center_px[0] / width
                sensory[2 * i + 1] = 1.0 - ball.center_px[1] / height
        return TrackingResult((balls[0], balls[1]), sensory)

    # --- internals ------------------------------------------------------------------------
    def _choose(self, mask: np.ndarray, state: _BallState) -> tuple[np.ndarray, float] | None:
        # Contours, not connectedComponentsWithStats: on a mostly empty 640x480 mask they cost
        # a tenth as much (the labelling pass touches every pixel). The chosen blob's centroid
        # and area are then measured exactly on its pixels.
        contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
        if not contours:
            return None
        n = len(contours)
        boxes = np.array([cv2.boundingRect(c) for c in contours], dtype=np.float64).reshape(n, 4)
        # a polygon through the boundary pixels' centres misses half a pixel all round
        areas = np.array([cv2.contourArea(c) + 0.5 * cv2.arcLength(c, True) + 1.0
                          for c in contours])
        w, h = boxes[:, 2], boxes[:, 3]
        aspect = np.minimum(w, h) / np.maximum(w, h)
        fill = areas / (w * h) / _DISK_FILL
        circularity = aspect * np.minimum(fill, 1.0 / fill)
        keep = (areas >= self._min_area) & (circularity >= self.config.min_circularity)
        if not keep.any():
            return None
        score = np.log(areas) + 2.0 * np.log(circularity + 1e-3)
        predicted = state.predicted(self.config.lost_memory_frames)
        if predicted is not None:
            centers = boxes[:, :2] + 0.5 * boxes[:, 2:]
            d2 = np.sum((centers - predicted) ** 2, axis=1)
            score = score - d2 / self.config.search_radius_px ** 2
        best = int(np.argmax(np.where(keep, score, -np.inf)))
        x, y, bw, bh = (int(v) for v in boxes[best])
        blob = np.zeros((bh, bw), np.uint8)
        cv2.drawContours(blob, contours, best, 255, cv2.FILLED, offset=(-x, -y))
        blob = cv2.bitwise_and(blob, mask[y:y + bh, x:x + bw])
        m = cv2.moments(blob, binaryImage=True)
        if m["m00"] <= 0:
            return None
        center = np.array([x + m["m10"] / m["m00"] + 0.5, y + m["m01"] / m["m00"] + 0.5])
        return center, float(m["m00"])

    def _track_ball(self, mask: np.ndarray, state: _BallState, width: int,
                    height: int) -> BallMeasurement:
        found = self._choose(mask, state)
        if found is None:
            state.frames_lost += 1
            state.smoothed = None
            state.velocity = np.zeros(2)
            return _LOST
        center, area = found
        if state.center is not None and state.frames_lost == 0:
            state.velocity = center - state.center
        else:
            state.velocity = np.zeros(2)
        state.center = center
        state.frames_lost = 0
        s = self.config.smoothing
        if s > 0.0 and state.smoothed is not None:
            center = (1.0 - s) * center + s * state.smoothed
        state.smoothed = center
        radius = math.sqrt(area / math.pi)
        camera = self.config.camera
        scale = camera.height / height
        depth = float(camera.depth_from_radius(radius * scale, self.config.ball_radius_m))
        pixels = np.array([center[0] * camera.width / width, center[1] * scale])
        position = camera.back_project(pixels, np.asarray(depth))
        return BallMeasurement(TRACKED, np.asarray(center, dtype=np.float64), radius, depth,
                               position)


def _check_frame(frame: np.ndarray) -> np.ndarray:
    frame = np.asarray(frame)
    if frame.ndim != 3 or frame.shape[2] != 3 or frame.dtype != np.uint8:
        raise ConfigError(f"tracker needs a BGR uint8 frame of shape (height, width, 3), got "
                          f"{frame.dtype} {frame.shape}")
    return frame


def draw_tracking(frame: np.ndarray, result: TrackingResult,
                  colors: BallColors | None = None) -> np.ndarray:
    """A copy of ``frame`` with the tracked balls circled and labelled, lost ones listed."""
    out = np.ascontiguousarray(frame).copy()
    marker = ((0, 255, 255), (255, 255, 0))  # yellow for left, cyan for right: both stand out
    names = [c.name for c in (colors or BallColors()).balls]
    for i, ball in enumerate(result.balls):
        label = f"{HAND_NAMES[i][0].upper()} ({names[i]})"
        if ball.tracked:
            c = (int(round(ball.center_px[0] * 4)), int(round(ball.center_px[1] * 4)))
            r = int(round(max(ball.radius_px, 2.0) * 4))
            cv2.circle(out, c, r + 12, marker[i], 2, cv2.LINE_AA, shift=2)
            cv2.drawMarker(out, (c[0] // 4, c[1] // 4), marker[i], cv2.MARKER_CROSS, 10, 1)
            cv2.putText(out, f"{label} {ball.depth_m:.2f} m",
                        (c[0] // 4 + r // 4 + 6, c[1] // 4 - r // 4 - 4),
                        cv2.FONT_HERSHEY_SIMPLEX, 0.45, marker[i], 1, cv2.LINE_AA)
        else:
            cv2.putText(out, f"{label}: lost", (8, 20 + 18 * i), cv2.FONT_HERSHEY_SIMPLEX, 0.5,
                        marker[i], 1, cv2.LINE_AA)
    return out
