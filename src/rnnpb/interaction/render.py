"""A side-by-side video of a session: what the robot sees | what the robot does."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from rnnpb.robot.camera import RobotCamera

LEFT_BGR = (40, 40, 220)  # the user's left hand: red ball
RIGHT_BGR = (220, 90, 30)  # the user's right hand: blue ball


def partial_video_path(path: str | os.PathLike[str]) -> Path:
    """Where :class:`rnnpb.perception.VideoWriter` writes ``path`` until it is closed: a
    hidden file beside it, renamed to ``path`` once the video is complete."""
    path = Path(path)
    return path.with_name(f".{path.stem}.partial{path.suffix}")


class SessionVideo:
    """Subscribe ``add`` to an :class:`InteractionLoop`; each step becomes one video frame.

    Left: the camera frame (or, for sources without images, the camera's view plane) with the
    observed hands as filled discs and the network's prediction for them as rings; right: the
    simulated robot executing the motor command, rendered by MuJoCo.

    The video is written under a hidden partial name and renamed when the session ends,
    however it ends (the source ran out, Ctrl-C, SIGTERM, an error after some frames): then it
    is a complete, playable file. A process killed outright (SIGKILL, a power cut) cannot
    finish an MP4 and leaves the hidden partial behind; the next video written to the same
    path removes it first.
    """

    def __init__(
        self, path: str | os.PathLike[str], fps: float = 2.5, camera: RobotCamera | None = None
    ) -> None:
        from rnnpb.perception import VideoWriter
        from rnnpb.robot import RobotRenderer

        self.camera = camera or RobotCamera()
        self.path = Path(path)
        # What a killed run left: an MP4 without its index, which no player opens.
        partial_video_path(self.path).unlink(missing_ok=True)
        self._writer = VideoWriter(self.path, fps=fps)
        self._renderer = RobotRenderer(self.camera.width, self.camera.height)
        self._ok = False

    def add(self, record) -> None:
        import cv2

        if record.frame is not None:
            left = cv2.resize(record.frame, (self.camera.width, self.camera.height))
        else:
            left = np.full((self.camera.height, self.camera.width, 3), 245, np.uint8)
        for values, colour in ((record.observed[:2], LEFT_BGR), (record.observed[2:], RIGHT_BGR)):
            if np.all(np.isfinite(values)):
                x, y = self.camera.pixels_from_normalized(values)
                cv2.circle(left, (int(x), int(y)), 12, colour, -1, cv2.LINE_AA)
        for values, colour in ((record.predicted[:2], LEFT_BGR), (record.predicted[2:], RIGHT_BGR)):
            if np.all(np.isfinite(values)):
                x, y = self.camera.pixels_from_normalized(values)
                cv2.circle(left, (int(x), int(y)), 18, colour, 2, cv2.LINE_AA)
        cv2.putText(
            left,
            f"step {record.step}  seen (disc) / predicted (ring)",
            (10, 24),
            cv2.FONT_HERSHEY_SIMPLEX,
            0.6,
            (30, 30, 30),
            1,
            cv2.LINE_AA,
        )
        right = cv2.cvtColor(self._renderer.render(record.motor, camera="front"), cv2.COLOR_RGB2BGR)
        pb = " ".join(f"{v:.2f}" for v in record.pb)
        cv2.putText(
            right,
            f"robot   PB {pb}",
            (10, 24),
            cv2.FONT_HERSHEY_SIMPLEX,
            0.6,
            (30, 30, 30),
            1,
            cv2.LINE_AA,
        )
        self._writer.write(np.concatenate([left, right], axis=1))

    def __enter__(self) -> SessionVideo:
        return self

    def __exit__(self, exc_type, *rest) -> None:
        self._renderer.close()
        self._writer.close(keep=self._writer.frames_written > 0)
