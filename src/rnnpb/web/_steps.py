"""The ``step`` message the session publishes for every step of the loop
(docs/dashboard.md, "Message protocol"), and where the person's hands are in 3-D for the
page's view."""

from __future__ import annotations

import math
from typing import Any

import numpy as np


def listed(values) -> list[float | None]:
    """``values`` as a JSON list: NaN and infinities become ``null``."""
    return [float(v) if math.isfinite(v) else None for v in np.asarray(values, float).ravel()]


class UserView:
    """Where the person's hands are in 3-D, from the view-plane values the robot perceives:
    back-projected through the robot's camera at the depth of the demonstrator's hands (the
    sensory vector has no depth), so the 3-D view can show the person in front of the robot."""

    def __init__(self) -> None:
        from rnnpb.demonstrator import UserBody
        from rnnpb.robot.camera import RobotCamera

        self.camera = RobotCamera()
        centres = UserBody().hand_centres
        self.depth = float(self.camera.camera_coordinates(centres)[:, 2].mean())
        self.rest = self.camera.sensory_from_hands(centres)

    def hands(self, sensory: np.ndarray) -> list[list[float] | None]:
        yz = np.asarray(sensory, dtype=np.float64).reshape(2, 2)
        out: list[list[float] | None] = []
        for hand in yz:
            if not np.all(np.isfinite(hand)):
                out.append(None)
                continue
            pixel = self.camera.pixels_from_normalized(hand)
            point = self.camera.back_project(pixel, np.array(self.depth))
            out.append(np.round(point, 4).tolist())
        return out


def step_message(record, *, model, loop, mode: str, dt: float, view: UserView) -> dict[str, Any]:
    """What the page shows of one step (``record``, a :class:`~rnnpb.interaction.StepRecord`
    of ``loop`` running ``model``): the hands seen and predicted, the command and the arms'
    pose, the PB and what was recognised, the timings, and the safety filter's doing. The
    caller adds teaching's and the routine level's fields."""
    from rnnpb.robot import forward_kinematics

    hands, elbows = forward_kinematics(record.motor)
    nearest, distance = model.nearest_pattern(record.pb)
    return {
        "type": "step",
        "step": record.step,
        "time_s": round(record.time_s, 4),
        "mode": mode,
        "observed": listed(record.observed),
        "predicted": listed(record.predicted),
        "predicted_next": listed(record.predicted_next),
        "motor": listed(record.motor),
        "pb": listed(record.pb),
        "nearest": nearest,
        "nearest_distance": distance,
        # What the step recognised (rnnpb.model.recognition): the readout says "not sure" or
        # "new movement" rather than a confident wrong name.
        "recognised": record.recognised,
        "confidence": round(float(record.confidence), 4),
        "novelty": record.novelty,
        "pattern_confidence": {k: round(float(v), 4) for k, v in record.pattern_confidence.items()},
        "prediction_error": listed([record.prediction_error])[0],
        "window_error": listed([record.window_error])[0],
        "held": record.held,
        "truth": str(record.truth.get("pattern", "")),
        "dt": dt,
        "user_hands": view.hands(record.observed),
        "arms": {"elbows": np.round(elbows, 5).tolist(), "hands": np.round(hands, 5).tolist()},
        "timings_ms": {k: round(v * 1e3, 3) for k, v in record.timings.items()},
        "missed_deadlines": loop.missed_deadlines if loop is not None else 0,
        # Why the generated command was unsafe (empty when safe), what the filter did, and
        # how many commands it has changed this run; what drove the motion (``regime``) and
        # why the meta-level held the command (``inhibited``, empty when sent), and how many
        # it has held this run.
        "unsafe": record.unsafe,
        "filtered": record.filtered,
        "prevented": loop.prevented_commands if loop is not None else 0,
        "regime": record.regime,
        "inhibited": record.inhibited,
        "inhibited_count": loop.inhibited_commands if loop is not None else 0,
    }
