"""``rnnpb cameras``: the cameras on this machine, so that a user need not guess ``webcam:N``."""

from __future__ import annotations

import argparse
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

NAME = "cameras"
HELP = "list the cameras present (index, resolution, frame rate) for --source webcam:N"
DESCRIPTION = """\
Probe the video devices of this machine with OpenCV, as LeRobot's camera finder does, and list
each camera that delivers a frame: its index (use it as `webcam:INDEX`), its device, the
resolution and the frame rate it reports. On Linux the candidates are /dev/video*; elsewhere
indices 0-9 are tried. A device that opens but gives no frame (a metadata node of a USB
camera) is left out.

Example:
  rnnpb cameras
  rnnpb interact --source webcam:0 --out run/ --paced
"""

#: Indices tried where there are no /dev/video* nodes to list (macOS, Windows).
FALLBACK_INDICES = range(10)


@dataclass(frozen=True)
class CameraInfo:
    """One camera found: ``index`` for ``webcam:INDEX``; ``device`` its path (or the index);
    ``width``, ``height`` pixels of the frame it delivered; ``fps`` the frame rate it reports
    (0 when it reports none)."""

    index: int
    device: str
    width: int
    height: int
    fps: float

    def describe(self) -> str:
        rate = f"{self.fps:g} frames/s" if self.fps > 0 else "frame rate not reported"
        return f"webcam:{self.index}  {self.device}  {self.width}x{self.height}, {rate}"


def candidate_devices() -> list[tuple[int, str]]:
    """(index, device) of each video device node, by index; indices 0-9 where the system has
    no /dev/video* nodes."""
    import re
    import sys
    from pathlib import Path

    if sys.platform.startswith("linux"):
        found = []
        for path in Path("/dev").glob("video*"):
            match = re.fullmatch(r"video(\d+)", path.name)
            if match:
                found.append((int(match.group(1)), str(path)))
        return sorted(found)
    return [(i, str(i)) for i in FALLBACK_INDICES]


def probe_cameras(
    devices: Iterable[tuple[int, str]], open_capture: Callable[[int], Any] | None = None
) -> list[CameraInfo]:
    """The devices that open and deliver a frame, with what they report.

    ``open_capture(index)`` returns an object with OpenCV's ``VideoCapture`` interface
    (``isOpened``, ``read``, ``get``, ``release``); by default ``cv2.VideoCapture``.
    """
    import cv2

    if open_capture is None:
        open_capture = cv2.VideoCapture
    cameras = []
    for index, device in devices:
        capture = open_capture(index)
        try:
            if not capture.isOpened():
                continue
            ok, frame = capture.read()
            if not ok or frame is None:
                continue
            height, width = frame.shape[:2]
            fps = float(capture.get(cv2.CAP_PROP_FPS) or 0.0)
            cameras.append(
                CameraInfo(
                    index, device, int(width), int(height), fps if fps > 0 and fps < 1e4 else 0.0
                )
            )
        finally:
            capture.release()
    return cameras


def add_arguments(parser: argparse.ArgumentParser) -> None:
    pass


def run(args: argparse.Namespace) -> int:
    import os

    # OpenCV's own complaints about devices that are not cameras go to its log, not the user.
    os.environ.setdefault("OPENCV_LOG_LEVEL", "ERROR")
    devices = candidate_devices()
    cameras = probe_cameras(devices)
    if not cameras:
        where = (
            f"none of {len(devices)} video device(s) delivered a frame"
            if devices
            else "no video devices (/dev/video*)"
        )
        print(
            f"no camera found: {where}. Without one, drive the robot with a video "
            "(--source video:FILE), the demonstrator (synthetic:1) or the dashboard "
            "(rnnpb serve)."
        )
        return 0
    print(f"{len(cameras)} camera(s):")
    for camera in cameras:
        print(f"  {camera.describe()}")
    return 0
