"""Colour calibration: derive the balls' HSV ranges from a frame of the user's own camera.

Two ways, both headless:

- from pixels: the user says where each ball is (``--left-pixel X,Y``); the hue, saturation and
  value around that pixel give a first range, the blob of that range containing the pixel is
  taken as the ball, and the final range is fitted to all of the blob's pixels;
- automatically: the blob of broad "red" and "blue" ranges that the tracker follows over the
  frames up to the calibration frame (the one that moves like a hand; the roundest large one
  when nothing moves) is taken as the left and right ball, and the range is fitted to it in the
  same way.

The fitted range: hue = the blob's circular median ± (its 98th-percentile deviation + a margin);
saturation and value from a margin below their 5th percentile up to 255, so that shading and
highlights on the ball stay inside while the dull background stays out.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from rnnpb.errors import RnnpbError
from rnnpb.perception._colors import BallColor, BallColors
from rnnpb.perception._tracker import BallTracker, TrackerConfig

BROAD_RED = BallColor("red", (165, 10), (100, 255), (50, 255))
BROAD_BLUE = BallColor("blue", (95, 135), (100, 255), (40, 255))
HUE_MARGIN = 4
SATURATION_MARGIN = 30
VALUE_MARGIN = 40


@dataclass(frozen=True)
class BallCalibration:
    """How one ball's range was found: the range, the blob it was fitted to and its size."""

    color: BallColor
    center_px: tuple[float, float]
    radius_px: float
    n_pixels: int


def _hue_stats(hue: np.ndarray) -> tuple[int, int]:
    """Circular median-ish centre and spread (OpenCV hue units) of hue samples."""
    angles = hue.astype(np.float64) * (2 * math.pi / 180.0)
    centre = math.atan2(np.sin(angles).mean(), np.cos(angles).mean())
    deviation = np.angle(np.exp(1j * (angles - centre)))  # wrapped to (-pi, pi]
    centre = centre + float(np.median(deviation))
    deviation = np.abs(np.angle(np.exp(1j * (angles - centre))))
    spread = float(np.percentile(deviation, 98)) * 180.0 / (2 * math.pi)
    return int(round(centre * 180.0 / (2 * math.pi))) % 180, int(math.ceil(spread))


def color_name(hue: int) -> str:
    """A colour's everyday name from its OpenCV hue (0…179)."""
    for upper, name in (
        (8, "red"),
        (22, "orange"),
        (35, "yellow"),
        (85, "green"),
        (100, "cyan"),
        (130, "blue"),
        (160, "magenta"),
        (180, "red"),
    ):
        if hue < upper:
            return name
    return "red"


def fit_color(hsv_pixels: np.ndarray, name: str | None = None) -> BallColor:
    """An HSV range that holds most of the given pixels, shape (n, 3), and little else."""
    hsv_pixels = np.asarray(hsv_pixels).reshape(-1, 3)
    if len(hsv_pixels) < 5:
        raise RnnpbError(f"calibration ({name or 'a'} ball): too few pixels to fit a colour range")
    centre, spread = _hue_stats(hsv_pixels[:, 0])
    name = name or color_name(centre)
    half = int(np.clip(spread + HUE_MARGIN, 5, 30))
    low, high = (centre - half) % 180, (centre + half) % 180
    s_low = int(np.clip(np.percentile(hsv_pixels[:, 1], 5) - SATURATION_MARGIN, 40, 230))
    v_low = int(np.clip(np.percentile(hsv_pixels[:, 2], 5) - VALUE_MARGIN, 20, 230))
    return BallColor(name, (low, high), (s_low, 255), (v_low, 255))


def _blob_at(mask: np.ndarray, xy: tuple[int, int]) -> np.ndarray | None:
    n, labels = cv2.connectedComponents(mask, connectivity=8)
    h, w = mask.shape
    x, y = xy
    window = labels[max(0, y - 3) : min(h, y + 4), max(0, x - 3) : min(w, x + 4)]
    ids = window[window > 0]
    if ids.size == 0:
        return None
    return labels == np.bincount(ids).argmax()


def _calibration(frame_hsv: np.ndarray, blob: np.ndarray, name: str | None) -> BallCalibration:
    color = fit_color(frame_hsv[blob], name)
    ys, xs = np.nonzero(blob)
    n = int(blob.sum())
    return BallCalibration(
        color, (float(xs.mean() + 0.5), float(ys.mean() + 0.5)), math.sqrt(n / math.pi), n
    )


def calibrate_from_pixel(
    frame: np.ndarray, xy: tuple[int, int], name: str | None = None, neighbourhood_px: int = 5
) -> BallCalibration:
    """Fit a ball's colour range from the ball at pixel ``xy`` = (column, row) of a BGR frame.

    ``name`` defaults to the everyday name of the fitted hue ("red", "blue", …).
    """
    h, w = frame.shape[:2]
    x, y = int(xy[0]), int(xy[1])
    ball = f"the {name} ball" if name else "the ball"
    if not (0 <= x < w and 0 <= y < h):
        raise RnnpbError(f"calibration ({ball}): pixel {x},{y} is outside the {w}x{h} frame")
    hsv = cv2.cvtColor(frame, cv2.COLOR_BGR2HSV)
    r = neighbourhood_px
    ys, xs = np.mgrid[max(0, y - r) : min(h, y + r + 1), max(0, x - r) : min(w, x + r + 1)]
    disk = (xs - x) ** 2 + (ys - y) ** 2 <= r * r
    samples = hsv[ys[disk], xs[disk]]
    if np.median(samples[:, 1]) < 60:
        raise RnnpbError(
            f"calibration ({ball}): the pixels around {x},{y} are grey "
            f"(median saturation {int(np.median(samples[:, 1]))} of 255); point "
            "at the middle of a coloured ball"
        )
    samples = samples[samples[:, 1] >= np.median(samples[:, 1]) * 0.6]
    first = fit_color(samples, name)
    name = first.name
    # The middle of the ball is its brightest, most saturated part; relax the first range so
    # that the blob reaches the ball's darker rim before fitting the final range to it.
    mask = BallTracker(TrackerConfig(opening_px=0)).mask(
        hsv,
        BallColor(
            name,
            ((first.hue[0] - 8) % 180, (first.hue[1] + 8) % 180),
            (max(40, first.saturation[0] - 50), 255),
            (max(20, first.value[0] - 60), 255),
        ),
    )
    blob = _blob_at(mask, (x, y))
    if blob is None:
        raise RnnpbError(f"calibration ({ball}): found no ball-coloured blob at {x},{y}")
    return _calibration(hsv, blob, name)


def locate_ball(
    frames: np.ndarray | Sequence[np.ndarray], color: BallColor
) -> tuple[np.ndarray, float] | None:
    """Where the ball of ``color`` is in the last of ``frames`` (BGR): its centre and area.

    The tracker runs over all the frames, so the ball is the blob of its colour that moves
    like a hand, not a still look-alike. When motion does not tell (a single frame, or
    nothing moved), the roundest large blob is taken.
    """
    frames = [frames] if isinstance(frames, np.ndarray) and frames.ndim == 3 else list(frames)
    tracker = BallTracker(TrackerConfig(colors=BallColors(color, color)))
    result = None
    for frame in frames:
        result = tracker.track(frame)
    if result is not None and result.balls[0].tracked:
        ball = result.balls[0]
        return ball.center_px, math.pi * ball.radius_px**2
    mask = tracker.mask(cv2.cvtColor(frames[-1], cv2.COLOR_BGR2HSV), color)
    contours, blobs = tracker._blobs(mask)
    if not len(blobs):
        return None
    best = int(np.argmax(np.log(blobs[:, 2]) + 4.0 * np.log(blobs[:, 3])))
    return tracker._measure(mask, contours[best])


def calibrate_automatically(
    frames: np.ndarray | Sequence[np.ndarray], broad: BallColor
) -> BallCalibration:
    """Fit a ball's colour range to the ball within the ``broad`` range in the last frame.

    ``frames``: one BGR frame or several in order; with several the ball is the blob that
    moves (see :func:`locate_ball`), so a still object of the ball's colour is not taken.
    """
    frames = [frames] if isinstance(frames, np.ndarray) and frames.ndim == 3 else list(frames)
    found = locate_ball(frames, broad)
    if found is None:
        raise RnnpbError(
            f"calibration: no round {broad.name} blob in the frame; give the "
            f"ball's position with --{'left' if broad is BROAD_RED else 'right'}"
            "-pixel X,Y"
        )
    center, _ = found
    hsv = cv2.cvtColor(frames[-1], cv2.COLOR_BGR2HSV)
    mask = BallTracker(TrackerConfig(colors=BallColors(broad, broad))).mask(hsv, broad)
    blob = _blob_at(mask, (int(center[0]), int(center[1])))
    assert blob is not None
    return _calibration(hsv, blob, broad.name)


def calibration_preview(
    frame: np.ndarray, colors: BallColors, calibrations: tuple[BallCalibration, BallCalibration]
) -> np.ndarray:
    """The frame with the found balls circled, next to the two masks of the fitted ranges."""
    tracker = BallTracker(TrackerConfig(colors=colors))
    masks = tracker.masks(frame)
    marked = frame.copy()
    panels = [marked]
    tints = ((0, 255, 255), (255, 255, 0))
    for i, (mask, cal) in enumerate(zip(masks, calibrations, strict=True)):
        c = (int(round(cal.center_px[0])), int(round(cal.center_px[1])))
        cv2.circle(marked, c, int(cal.radius_px) + 6, tints[i], 2, cv2.LINE_AA)
        panel = np.zeros_like(frame)
        panel[mask > 0] = tints[i]
        side = "left" if i == 0 else "right"
        cv2.putText(
            panel,
            f"{side}: {cal.color.name} hue {cal.color.hue} sat "
            f"{cal.color.saturation} val {cal.color.value}",
            (8, 20),
            cv2.FONT_HERSHEY_SIMPLEX,
            0.45,
            (255, 255, 255),
            1,
            cv2.LINE_AA,
        )
        panels.append(panel)
    return np.hstack(panels)
