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
4. follow every blob of the colour as a track (a Kalman filter each) and choose which is the
   ball: the ball keeps its track while it is seen, a still look-alike gives way to a round
   blob that moves, a lost ball is taken up again only by a round blob that appears near
   where it was and inside the range the hand moved over; a blob the ball has run into (a
   look-alike of its colour touching or crossing it) is split by :func:`split_disk`;
5. centre = the centroid of the chosen blob's pixels (``cv2.moments``, sub-pixel; the fitted
   circle's centre in a split blob), radius = ``sqrt(area / pi)``,
   depth = ``focal_px * ball_radius_m / radius``.

Pixel convention: pixel ``(i, j)`` covers columns ``[i, i + 1)`` and rows ``[j, j + 1)``, so a
centroid of pixel indices is shifted by +0.5 to continuous image coordinates, the coordinates
:class:`rnnpb.robot.camera.RobotCamera` projects to. ``Y = column / width``,
``Z = 1 - row / height`` with the frame's own size.

A ball that is not found gives NaN for its hand and status ``"lost"``; the tracker keeps its
last position for a while to prefer blobs near it when the ball reappears.
"""

from __future__ import annotations

import math
from collections import deque
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
_SPLIT_RATIO = 1.3  # a blob this much bigger than the ball may hold it: look for it inside
_SPLIT_ROUNDNESS = 0.7  # ... and so may a bigger blob less round than this
_COAST_DAMPING = 0.6  # an unseen track's velocity shrinks so: a hand turns, it does not fly off
_PATH_FRAMES = 90  # the ball's last positions that say where the hand moves


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
        # where the ball has been lately: a hand moves to and fro over a range, and a ball
        # coming back from behind something comes back inside it
        self.path: deque[np.ndarray] = deque(maxlen=_PATH_FRAMES)
        # frames since the ball was taken up again outside that range (0: it was not)
        self.provisional = 0

    def within_path(self, center: np.ndarray, margin: float) -> bool:
        """Whether ``center`` lies in the box of the ball's recent positions grown by
        ``margin`` (True when there is no path yet)."""
        if not self.path:
            return True
        points = np.asarray(self.path)
        low, high = points.min(axis=0) - margin, points.max(axis=0) + margin
        return bool(np.all(center >= low) and np.all(center <= high))


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

    def _associate(
        self,
        state: _BallState,
        blobs: np.ndarray,
        contours: list[np.ndarray],
        mask: np.ndarray,
    ) -> tuple[list[_Track | None], tuple[np.ndarray, float] | None]:
        """Match blobs to the colour's tracks (nearest to each track's prediction, within a
        gate of a few radii, widening while a track is unseen); unmatched blobs start tracks,
        tracks unseen for more than ``lost_memory_frames`` are forgotten.

        Returns each blob's track and, when the ball has run into a look-alike of its colour
        and was found inside the merged blob, the ball's centre and area there."""
        config = self.config
        owners: list[_Track | None] = [None] * len(blobs)
        ball = state.selected
        pairs: list[tuple[float, int, int]] = []
        splits: dict[int, tuple[np.ndarray, float]] = {}  # merged blob -> the ball in it
        predictions = [track.predict() for track in state.tracks]  # all, before any split
        for k, track in enumerate(state.tracks):
            predicted = predictions[k]
            if not len(blobs):
                continue
            d = np.linalg.norm(blobs[:, :2] - predicted, axis=1)
            ratio = blobs[:, 2] / track.mean_area
            if track is not ball:
                fits = (d < _gate(track)) & (ratio > 0.4) & (ratio < 2.5)
                pairs.extend((float(d[j]), k, int(j)) for j in np.nonzero(fits)[0])
                continue
            if track.frames_lost:
                # the prediction drifts off while the ball is hidden; where it was last seen
                # stays a good guess for a hand moving to and fro
                d = np.minimum(d, np.linalg.norm(blobs[:, :2] - track.center, axis=1))
            fits = (d < _gate(track)) & (ratio > 0.5) & (ratio < _MERGED_RATIO)
            pairs.extend((float(d[j]), k, int(j)) for j in np.nonzero(fits)[0])
            if track.frames_lost <= 2:
                # A blob much bigger than the ball is the ball and a look-alike of its colour
                # run together; its centroid is neither's. The ball is found inside it, and
                # the look-alike's track coasts on its prediction until they part.
                found = self._split_merged(track, state.tracks, blobs, contours, mask)
                if found is not None:
                    j, center, area = found
                    splits[j] = (center, area)  # the track keeps its size: the fit is rougher
                    pairs = [p for p in pairs if p[1:] != (k, j)]
                    pairs.append((float(np.linalg.norm(center - predicted)), k, j))
        used_tracks: set[int] = set()
        split = None
        for _, k, j in sorted(pairs):
            if k in used_tracks or owners[j] is not None:
                continue
            track = state.tracks[k]
            if j in splits:
                if track is not ball:
                    continue
                split = splits[j]
                track.update(split[0], track.mean_area, track.mean_roundness, config.move_px)
            else:
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
                if track is ball:  # a hand turns; a look-alike carried past goes straight on
                    track.kalman.statePost[2:] *= _COAST_DAMPING
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
        return owners, split

    def _split_merged(
        self,
        ball: _Track,
        tracks: list[_Track],
        blobs: np.ndarray,
        contours: list[np.ndarray],
        mask: np.ndarray,
    ) -> tuple[int, np.ndarray, float] | None:
        """The ball inside a blob it has merged with (a look-alike of its colour touching or
        crossing it): the nearest such blob to the ball's prediction that holds a disk of the
        ball's size there; the blob's index, the disk's centre and area."""
        radius = math.sqrt(ball.mean_area / math.pi)
        d = np.linalg.norm(blobs[:, :2] - ball.prediction, axis=1)
        ratio = blobs[:, 2] / ball.mean_area
        others = np.array(
            [t.prediction for t in tracks if t is not ball and t.frames_lost <= 2]
        ).reshape(-1, 2)
        # much bigger than the ball, or bigger and not round (a sliver of a book behind an arm)
        merged = (ratio >= _SPLIT_RATIO) | ((ratio > 1.0) & (blobs[:, 3] < _SPLIT_ROUNDNESS))
        merged &= d < _gate(ball) + 2.0 * radius
        for j in np.nonzero(merged)[0][np.argsort(d[merged])]:
            found = split_disk(mask, contours[j], ball.prediction, radius, others)
            if found is not None:
                return int(j), found[0], found[1]
        return None

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
            back = self._back_in_range(state, selected, seen)
            if back is not None:
                return back
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
            # the hand goes on moving over the range it moved over; the ball comes back there
            margin = 2.0 * math.sqrt(selected.mean_area / math.pi) + 10.0 * selected.frames_lost
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
                if d < reach and 0.4 < ratio < 2.5 and state.within_path(t.center, margin):
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
            radius = math.sqrt(selected.mean_area / math.pi)
            state.provisional = 0 if state.within_path(best.center, 2.0 * radius) else 1
            return best
        movers = [t for t in candidates if t.moved]
        if movers:
            return max(movers, key=lambda t: t.roundness + math.log(t.area) * 0.25)
        plausible = [t for t in seen if t.roundness >= config.min_roundness]
        if len(plausible) == 1:
            return plausible[0]
        return None

    def _back_in_range(
        self, state: _BallState, selected: _Track, seen: list[_Track]
    ) -> _Track | None:
        """A blob taken for the ball when it came back outside the range the hand moved over
        is on probation: a round blob of the ball's size that then shows up inside that range
        (not one that has been standing there) is the ball, back from behind what hid it."""
        if not state.provisional:
            return None
        radius = math.sqrt(selected.mean_area / math.pi)
        state.provisional += 1
        if state.provisional > _PATH_FRAMES or state.within_path(selected.center, 2.0 * radius):
            state.provisional = 0  # it moves where the hand moved, or has long enough: the ball
            return None
        config = self.config
        inside = [
            t
            for t in seen
            if t is not selected
            and t.roundness >= config.min_roundness + 0.2
            and 0.5 < t.area / selected.mean_area < 2.0
            and not (t.age >= config.static_frames and not t.moved)
            and state.within_path(t.center, 2.0 * radius)
        ]
        if not inside:
            return None
        state.provisional = 0
        back = max(inside, key=lambda t: t.roundness)
        back.moving_frames = max(back.moving_frames, selected.moving_frames)
        return back

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
        owners, split = self._associate(state, blobs, contours, mask)
        if split is not None:
            return split  # the ball, followed through its merge with a look-alike
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
        if not state.provisional:  # a blob on probation does not say where the hand goes
            state.path.append(center)
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


def _gate(track: _Track) -> float:
    """How far from its prediction a track's blob may be: a few radii, widening for the first
    frames the track is unseen (not for ever: a look-alike's track long unseen would take up
    whatever blob of its colour appears, the ball coming back among them)."""
    radius = math.sqrt(track.mean_area / math.pi)
    return max(3.0 * radius, 40.0) + 15.0 * min(track.frames_lost, 4)


def split_disk(
    mask: np.ndarray,
    contour: np.ndarray,
    near: np.ndarray,
    radius: float,
    others: np.ndarray | None = None,
) -> tuple[np.ndarray, float] | None:
    """Find a disk of about ``radius`` inside a blob that holds it and something else.

    The blob's distance transform peaks at the centres of its round parts; the peak nearest
    ``near`` that is deep enough for a disk of ``radius`` is refined by a least-squares circle
    through the blob's boundary points about ``radius`` from it (the disk's own arc; the other
    object's boundary lies elsewhere).

    Parameters
    ----------
    mask : array, shape (height, width), uint8
        The colour's mask the contour was found in.
    contour : array, shape (n, 1, 2)
        The merged blob's outer contour.
    near : array, shape (2,)
        Where the disk is expected (continuous image coordinates, column, row).
    radius : float
        The disk's expected radius, pixels.
    others : array, shape (k, 2), optional
        Where other objects of the colour are expected (their tracks' predictions): a disk
        nearer one of them than ``near``, and within half a radius of it, is that object.

    Returns
    -------
    (array of shape (2,), float) or None
        The disk's centre (continuous image coordinates) and area (px²), or None when the blob
        holds no disk of that size near ``near``, or what it holds is not round.
    """
    x, y, w, h = cv2.boundingRect(contour)
    blob = np.zeros((h + 2, w + 2), np.uint8)  # a frame of background round the blob
    cv2.drawContours(blob, [contour], 0, 255, cv2.FILLED, offset=(1 - x, 1 - y))
    blob[1:-1, 1:-1] = cv2.bitwise_and(blob[1:-1, 1:-1], mask[y : y + h, x : x + w])
    depth = cv2.distanceTransform(blob, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    peaks = (depth >= 0.75 * radius) & (depth >= cv2.dilate(depth, np.ones((3, 3), np.uint8)))
    rows, cols = np.nonzero(peaks)
    if not len(rows):
        return None
    # continuous image coordinates of the peak pixels' centres, deepest first
    order = np.argsort(-depth[rows, cols])
    points = np.column_stack([cols + x - 1 + 0.5, rows + y - 1 + 0.5])[order]
    points = points[np.linalg.norm(points - near, axis=1) <= 1.5 * max(radius, 12.0)]
    starts: list[np.ndarray] = []
    for p in points:  # one start per round part: peaks closer than a third of a radius are one
        if all(np.linalg.norm(p - q) > 0.35 * radius for q in starts):
            starts.append(p)
        if len(starts) == 4:
            break
    if not starts:
        return None
    boundary, _ = cv2.findContours(blob, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    edge = np.concatenate([b.reshape(-1, 2) for b in boundary]).astype(np.float64)
    edge += np.array([x - 1 + 0.5, y - 1 + 0.5])
    best, best_score = None, -math.inf
    for start in starts:
        fit = _fit_disk(edge, start, radius)
        if fit is None:
            continue
        center, fitted_radius, coverage = fit
        distance = float(np.linalg.norm(center - near))
        if others is not None and len(others):
            other = float(np.min(np.linalg.norm(others - center, axis=1)))
            if other < distance and other < 0.5 * radius:
                continue  # the look-alike, where its own track expects it
        # The ball is in front of what it merges with (look-alikes pass behind the hands), so
        # its own outline is the one seen the most of; then its size, then nearness to the
        # prediction (which overshoots when the hand turns).
        size = abs(fitted_radius + 0.5 - radius) / radius
        score = coverage - 2.0 * size - 0.25 * distance / radius
        if score > best_score:
            best, best_score = (center, math.pi * (fitted_radius + 0.5) ** 2), score
    return best


def _fit_disk(
    edge: np.ndarray, start: np.ndarray, radius: float
) -> tuple[np.ndarray, float, float] | None:
    """A circle of about ``radius`` through the boundary points ``edge`` (n, 2) near ``start``:
    its centre, radius and the fraction of its outline the points cover; None if the points
    about ``radius`` from ``start`` do not lie on a circle of about that size."""
    center = start
    fitted_radius = radius - 0.5  # boundary pixels' centres lie half a pixel inside the edge
    for tolerance in (0.25 * radius + 1.0, 0.12 * radius + 1.0, 0.06 * radius + 1.0):
        r = np.linalg.norm(edge - center, axis=1)
        arc = edge[np.abs(r - fitted_radius) < tolerance]
        if len(arc) < 12:
            return None
        # Kasa's algebraic fit: x² + y² = a x + b y + c
        design = np.column_stack([arc, np.ones(len(arc))])
        (a, b, c), *_ = np.linalg.lstsq(design, (arc**2).sum(axis=1), rcond=None)
        center = np.array([a / 2.0, b / 2.0])
        fitted_radius = math.sqrt(max(c + center @ center, 0.0))
    r = np.linalg.norm(arc - center, axis=1)
    round_enough = np.sqrt(np.mean((r - fitted_radius) ** 2)) < max(1.0, 0.06 * radius)
    # the arc goes most of the way round (two straight sides of a book would fit a circle too)
    angles = np.arctan2(arc[:, 1] - center[1], arc[:, 0] - center[0])
    coverage = len(np.unique(np.floor((angles + math.pi) / (2 * math.pi) * 16))) / 16
    if not (round_enough and coverage >= 0.5 and 0.8 < (fitted_radius + 0.5) / radius < 1.15):
        return None
    return center, fitted_radius, coverage


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
    shoulders = getattr(result, "shoulders_px", None)  # bare hands: the pose tracker's body
    if shoulders is None:
        names = [c.name for c in (colors or BallColors()).balls]
    else:
        names = ["hand", "hand"]
        if np.isfinite(shoulders).all():
            ends = [tuple(int(round(v)) for v in point) for point in shoulders]
            cv2.line(out, ends[0], ends[1], (255, 255, 255), 2, cv2.LINE_AA)
    for i, ball in enumerate(result.balls):
        label = f"{HAND_NAMES[i][0].upper()} ({names[i]})"
        if ball.tracked:
            c = (int(round(ball.center_px[0] * 4)), int(round(ball.center_px[1] * 4)))
            radius = ball.radius_px if math.isfinite(ball.radius_px) else 2.0
            r = int(round(max(radius, 2.0) * 4))
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
