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
_MERGED_RATIO = 1.6  # a blob this much bigger than the ball holds the ball and something else


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
    lost_memory_frames: int = 30
    smoothing: float = 0.0
    min_roundness: float = 0.45
    move_px: float = 2.0
    static_frames: int = 3
    camera: RobotCamera = field(default_factory=RobotCamera)

    def __post_init__(self) -> None:
        if not isinstance(self.colors, BallColors):
            raise ConfigError("tracker colors must be a BallColors")
        if not self.ball_radius_m > 0:
            raise ConfigError(f"tracker ball_radius_m must be > 0, got {self.ball_radius_m}")
        if not self.min_radius_px >= 0:
            raise ConfigError(f"tracker min_radius_px must be >= 0, got {self.min_radius_px}")
        if not 0.0 <= self.min_circularity <= 1.0:
            raise ConfigError(
                f"tracker min_circularity must be in [0, 1], got {self.min_circularity}"
            )
        if not (isinstance(self.opening_px, int) and 0 <= self.opening_px <= 31):
            raise ConfigError(
                f"tracker opening_px must be an integer in [0, 31], got {self.opening_px}"
            )
        if not self.search_radius_px > 0:
            raise ConfigError(f"tracker search_radius_px must be > 0, got {self.search_radius_px}")
        if self.lost_memory_frames < 0:
            raise ConfigError(
                f"tracker lost_memory_frames must be >= 0, got {self.lost_memory_frames}"
            )
        if not 0.0 <= self.smoothing < 1.0:
            raise ConfigError(f"tracker smoothing must be in [0, 1), got {self.smoothing}")
        if not 0.0 <= self.min_roundness <= 1.0:
            raise ConfigError(f"tracker min_roundness must be in [0, 1], got {self.min_roundness}")
        if not self.move_px > 0:
            raise ConfigError(f"tracker move_px must be > 0, got {self.move_px}")
        if self.static_frames < 1:
            raise ConfigError(f"tracker static_frames must be >= 1, got {self.static_frames}")


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


class _Track:
    """One blob of a ball's colour followed from frame to frame (the ball or a look-alike).

    A constant-velocity Kalman filter (``cv2.KalmanFilter``, state x, y, vx, vy) predicts
    where the blob will be; ``moving_frames`` counts the frames in which it moved by more than
    ``move_px`` without changing its size much (a ball on a hand does; a book on a shelf does
    not, and a blob that only grows or shrinks as something passes in front of it does not).
    """

    def __init__(self, center: np.ndarray, area: float, roundness: float) -> None:
        kf = cv2.KalmanFilter(4, 2)
        kf.transitionMatrix = np.array(
            [[1, 0, 1, 0], [0, 1, 0, 1], [0, 0, 1, 0], [0, 0, 0, 1]], np.float32
        )
        kf.measurementMatrix = np.eye(2, 4, dtype=np.float32)
        # a hand circling at 30 px/frame accelerates by ~15 px/frame^2: velocity noise 10 px
        kf.processNoiseCov = np.diag([4.0, 4.0, 100.0, 100.0]).astype(np.float32)
        kf.measurementNoiseCov = np.eye(2, dtype=np.float32)
        kf.errorCovPost = np.diag([1.0, 1.0, 400.0, 400.0]).astype(np.float32)
        kf.statePost = np.array([[center[0]], [center[1]], [0.0], [0.0]], np.float32)
        self.kalman = kf
        self.center = center
        self.area = area
        self.roundness = roundness
        self.mean_roundness = roundness
        self.mean_area = area
        self.age = 1
        self.frames_lost = 0
        self.moving_frames = 0
        self.prediction = center

    def predict(self) -> np.ndarray:
        self.prediction = self.kalman.predict()[:2, 0].astype(np.float64)
        return self.prediction

    def update(self, center: np.ndarray, area: float, roundness: float, move_px: float) -> None:
        step = float(np.linalg.norm(center - self.center))
        ratio = area / self.area
        if step > move_px and 0.7 < ratio < 1.0 / 0.7:
            self.moving_frames += 1
        self.kalman.correct(np.asarray(center, np.float32).reshape(2, 1))
        self.center, self.area, self.roundness = center, area, roundness
        self.mean_roundness += 0.3 * (roundness - self.mean_roundness)
        self.mean_area += 0.2 * (area - self.mean_area)
        self.age += 1
        self.frames_lost = 0

    @property
    def moved(self) -> bool:
        return self.moving_frames >= 2


class _BallState:
    """What the tracker remembers of one ball between frames: every blob of its colour as a
    track, and which track is the ball (``selected``)."""

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        self.tracks: list[_Track] = []
        self.selected: _Track | None = None
        self.smoothed: np.ndarray | None = None


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
        self._kernel = cv2.getStructuringElement(cv2.MORPH_RECT, (k, k)) if k > 1 else None
        self._min_area = math.pi * self.config.min_radius_px**2
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
    def _blobs(self, mask: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
        """The blobs that pass the size and shape checks: their contours and, per blob, a row
        ``(x, y, area, roundness)`` (centre from the contour's moments; roundness = the blob's
        area over that of its smallest enclosing circle, 1 for a disk, 2/pi for a square)."""
        # Contours, not connectedComponentsWithStats: on a mostly empty 640x480 mask they cost
        # a tenth as much (the labelling pass touches every pixel). The chosen blob's centroid
        # and area are then measured exactly on its pixels.
        contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
        kept, rows = [], []
        for contour in contours:
            x, y, w, h = cv2.boundingRect(contour)
            # a polygon through the boundary pixels' centres misses half a pixel all round
            area = cv2.contourArea(contour) + 0.5 * cv2.arcLength(contour, True) + 1.0
            if area < self._min_area:
                continue
            fill = area / (w * h) / _DISK_FILL
            if min(w, h) / max(w, h) * min(fill, 1.0 / fill) < self.config.min_circularity:
                continue
            m = cv2.moments(contour)
            if m["m00"] > 0:
                center = (m["m10"] / m["m00"] + 0.5, m["m01"] / m["m00"] + 0.5)
            else:
                center = (x + 0.5 * w, y + 0.5 * h)
            _, r = cv2.minEnclosingCircle(contour)
            roundness = min(1.0, area / (math.pi * (r + 0.5) ** 2))
            kept.append(contour)
            rows.append((center[0], center[1], area, roundness))
        return kept, np.array(rows, dtype=np.float64).reshape(-1, 4)

    def _associate(self, state: _BallState, blobs: np.ndarray) -> list[_Track | None]:
        """Match blobs to the colour's tracks (nearest to each track's prediction, within a
        gate of a few radii, widening while a track is unseen); unmatched blobs start tracks,
        tracks unseen for more than ``lost_memory_frames`` are forgotten."""
        config = self.config
        owners: list[_Track | None] = [None] * len(blobs)
        pairs = []
        for k, track in enumerate(state.tracks):
            predicted = track.predict()
            radius = math.sqrt(track.mean_area / math.pi)
            gate = max(3.0 * radius, 40.0) + 15.0 * track.frames_lost
            if len(blobs):
                d = np.linalg.norm(blobs[:, :2] - predicted, axis=1)
                ratio = blobs[:, 2] / track.mean_area
                # A blob much bigger than the ball is the ball and a look-alike of its colour
                # run together; its centroid is neither's. The ball coasts on its prediction
                # until they part, rather than being dragged off by the look-alike.
                if track is state.selected:
                    fits = (ratio > 0.5) & (ratio < _MERGED_RATIO)
                else:
                    fits = (ratio > 0.4) & (ratio < 2.5)
                for j in np.nonzero((d < gate) & fits)[0]:
                    pairs.append((float(d[j]), k, int(j)))
        used_tracks: set[int] = set()
        for _, k, j in sorted(pairs):
            if k in used_tracks or owners[j] is not None:
                continue
            track = state.tracks[k]
            track.update(
                blobs[j, :2].copy(), float(blobs[j, 2]), float(blobs[j, 3]), config.move_px
            )
            owners[j] = track
            used_tracks.add(k)
        survivors = []
        for k, track in enumerate(state.tracks):
            if k not in used_tracks:
                track.frames_lost += 1
                # coast on the prediction: the state moves on, the last measurement stays
                track.kalman.statePost = track.kalman.statePre.copy()
                track.kalman.errorCovPost = track.kalman.errorCovPre.copy()
            if track.frames_lost <= config.lost_memory_frames:
                survivors.append(track)
        for j in range(len(blobs)):
            if owners[j] is None:
                owners[j] = _Track(blobs[j, :2].copy(), float(blobs[j, 2]), float(blobs[j, 3]))
                survivors.append(owners[j])
        state.tracks = survivors
        if state.selected is not None and state.selected not in survivors:
            state.selected = None
        return owners

    def _select(self, state: _BallState, owners: list[_Track | None]) -> _Track | None:
        """Which of this frame's blobs is the ball.

        The ball keeps its track while it is seen. A track that has never moved gives way to
        one that has: a ball taken for the ball by a still look-alike is found again as soon as
        the real one moves. Without a track (the start, or the ball lost), a blob is taken only
        when it is unambiguous: one that moved (the nearest to where the ball was lost, and the
        roundest), or the only blob of the colour when no lost ball is being waited for. Blobs
        that have stayed still since they appeared are scenery while the ball is away.
        """
        config = self.config
        seen = [t for t in owners if t is not None]
        selected = state.selected
        if selected is not None and selected.frames_lost == 0:
            if selected.moved:
                # a moving look-alike taken while the ball was away is not round: give it up
                # for a round mover (the ball, back)
                if selected.mean_roundness >= config.min_roundness + 0.2:
                    return selected
                movers = [
                    t
                    for t in seen
                    if t.moved
                    and t is not selected
                    and t.mean_roundness >= selected.mean_roundness + 0.25
                ]
            else:
                movers = [t for t in seen if t.moved and t.roundness >= config.min_roundness]
            if not movers:
                return selected
            return max(movers, key=lambda t: t.roundness)
        waiting = selected is not None  # the ball is unseen but remembered
        candidates = [
            t
            for t in seen
            if t.roundness >= config.min_roundness
            and not (t.age >= config.static_frames and not t.moved)
        ]
        if waiting:
            assert selected is not None
            reach = config.search_radius_px + 20.0 * selected.frames_lost
            scored = []
            for t in candidates:
                if t.roundness < config.min_roundness + 0.2:
                    continue  # only a round blob is taken for the ball coming back
                if t.age > selected.frames_lost + 2:
                    continue  # it was there all the while the ball was not: not the ball
                # the prediction drifts off while the ball is hidden; where it was last seen
                # stays a good guess for a hand moving to and fro
                d = float(
                    min(
                        np.linalg.norm(t.center - selected.prediction),
                        np.linalg.norm(t.center - selected.center),
                    )
                )
                ratio = t.area / selected.mean_area
                if d < reach and 0.4 < ratio < 2.5:
                    scored.append(
                        (
                            d / config.search_radius_px
                            - t.roundness
                            - 0.5 * (t.age <= selected.frames_lost + 1),
                            t,
                        )
                    )
            if not scored:
                return None
            best = min(scored, key=lambda item: item[0])[1]
            best.moving_frames = max(best.moving_frames, selected.moving_frames)
            return best
        movers = [t for t in candidates if t.moved]
        if movers:
            return max(movers, key=lambda t: t.roundness + math.log(t.area) * 0.25)
        plausible = [t for t in seen if t.roundness >= config.min_roundness]
        if len(plausible) == 1:
            return plausible[0]
        return None

    def _measure(self, mask: np.ndarray, contour: np.ndarray) -> tuple[np.ndarray, float] | None:
        x, y, bw, bh = cv2.boundingRect(contour)
        blob = np.zeros((bh, bw), np.uint8)
        cv2.drawContours(blob, [contour], 0, 255, cv2.FILLED, offset=(-x, -y))
        blob = cv2.bitwise_and(blob, mask[y : y + bh, x : x + bw])
        m = cv2.moments(blob, binaryImage=True)
        if m["m00"] <= 0:
            return None
        center = np.array([x + m["m10"] / m["m00"] + 0.5, y + m["m01"] / m["m00"] + 0.5])
        return center, float(m["m00"])

    def _choose(self, mask: np.ndarray, state: _BallState) -> tuple[np.ndarray, float] | None:
        """Update the colour's tracks with one mask; the ball's exact centre and area."""
        contours, blobs = self._blobs(mask)
        owners = self._associate(state, blobs)
        chosen = self._select(state, owners)
        if chosen is None:
            if state.selected is not None and state.selected.frames_lost == 0:
                state.selected.frames_lost = 0  # seen, but not taken for the ball this frame
            return None
        state.selected = chosen
        return self._measure(mask, contours[owners.index(chosen)])

    def _track_ball(
        self, mask: np.ndarray, state: _BallState, width: int, height: int
    ) -> BallMeasurement:
        found = self._choose(mask, state)
        if found is None:
            state.smoothed = None
            return _LOST
        center, area = found
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
        return BallMeasurement(
            TRACKED, np.asarray(center, dtype=np.float64), radius, depth, position
        )


def _check_frame(frame: np.ndarray) -> np.ndarray:
    frame = np.asarray(frame)
    if frame.ndim != 3 or frame.shape[2] != 3 or frame.dtype != np.uint8:
        raise ConfigError(
            f"tracker needs a BGR uint8 frame of shape (height, width, 3), got "
            f"{frame.dtype} {frame.shape}"
        )
    return frame


def draw_tracking(
    frame: np.ndarray, result: TrackingResult, colors: BallColors | None = None
) -> np.ndarray:
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
            cv2.putText(
                out,
                f"{label} {ball.depth_m:.2f} m",
                (c[0] // 4 + r // 4 + 6, c[1] // 4 - r // 4 - 4),
                cv2.FONT_HERSHEY_SIMPLEX,
                0.45,
                marker[i],
                1,
                cv2.LINE_AA,
            )
        else:
            cv2.putText(
                out,
                f"{label}: lost",
                (8, 20 + 18 * i),
                cv2.FONT_HERSHEY_SIMPLEX,
                0.5,
                marker[i],
                1,
                cv2.LINE_AA,
            )
    return out
