"""The dashboard's webcam: which camera, how its frames become hands (coloured balls or bare
hands), the camera source while the webcam drives, and the image the page shows."""

from __future__ import annotations

import base64
from typing import Any

import numpy as np

from rnnpb.errors import RnnpbError
from rnnpb.sources import UserSource

FRAME_WIDTH = 320
"""Width (pixels) of the camera image sent to the page."""


class Webcam:
    """The camera ``index`` (for the next :meth:`open`) seen through ``perception``
    (``balls`` or ``pose``); ``source`` is the open camera source, None while closed.
    ``framing``: metres from the camera at which bare hands' body is placed — the running
    model's framing (:func:`rnnpb.learning_phase.placed_body`), so that a person is seen as
    the model learned people; None: the standard user's place."""

    def __init__(self) -> None:
        self.index = 0
        self.perception = "balls"
        self.framing: float | None = None
        self.source: UserSource | None = None

    @property
    def is_open(self) -> bool:
        return self.source is not None

    def open(self) -> UserSource:
        """Open camera ``index`` with the tracker ``perception`` names (a camera open before
        is closed once the new one works); a missing camera raises its reason."""
        from rnnpb.perception import PoseConfig, open_camera_source

        pose_config = None
        if self.perception == "pose" and self.framing is not None:
            from rnnpb.learning_phase import placed_body

            pose_config = PoseConfig(body=placed_body(self.framing))
        webcam = open_camera_source(
            "webcam", self.index, perception=self.perception, pose_config=pose_config
        )
        try:
            webcam.connect()
        except RnnpbError as error:
            webcam.close()
            raise RnnpbError(f"no camera: {error}") from None
        self.close()
        self.source = webcam
        return webcam

    def frame_for(self, framing: float) -> UserSource | None:
        """Bare hands framed at ``framing`` metres from now on (a model with another framing
        runs): an open pose camera is opened again with it (and kept as it was when that
        fails). Returns the camera source now open, if any."""
        if framing == self.framing:
            return self.source
        previous, self.framing = self.framing, framing
        if self.source is None or self.perception != "pose":
            return self.source
        try:
            return self.open()
        except RnnpbError:
            self.framing = previous
            raise

    def close(self) -> None:
        if self.source is not None:
            self.source.close()
            self.source = None

    def set_perception(self, perception: str) -> UserSource | None:
        """Balls or bare hands; an open camera is opened again with the new tracker (and kept
        as it was when that fails). Returns the camera source now open, if any."""
        if perception == self.perception:
            return self.source
        from rnnpb.perception import HANDS_INSTALL, pose_available

        if perception == "pose" and not pose_available():
            raise RnnpbError(f"bare hands need the pose model: {HANDS_INSTALL}")
        previous, self.perception = self.perception, perception
        if self.source is None:
            return None
        try:
            return self.open()
        except RnnpbError:
            self.perception = previous
            raise

    def _tracked(self) -> Any:
        return getattr(self.source, "last_result", None)

    def hands_3d(self) -> np.ndarray | None:
        """The last frame's hands in 3-D (from the balls' size), None while closed or
        before a frame was tracked."""
        result = self._tracked()
        return None if result is None else result.hands_3d

    def frame_message(self, frame: np.ndarray) -> dict[str, Any] | None:
        """The ``frame`` message: the camera image, :data:`FRAME_WIDTH` wide, with the tracked
        hands drawn, as JPEG (None when it cannot be encoded)."""
        import cv2

        from rnnpb.perception import draw_tracking

        result = self._tracked()
        image = draw_tracking(frame, result) if result is not None else frame
        height = int(round(image.shape[0] * FRAME_WIDTH / image.shape[1]))
        image = cv2.resize(image, (FRAME_WIDTH, height), interpolation=cv2.INTER_AREA)
        ok, jpeg = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 70])
        if not ok:
            return None
        return {"type": "frame", "jpeg": base64.b64encode(jpeg.tobytes()).decode("ascii")}
