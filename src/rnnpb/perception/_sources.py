"""Camera sources: where the robot's frames come from.

Every source is a :class:`FrameSource`, a context manager with ``connect`` / ``read`` /
``close``; ``read`` returns the next BGR frame (uint8, shape (height, width, 3)) or ``None`` at
the end of the stream. A missing device or an unreadable file raises an
:class:`rnnpb.errors.RnnpbError` from ``connect``, quickly: a webcam's open and each of its
reads run under a timeout, so an unplugged or stuck camera cannot hang the robot.
"""

from __future__ import annotations

import math
import os
import queue
import re
import sys
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

import cv2
import numpy as np

from rnnpb.errors import DataFileError, RnnpbError

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp", ".ppm", ".pgm")
_T = TypeVar("_T")


class FrameSource:
    """Base class of camera sources.

    Attributes
    ----------
    description : str
        What this source reads (for messages).
    frame_index : int
        Index of the frame the last ``read`` returned (-1 before the first).
    last_truth : dict
        Ground truth of the last frame where the source knows it (synthetic camera), else ``{}``.
    """

    description = "camera source"

    def __init__(self) -> None:
        self.frame_index = -1
        self.last_truth: dict[str, Any] = {}

    def connect(self) -> None:
        """Open the device or file; raise :class:`RnnpbError` if it cannot be read."""

    def read(self) -> np.ndarray | None:
        """The next BGR frame, or ``None`` at the end of the stream."""
        raise NotImplementedError

    def close(self) -> None:
        """Release the device or file. Safe to call twice."""

    def __enter__(self) -> FrameSource:
        self.connect()
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def __iter__(self):
        while (frame := self.read()) is not None:
            yield frame


def _as_bgr(frame: np.ndarray) -> np.ndarray:
    if frame.ndim == 2:
        return cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR)
    if frame.shape[2] == 4:
        return cv2.cvtColor(frame, cv2.COLOR_BGRA2BGR)
    return frame


def _quiet_opencv() -> None:
    # OpenCV prints its own warnings for a device it cannot open; ours is the one message that
    # matters, so keep its log to errors.
    try:
        cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_ERROR)
    except AttributeError:  # pragma: no cover - older builds
        pass


def call_with_timeout(fn: Callable[[], _T], timeout_s: float, what: str) -> _T:
    """Run ``fn`` in a daemon thread; raise :class:`RnnpbError` if it takes over ``timeout_s``.

    A stuck driver call cannot be cancelled, but the daemon thread never keeps the program
    from exiting, and the caller gets a clear error instead of a hang.
    """
    box: queue.Queue = queue.Queue(maxsize=1)

    def worker() -> None:
        try:
            box.put((True, fn()))
        except BaseException as error:  # handed to the caller's thread
            box.put((False, error))

    threading.Thread(target=worker, name=f"rnnpb-{what}", daemon=True).start()
    try:
        ok, value = box.get(timeout=timeout_s)
    except queue.Empty:
        raise RnnpbError(f"{what}: no answer within {timeout_s:g} s") from None
    if not ok:
        raise value
    return value


class WebcamSource(FrameSource):
    """A camera device through ``cv2.VideoCapture(index)``.

    Parameters
    ----------
    index : int
        The device index (``/dev/videoINDEX`` on Linux).
    width, height : int, optional
        Requested capture size; the device may choose another.
    open_timeout_s, read_timeout_s : float
        Limits on opening the device and on each frame.
    """

    def __init__(
        self,
        index: int = 0,
        width: int | None = 640,
        height: int | None = 480,
        open_timeout_s: float = 5.0,
        read_timeout_s: float = 2.0,
    ) -> None:
        super().__init__()
        if index < 0:
            raise RnnpbError(f"webcam index must be >= 0, got {index}")
        self.index = index
        self.width, self.height = width, height
        self.open_timeout_s, self.read_timeout_s = open_timeout_s, read_timeout_s
        self.description = f"webcam {index}"
        self._capture: cv2.VideoCapture | None = None

    def connect(self) -> None:
        if self._capture is not None:
            return
        if sys.platform.startswith("linux") and not Path(f"/dev/video{self.index}").exists():
            raise RnnpbError(
                f"{self.description}: no such camera (/dev/video{self.index} does not exist)"
            )
        _quiet_opencv()

        def open_device() -> cv2.VideoCapture:
            capture = cv2.VideoCapture(self.index)
            if capture.isOpened():
                if self.width:
                    capture.set(cv2.CAP_PROP_FRAME_WIDTH, self.width)
                if self.height:
                    capture.set(cv2.CAP_PROP_FRAME_HEIGHT, self.height)
            return capture

        capture = call_with_timeout(open_device, self.open_timeout_s, f"opening {self.description}")
        if not capture.isOpened():
            capture.release()
            raise RnnpbError(
                f"{self.description}: cannot open the camera (missing, busy or not permitted)"
            )
        self._capture = capture

    def read(self) -> np.ndarray | None:
        if self._capture is None:
            raise RnnpbError(f"{self.description}: read before connect")
        capture = self._capture
        ok, frame = call_with_timeout(
            capture.read, self.read_timeout_s, f"reading {self.description}"
        )
        if not ok or frame is None:
            raise RnnpbError(f"{self.description}: the camera stopped delivering frames")
        self.frame_index += 1
        return _as_bgr(frame)

    def close(self) -> None:
        if self._capture is not None:
            self._capture.release()
            self._capture = None


def video_fps(path: str | os.PathLike[str]) -> float:
    """A video file's frame rate as recorded, 0 when it is unknown (or the file unreadable)."""
    _quiet_opencv()
    capture = cv2.VideoCapture(str(path))
    try:
        fps = float(capture.get(cv2.CAP_PROP_FPS)) if capture.isOpened() else 0.0
    finally:
        capture.release()
    return fps if math.isfinite(fps) and fps > 0 else 0.0


class VideoFileSource(FrameSource):
    """The frames of a video file (anything OpenCV's FFmpeg backend decodes)."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        super().__init__()
        self.path = Path(path)
        self.description = str(self.path)
        self._capture: cv2.VideoCapture | None = None
        self._first: np.ndarray | None = None

    def connect(self) -> None:
        if self._capture is not None:
            return
        if not self.path.exists():
            raise DataFileError(f"{self.path}: no such video file")
        if not self.path.is_file():
            raise DataFileError(f"{self.path}: is not a file, expected a video")
        _quiet_opencv()
        capture = cv2.VideoCapture(str(self.path))
        ok, frame = capture.read() if capture.isOpened() else (False, None)
        if not ok or frame is None:
            capture.release()
            raise DataFileError(
                f"{self.path}: cannot decode this file as a video (not a video, "
                "truncated, or a codec OpenCV lacks)"
            )
        self._capture, self._first = capture, _as_bgr(frame)

    @property
    def fps(self) -> float:
        """The file's frame rate as recorded (0 if unknown)."""
        return float(self._capture.get(cv2.CAP_PROP_FPS)) if self._capture is not None else 0.0

    def read(self) -> np.ndarray | None:
        if self._capture is None:
            raise RnnpbError(f"{self.description}: read before connect")
        if self._first is not None:
            frame, self._first = self._first, None
        else:
            ok, frame = self._capture.read()
            if not ok or frame is None:
                return None
            frame = _as_bgr(frame)
        self.frame_index += 1
        return frame

    def close(self) -> None:
        if self._capture is not None:
            self._capture.release()
            self._capture = None
        self._first = None


def _natural_key(path: Path) -> list:
    return [int(part) if part.isdigit() else part.lower() for part in re.split(r"(\d+)", path.name)]


class ImageFolderSource(FrameSource):
    """The images of a folder, in natural order of their names (``f2.png`` before ``f10.png``)."""

    def __init__(self, folder: str | os.PathLike[str]) -> None:
        super().__init__()
        self.folder = Path(folder)
        self.description = str(self.folder)
        self.files: list[Path] = []

    def connect(self) -> None:
        if not self.folder.is_dir():
            raise DataFileError(f"{self.folder}: no such folder of images")
        self.files = sorted(
            (
                p
                for p in self.folder.iterdir()
                if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES
            ),
            key=_natural_key,
        )
        if not self.files:
            raise DataFileError(f"{self.folder}: holds no images ({', '.join(IMAGE_SUFFIXES)})")

    def read(self) -> np.ndarray | None:
        if self.frame_index + 1 >= len(self.files):
            return None
        path = self.files[self.frame_index + 1]
        try:
            frame = cv2.imread(str(path), cv2.IMREAD_COLOR)
        except cv2.error as error:
            # OpenCV checks the size a header claims before decoding (at most 2^30 pixels,
            # CV_IO_MAX_IMAGE_PIXELS) and raises rather than returning None.
            reason = " ".join(str(error).split())
            if "CV_IO_MAX_IMAGE_PIXELS" in reason or "validateInputImageSize" in reason:
                reason = "its header claims more than 2^30 pixels"
            raise DataFileError(f"{path}: cannot read this image ({reason[:160]})") from None
        if frame is None:
            raise DataFileError(f"{path}: cannot read this image")
        self.frame_index += 1
        return frame


class ArraySource(FrameSource):
    """Frames from an array of shape (n_frames, height, width, 3) — the fake for tests."""

    def __init__(self, frames: np.ndarray, description: str = "frame array") -> None:
        super().__init__()
        self.frames = np.asarray(frames)
        if self.frames.ndim != 4 or self.frames.shape[3] != 3 or self.frames.dtype != np.uint8:
            raise RnnpbError(
                f"{description}: expected uint8 frames of shape (n, height, width, "
                f"3), got {self.frames.dtype} {self.frames.shape}"
            )
        self.description = description

    def read(self) -> np.ndarray | None:
        if self.frame_index + 1 >= len(self.frames):
            return None
        self.frame_index += 1
        return self.frames[self.frame_index]


class LimitedSource(FrameSource):
    """At most ``max_frames`` frames of another source."""

    def __init__(self, source: FrameSource, max_frames: int) -> None:
        super().__init__()
        self.source, self.max_frames = source, max_frames
        self.description = source.description

    def connect(self) -> None:
        self.source.connect()

    def read(self) -> np.ndarray | None:
        if self.frame_index + 1 >= self.max_frames:
            return None
        frame = self.source.read()
        if frame is not None:
            self.frame_index += 1
            self.last_truth = self.source.last_truth
        return frame

    def close(self) -> None:
        self.source.close()


def video_fourcc(path: str | os.PathLike[str]) -> str:
    """The codec rnnpb writes for a file name: ``mp4v`` for .mp4/.m4v/.mov, ``MJPG`` for .avi."""
    suffix = Path(path).suffix.lower()
    if suffix in (".mp4", ".m4v", ".mov"):
        return "mp4v"
    if suffix == ".avi":
        return "MJPG"
    raise RnnpbError(f"{path}: write videos as .mp4 (mp4v) or .avi (MJPG)")


class VideoWriter:
    """Writes BGR frames to a video file (``mp4v`` in .mp4, ``MJPG`` in .avi).

    The file is written under a temporary name and renamed when closed without error, so a
    failed run leaves no half-written video behind.
    """

    def __init__(self, path: str | os.PathLike[str], fps: float = 10.0) -> None:
        self.path = Path(path)
        self.fps = fps
        self.fourcc = video_fourcc(self.path)
        self._tmp = self.path.with_name(f".{self.path.stem}.partial{self.path.suffix}")
        self._writer: cv2.VideoWriter | None = None
        self.frames_written = 0

    def write(self, frame: np.ndarray) -> None:
        frame = np.ascontiguousarray(frame)
        if self._writer is None:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            height, width = frame.shape[:2]
            self._writer = cv2.VideoWriter(
                str(self._tmp), cv2.VideoWriter_fourcc(*self.fourcc), self.fps, (width, height)
            )
            if not self._writer.isOpened():
                self._writer = None
                raise RnnpbError(f"{self.path}: cannot write a {self.fourcc} video here")
        self._writer.write(frame)
        self.frames_written += 1

    def close(self, keep: bool = True) -> None:
        if self._writer is not None:
            self._writer.release()
            self._writer = None
        if keep and self.frames_written:
            os.replace(self._tmp, self.path)
        elif self._tmp.exists():
            self._tmp.unlink()

    def __enter__(self) -> VideoWriter:
        return self

    def __exit__(self, exc_type: object, *rest: object) -> None:
        self.close(keep=exc_type is None)
