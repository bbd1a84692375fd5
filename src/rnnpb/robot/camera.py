"""The robot's head camera as a pinhole model, shared by the demonstrator, perception and the
MuJoCo scene so that all three agree on what the robot sees.

Frames (docs/design.md): the robot frame has its origin on the floor under the robot's torso,
``x`` forward (towards the user), ``y`` to the robot's left, ``z`` up; metres. The camera sits in
the head, looks forward along ``x``, tilted up by ``pitch_deg``. Image columns grow to the
robot's right, rows grow downwards. The sensory values are the image coordinates normalized to
[0, 1]: ``Y = column / width`` (left to right as the robot sees it) and
``Z = 1 - row / height`` (bottom to top).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rnnpb.errors import ConfigError


@dataclass(frozen=True)
class RobotCamera:
    """A pinhole camera in the robot's head.

    Attributes
    ----------
    width, height : int
        Image size in pixels.
    fovy_deg : float
        Vertical field of view in degrees (MuJoCo's ``fovy``).
    position : tuple of 3 floats
        Camera centre in the robot frame, metres.
    pitch_deg : float
        Upward tilt of the optical axis from horizontal, degrees.
    """

    width: int = 640
    height: int = 480
    fovy_deg: float = 60.0
    position: tuple[float, float, float] = (0.03, 0.0, 0.52)
    pitch_deg: float = 10.0

    def __post_init__(self) -> None:
        if self.width < 8 or self.height < 8:
            raise ConfigError(
                f"camera image must be at least 8x8 pixels, got {self.width}x{self.height}"
            )
        if not 1.0 < self.fovy_deg < 170.0:
            raise ConfigError(f"camera fovy_deg must be in (1, 170), got {self.fovy_deg}")
        if len(self.position) != 3:
            raise ConfigError("camera position must have 3 coordinates")

    # --- geometry -------------------------------------------------------------------------
    @property
    def focal_px(self) -> float:
        """Focal length in pixels (same horizontally and vertically)."""
        return 0.5 * self.height / math.tan(math.radians(self.fovy_deg) / 2.0)

    @property
    def axes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(right, up, forward) unit vectors of the camera in the robot frame."""
        p = math.radians(self.pitch_deg)
        forward = np.array([math.cos(p), 0.0, math.sin(p)])
        right = np.array([0.0, -1.0, 0.0])
        up = np.array([-math.sin(p), 0.0, math.cos(p)])
        return right, up, forward

    def mjcf_attributes(self) -> dict[str, str]:
        """``pos``, ``xyaxes`` and ``fovy`` for an MJCF ``<camera>`` in the robot frame."""
        right, up, _ = self.axes
        fmt = " ".join
        return {
            "pos": fmt(f"{v:.6g}" for v in self.position),
            "xyaxes": fmt(f"{v:.6g}" for v in (*right, *up)),
            "fovy": f"{self.fovy_deg:.6g}",
        }

    def camera_coordinates(self, points: np.ndarray) -> np.ndarray:
        """Points in the robot frame, shape (..., 3) → camera (right, up, depth), shape (..., 3)."""
        points = np.asarray(points, dtype=np.float64)
        right, up, forward = self.axes
        d = points - np.asarray(self.position)
        return np.stack([d @ right, d @ up, d @ forward], axis=-1)

    def project(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Project robot-frame points (..., 3) → pixel (column, row) (..., 2) and depth (...)."""
        cam = self.camera_coordinates(points)
        depth = cam[..., 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            col = 0.5 * self.width + self.focal_px * cam[..., 0] / depth
            row = 0.5 * self.height - self.focal_px * cam[..., 1] / depth
        return np.stack([col, row], axis=-1), depth

    def back_project(self, pixels: np.ndarray, depth: np.ndarray) -> np.ndarray:
        """Pixel (column, row) (..., 2) at a depth (...) along the axis → robot-frame points."""
        pixels = np.asarray(pixels, dtype=np.float64)
        depth = np.asarray(depth, dtype=np.float64)
        x = (pixels[..., 0] - 0.5 * self.width) * depth / self.focal_px
        y = (0.5 * self.height - pixels[..., 1]) * depth / self.focal_px
        right, up, forward = self.axes
        return (
            np.asarray(self.position)
            + x[..., None] * right
            + y[..., None] * up
            + depth[..., None] * forward
        )

    def normalize_pixels(self, pixels: np.ndarray) -> np.ndarray:
        """Pixel (column, row) (..., 2) → normalized view-plane (Y, Z) (..., 2) in [0, 1]."""
        pixels = np.asarray(pixels, dtype=np.float64)
        return np.stack([pixels[..., 0] / self.width, 1.0 - pixels[..., 1] / self.height], -1)

    def pixels_from_normalized(self, yz: np.ndarray) -> np.ndarray:
        """Normalized view-plane (Y, Z) (..., 2) → pixel (column, row) (..., 2)."""
        yz = np.asarray(yz, dtype=np.float64)
        return np.stack([yz[..., 0] * self.width, (1.0 - yz[..., 1]) * self.height], -1)

    def sensory_from_hands(self, hands: np.ndarray) -> np.ndarray:
        """The sensory vector from 3-D hand positions.

        Parameters
        ----------
        hands : array, shape (..., 2, 3)
            The user's left hand (index 0) and right hand (index 1) in the robot frame.

        Returns
        -------
        array, shape (..., 4)
            ``lhy lhz rhy rhz``.
        """
        pixels, _ = self.project(hands)
        yz = self.normalize_pixels(pixels)
        return yz.reshape(*yz.shape[:-2], 4)

    def apparent_radius_px(self, depth: np.ndarray, radius_m: float) -> np.ndarray:
        """Apparent radius in pixels of a ball of ``radius_m`` at ``depth`` metres."""
        return self.focal_px * radius_m / np.asarray(depth, dtype=np.float64)

    def depth_from_radius(self, radius_px: np.ndarray, radius_m: float) -> np.ndarray:
        """Depth estimate (metres) from a ball's apparent radius in pixels."""
        return self.focal_px * radius_m / np.asarray(radius_px, dtype=np.float64)
