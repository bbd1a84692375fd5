"""The user's hands in 3-D from the colour balls: depth from apparent size, or a fixed plane.

The paper's learning phase (its section 2.1, Fig. 2a) needs the hands' 3-D positions: the
robot's joint angles come from them by the mirror mapping and inverse kinematics. A camera
gives each ball's image centre and apparent radius; a ball of known radius ``R`` at depth ``d``
along the optical axis appears with radius ``r = f R / d`` pixels (``f`` the focal length,
:meth:`rnnpb.robot.camera.RobotCamera.apparent_radius_px`), so ``d = f R / r``, and the centre
back-projected at that depth is the hand (:meth:`RobotCamera.back_project`).

Depth from size is the noisiest of the three coordinates: a radius error of ``δr`` pixels moves
the hand by ``d δr / r`` along the axis (about 2.5 cm per pixel at 0.65 m with 4 cm balls), and
a ball half hidden by an occluder or smeared by motion blur looks smaller, hence farther. A
person's hands do not jump in depth from one step to the next, so the depths of a recording
are filtered over time before use: a running median over ``median_steps`` (which removes the
single-frame outliers of partial occlusion) and, where a ball was lost for at most
``max_gap_steps`` steps, linear interpolation of the centre and the depth across the gap.
Longer gaps stay NaN: a recording is cut around them.

Sources without depth — the mouse in the dashboard, a sensory CSV — put the hands on a fixed
plane in front of the robot: ``x = plane_x`` in the robot frame (default the demonstrator's
``UserBody.hand_depth``, 0.68 m, the plane the synthetic user's hands move in), where the ray
through the image point meets it (:func:`hands_on_plane`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rnnpb.demonstrator import UserBody
from rnnpb.errors import ConfigError
from rnnpb.robot.camera import RobotCamera

MOUSE_PLANE_X = UserBody().hand_depth
"""``x`` (metres, robot frame) of the plane the hands of a source without depth move in."""


@dataclass(frozen=True)
class DepthConfig:
    """How depth is recovered from the balls' apparent size.

    Attributes
    ----------
    ball_radius_m : float
        The balls' real radius, metres (the synthetic camera's and the tracker's default 4 cm).
    median_steps : int
        Length of the running median over each hand's depth (odd; 1: no filtering).
    max_gap_steps : int
        Lost stretches of at most this many steps are interpolated; longer ones stay NaN.
    """

    ball_radius_m: float = 0.04
    median_steps: int = 3
    max_gap_steps: int = 5

    def __post_init__(self) -> None:
        if not self.ball_radius_m > 0:
            raise ConfigError(f"depth ball_radius_m must be > 0, got {self.ball_radius_m}")
        if self.median_steps < 1 or self.median_steps % 2 == 0:
            raise ConfigError(
                f"depth median_steps must be an odd number >= 1, got {self.median_steps}"
            )
        if self.max_gap_steps < 0:
            raise ConfigError(f"depth max_gap_steps must be >= 0, got {self.max_gap_steps}")


def depth_from_size(
    radius_px: np.ndarray,
    camera: RobotCamera,
    ball_radius_m: float,
    image_height: int | None = None,
) -> np.ndarray:
    """Depth along the optical axis (metres) from apparent radii (pixels), same shape.

    ``image_height`` is the height of the frames the radii were measured in, when they are not
    the camera model's size (a webcam at 320x240 against the 640x480 model).
    """
    scale = camera.height / image_height if image_height else 1.0
    radius = np.asarray(radius_px, dtype=np.float64) * scale
    with np.errstate(divide="ignore", invalid="ignore"):
        depth = camera.depth_from_radius(radius, ball_radius_m)
    return np.where(radius > 0, depth, np.nan)


def running_median(values: np.ndarray, steps: int) -> np.ndarray:
    """The median over a centred window of ``steps`` along axis 0, ignoring NaN; (n, ...).

    Steps that were NaN stay NaN (filtering does not invent measurements).
    """
    values = np.asarray(values, dtype=np.float64)
    if steps <= 1 or len(values) == 0:
        return values.copy()
    half = steps // 2
    padded = np.concatenate(
        [
            np.full((half, *values.shape[1:]), np.nan),
            values,
            np.full((half, *values.shape[1:]), np.nan),
        ]
    )
    windows = np.lib.stride_tricks.sliding_window_view(padded, steps, axis=0)
    out = np.full(values.shape, np.nan)
    seen = np.isfinite(values)
    if seen.any():
        with np.errstate(invalid="ignore"):
            medians = np.nanmedian(np.where(np.isfinite(windows), windows, np.nan)[seen], axis=-1)
        out[seen] = medians
    return out


def fill_gaps(values: np.ndarray, max_gap: int) -> np.ndarray:
    """Linear interpolation along axis 0 across NaN runs of at most ``max_gap`` steps that have
    a measurement on both sides; (n, ...), columns independent. Other NaN stay NaN."""
    values = np.array(values, dtype=np.float64)
    flat = values.reshape(len(values), -1)
    steps = np.arange(len(values))
    for column in flat.T:
        missing = ~np.isfinite(column)
        if not missing.any() or missing.all():
            continue
        known = steps[~missing]
        filled = np.interp(steps, known, column[~missing])
        # the length of the gap each missing step belongs to, and whether it is interior
        run_start = np.where(missing & ~np.concatenate([[False], missing[:-1]]))[0]
        run_stop = np.where(missing & ~np.concatenate([missing[1:], [False]]))[0] + 1
        for start, stop in zip(run_start, run_stop, strict=True):
            if start > 0 and stop < len(column) and stop - start <= max_gap:
                column[start:stop] = filled[start:stop]
    return flat.reshape(values.shape)


def hands_from_balls(
    center_px: np.ndarray,
    radius_px: np.ndarray,
    camera: RobotCamera | None = None,
    config: DepthConfig | None = None,
    image_size: tuple[int, int] | None = None,
) -> np.ndarray:
    """A recording's 3-D hand positions from the balls' image centres and apparent radii.

    Parameters
    ----------
    center_px : array, shape (n_steps, 2, 2)
        Per step, the left and right balls' (column, row); NaN where lost.
    radius_px : array, shape (n_steps, 2)
        Their apparent radii, pixels; NaN where lost.
    camera : RobotCamera, optional
        The camera model (default the robot's head camera).
    config : DepthConfig, optional
    image_size : (width, height), optional
        Size of the frames measured, when it is not the camera model's.

    Returns
    -------
    array, shape (n_steps, 2, 3)
        The hands in the robot frame, metres; NaN where a ball was lost longer than
        ``max_gap_steps``.
    """
    camera = camera or RobotCamera()
    config = config or DepthConfig()
    center = np.asarray(center_px, dtype=np.float64)
    radius = np.asarray(radius_px, dtype=np.float64)
    if center.ndim != 3 or center.shape[1:] != (2, 2) or radius.shape != center.shape[:2]:
        raise ConfigError(
            f"hands_from_balls: centres (n, 2, 2) and radii (n, 2) expected, got "
            f"{center.shape} and {radius.shape}"
        )
    if image_size is not None:
        width, height = image_size
        center = center * np.array([camera.width / width, camera.height / height])
    depth = depth_from_size(radius, camera, config.ball_radius_m)
    depth = running_median(depth, config.median_steps)
    lost = ~np.isfinite(depth) | ~np.isfinite(center).all(axis=-1)
    center = np.where(lost[..., None], np.nan, center)
    depth = np.where(lost, np.nan, depth)
    center = fill_gaps(center, config.max_gap_steps)
    depth = fill_gaps(depth, config.max_gap_steps)
    return camera.back_project(center, depth)


def hands_on_plane(
    sensory: np.ndarray, camera: RobotCamera | None = None, plane_x: float = MOUSE_PLANE_X
) -> np.ndarray:
    """3-D hands of a source without depth: the image points' rays meet the plane ``x = plane_x``.

    Parameters
    ----------
    sensory : array, shape (..., 4)
        ``lhy lhz rhy rhz`` in [0, 1]; NaN stays NaN.
    camera : RobotCamera, optional
    plane_x : float
        ``x`` of the plane in the robot frame, metres (default :data:`MOUSE_PLANE_X`).

    Returns
    -------
    array, shape (..., 2, 3)
        Left and right hand in the robot frame, metres.
    """
    camera = camera or RobotCamera()
    sensory = np.asarray(sensory, dtype=np.float64)
    if sensory.shape[-1:] != (4,):
        raise ConfigError(f"hands_on_plane: sensory (..., 4) expected, got {sensory.shape}")
    if not plane_x > camera.position[0] + 0.05:
        raise ConfigError(
            f"hands_on_plane: the plane x = {plane_x} m must lie in front of the "
            f"camera (x > {camera.position[0] + 0.05:.2f} m)"
        )
    pixels = camera.pixels_from_normalized(sensory.reshape(*sensory.shape[:-1], 2, 2))
    origin = np.asarray(camera.position)
    direction = camera.back_project(pixels, np.ones(pixels.shape[:-1])) - origin
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (plane_x - origin[0]) / direction[..., 0]
    s = np.where(s > 0, s, np.nan)  # a ray pointing away from the plane meets it nowhere
    return origin + s[..., None] * direction
