"""Offscreen images and videos of the humanoid from its head camera or an outside camera.

Rendering is headless: the OpenGL is ``MUJOCO_GL`` if the program set it, else EGL, else OSMesa,
chosen when the first model is loaded (:mod:`rnnpb.robot._gl`).
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.robot._gl import import_mujoco
from rnnpb.robot._mujoco import ROBOT_EYE, load_model, set_pose
from rnnpb.robot.camera import RobotCamera

if TYPE_CHECKING:
    import mujoco

CAMERAS: tuple[str, ...] = (ROBOT_EYE, "front", "three_quarter")
"""Named cameras: the robot's head camera and two outside views of the robot."""


class RobotRenderer:
    """Renders the humanoid in a given pose.

    Parameters
    ----------
    width, height : int
        Image size in pixels; for ``robot_eye`` use the camera model's size so that pixels
        agree with :class:`RobotCamera` projections.
    camera : RobotCamera, optional
        The head camera model placed in the scene.
    model : mujoco.MjModel, optional
        A model from :func:`rnnpb.robot.load_model` (to share one with a simulation).

    Use as a context manager, or call :meth:`close`, to free the GL context.
    """

    def __init__(
        self,
        width: int = 640,
        height: int = 480,
        camera: RobotCamera | None = None,
        model: mujoco.MjModel | None = None,
    ) -> None:
        self.camera = camera or RobotCamera()
        self.model = model if model is not None else load_model(self.camera)
        if width > self.model.vis.global_.offwidth or height > self.model.vis.global_.offheight:
            raise ConfigError(
                f"render size {width}x{height} exceeds the model's offscreen "
                f"buffer {self.model.vis.global_.offwidth}x"
                f"{self.model.vis.global_.offheight}"
            )
        mj = import_mujoco()
        self.data = mj.MjData(self.model)
        self.width, self.height = int(width), int(height)
        try:
            self._renderer = mj.Renderer(self.model, height=self.height, width=self.width)
        except Exception as error:  # the GL library loads but gives no context (no device)
            raise ConfigError(
                f"MuJoCo cannot render with MUJOCO_GL={os.environ.get('MUJOCO_GL', '')!r}: "
                f"{error}; set MUJOCO_GL=osmesa (software rendering) before the first "
                "simulation or renderer is made"
            ) from error

    def _check_camera(self, camera: str) -> None:
        if camera not in CAMERAS:
            raise ConfigError(f"unknown camera {camera!r} (known: {', '.join(CAMERAS)})")

    def render(
        self, joints: np.ndarray, camera: str = "front", user_hands: np.ndarray | None = None
    ) -> np.ndarray:
        """An RGB image, shape (height, width, 3) uint8, of the robot at ``joints`` (8,),
        with the user's hand balls at ``user_hands`` (2, 3) if given."""
        self._check_camera(camera)
        set_pose(self.model, self.data, joints, user_hands)
        self._renderer.update_scene(self.data, camera=camera)
        return self._renderer.render().copy()

    def segmentation(
        self, joints: np.ndarray, camera: str = "front", user_hands: np.ndarray | None = None
    ) -> np.ndarray:
        """Geom id per pixel, shape (height, width) int; -1 where nothing (the sky) is seen."""
        self._check_camera(camera)
        set_pose(self.model, self.data, joints, user_hands)
        self._renderer.enable_segmentation_rendering()
        try:
            self._renderer.update_scene(self.data, camera=camera)
            seg = self._renderer.render()
        finally:
            self._renderer.disable_segmentation_rendering()
        ids = seg[..., 0].astype(np.int64)
        ids[seg[..., 1] != int(import_mujoco().mjtObj.mjOBJ_GEOM)] = -1
        return ids

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def __enter__(self) -> RobotRenderer:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()


def render_pose(
    joints: np.ndarray,
    camera: str = "front",
    width: int = 640,
    height: int = 480,
    user_hands: np.ndarray | None = None,
) -> np.ndarray:
    """One RGB image (height, width, 3) uint8 of the robot at ``joints`` (8,) radians."""
    with RobotRenderer(width, height) as renderer:
        return renderer.render(joints, camera, user_hands)


def write_video(
    path: str | os.PathLike[str], frames: Iterable[np.ndarray], fps: float = 2.5
) -> Path:
    """Write RGB frames (each (height, width, 3) uint8) as an mp4 video (OpenCV, ``mp4v``).

    The default frame rate plays a 0.4 s network step in real time.
    """
    import cv2

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    # Written under a temporary name and renamed when complete: never a half-written video.
    partial = path.with_name(f".{path.stem}.partial{path.suffix}")
    writer = None
    count = 0
    try:
        for frame in frames:
            frame = np.asarray(frame)
            if frame.ndim != 3 or frame.shape[2] != 3 or frame.dtype != np.uint8:
                raise ConfigError(
                    f"video frames must be (height, width, 3) uint8, got "
                    f"{frame.shape} {frame.dtype}"
                )
            if writer is None:
                size = (frame.shape[1], frame.shape[0])
                writer = cv2.VideoWriter(str(partial), cv2.VideoWriter_fourcc(*"mp4v"), fps, size)
                if not writer.isOpened():
                    raise ConfigError(f"{path}: cannot open a video writer")
            writer.write(np.ascontiguousarray(frame[..., ::-1]))
            count += 1
    except BaseException:
        if writer is not None:
            writer.release()
        partial.unlink(missing_ok=True)
        raise
    if writer is not None:
        writer.release()
    if count == 0:
        raise ConfigError(f"{path}: no frames to write")
    os.replace(partial, path)
    return path
