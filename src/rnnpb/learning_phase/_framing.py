"""Framing: where the person stands in the robot camera's view.

Every source of a person's hands that knows the person's body (motion capture, the pose model)
expresses the hands relative to that body and puts them on the standard user
(:class:`rnnpb.demonstrator.UserBody`): shoulders 0.95 m high and 0.38 m apart, an arm 0.62 m
long. The *framing* is how far from the robot that standard body stands: the sensory values are
where the robot's head camera sees its hands there. At the standard user's place (1 m, where the
demonstrator stands) hands raised above the head or spread wide leave the camera's view, which
is low (0.52 m) and 60° high; further back the whole reach fits, smaller.

The learning phase frames a person by their whole reach (``framing="reach"``, the default):
the nearest distance at which every point an arm of the standard body can reach lies inside the
view with a margin of :data:`MARGIN` (:func:`reach_distance`: 1.55 m for the robot's camera).
Every person, whatever their size and whatever they recorded, is so framed alike, and a model
learned from several recordings sees all of them the same way. ``framing="fit"`` takes instead
the nearest distance at which this recording's hands lie inside the view (from the standard 1 m
back in steps of 5 cm): a small movement is then seen larger; a number gives the distance. A
hand still outside the view (a framing given or fitted to less than the person reached) is
*framed*: put on the edge of the view, and counted. The joint angles do not depend on the
framing (the mirror mapping scales the standard body's reach to the robot's wherever it
stands), only what the camera sees does; a model keeps the framing it learned with, and a
person it then watches is framed the same way (docs/design.md, "Framing").

Sources that do not know the body (coloured balls, the mouse, a sensory file) are framed by the
camera itself: their values are where they were seen.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from rnnpb.demonstrator import UserBody
from rnnpb.errors import ConfigError
from rnnpb.robot.camera import RobotCamera

STANDARD_DISTANCE = UserBody().distance
"""Metres: the standard user's place, where the demonstrator's data are framed."""
MAX_DISTANCE = 3.0
"""Metres: the farthest framing; beyond it a person's movement is a few pixels."""
DISTANCE_STEP = 0.05
"""Metres between the framings tried: fine against the view's change per step (about 4 %)."""
MARGIN = 0.02
"""Share of the view kept free around the hands: a person's next movement may reach a little
further than the recording's."""


def placed_body(distance: float) -> UserBody:
    """The standard user with the shoulders ``distance`` metres from the robot (the plane the
    hands move in stays in front of them)."""
    if not (math.isfinite(distance) and 0.5 <= distance <= MAX_DISTANCE):
        raise ConfigError(f"a framing must be from 0.5 to {MAX_DISTANCE:g} m, got {distance}")
    standard = UserBody()
    return UserBody(distance=distance, hand_depth=min(standard.hand_depth, 0.9 * distance))


def hands_at(hands: np.ndarray, distance: float) -> np.ndarray:
    """Hands on the standard body at :data:`STANDARD_DISTANCE` (..., 2, 3), moved with it to
    ``distance`` metres from the robot."""
    return np.asarray(hands, dtype=np.float64) + np.array([distance - STANDARD_DISTANCE, 0, 0])


@dataclass(frozen=True)
class Framing:
    """A recording's framing.

    Attributes
    ----------
    distance : float or None
        Metres from the robot to the standard body's shoulders; None: the camera's own view
        (a source that does not know the body).
    chosen : bool
        Chosen from the recording (not given).
    framed_steps : int
        Steps on which a hand lay outside the view and was put on its edge.
    """

    distance: float | None
    rule: str = "given"
    framed_steps: int = 0

    def describe(self) -> str:
        if self.distance is None:
            return "framed by the camera (the values are where the hands were seen)"
        how = {
            "reach": "the whole reach of the body in view",
            "fit": "the nearest that keeps this recording in view",
        }.get(self.rule, "given")
        words = f"the person framed at {self.distance:.2f} m ({how})"
        if self.framed_steps:
            words += f"; a hand outside the view on {self.framed_steps} steps was put on its edge"
        return words

    def to_json(self) -> dict:
        return {
            "distance_m": None if self.distance is None else round(self.distance, 4),
            "rule": self.rule,
            "framed_steps": self.framed_steps,
        }


FRAMINGS = ("reach", "fit")
"""The framings chosen by rule: the whole reach of the body, or fitted to the recording."""


@functools.cache
def reach_distance(camera: RobotCamera | None = None, margin: float = MARGIN) -> float:
    """The nearest framing (a multiple of :data:`DISTANCE_STEP` from the standard 1 m) at which
    every point within an arm's reach of either shoulder of the standard body lies inside the
    camera's view with ``margin``."""
    camera = camera or RobotCamera()
    body = UserBody()
    # Points on the sphere of the arm's reach about each shoulder (a Fibonacci lattice).
    count = 4000
    index = np.arange(count) + 0.5
    polar = np.arccos(1 - 2 * index / count)
    azimuth = np.pi * (1 + 5**0.5) * index
    sphere = np.stack(
        [np.cos(azimuth) * np.sin(polar), np.sin(azimuth) * np.sin(polar), np.cos(polar)], axis=1
    )
    hands = np.stack([shoulder + body.arm_reach * sphere for shoulder in body.shoulders], axis=1)
    found = choose_distance(lambda d: projected(hands, d, camera), margin=margin)
    return MAX_DISTANCE if found is None else found


def _in_view(sensory: np.ndarray, margin: float) -> bool:
    seen = sensory[np.isfinite(sensory)]
    return bool(np.all((seen >= margin) & (seen <= 1 - margin)))


def choose_distance(sensory_at, margin: float = MARGIN) -> float | None:
    """The nearest framing from the standard 1 m back, in steps of :data:`DISTANCE_STEP`, at
    which ``sensory_at(distance)`` — sensory values (n, 4) with the standard body there — lie
    inside the view with ``margin``; None when none up to :data:`MAX_DISTANCE` does."""
    count = int(round((MAX_DISTANCE - STANDARD_DISTANCE) / DISTANCE_STEP))
    for i in range(count + 1):
        distance = round(STANDARD_DISTANCE + i * DISTANCE_STEP, 4)
        if _in_view(sensory_at(distance), margin):
            return distance
    return None


def framed(sensory: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sensory values (n, 4) with every value outside [0, 1] put on the view's edge, and the
    steps (n,) where one was."""
    sensory = np.asarray(sensory, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        outside = np.asarray(((sensory < 0) | (sensory > 1)).any(axis=1))
    return np.clip(sensory, 0.0, 1.0), outside


def projected(hands: np.ndarray, distance: float, camera: RobotCamera | None = None) -> np.ndarray:
    """What the robot's camera sees of hands on the standard body (n, 2, 3) when that body
    stands ``distance`` metres away: sensory values (n, 4), outside [0, 1] where a hand is out
    of view."""
    return (camera or RobotCamera()).sensory_from_hands(hands_at(hands, distance))


def resolve(
    framing: float | str, sensory_at, camera: RobotCamera | None = None
) -> tuple[float, str]:
    """The distance a framing names (``"reach"``, ``"fit"`` or metres) for a recording whose
    sensory values at a distance are ``sensory_at(distance)``, and the rule that gave it."""
    camera = camera or RobotCamera()
    if framing == "reach":
        return reach_distance(camera), "reach"
    if framing == "fit":
        found = choose_distance(sensory_at)
        return (MAX_DISTANCE if found is None else found), "fit"
    if isinstance(framing, str):
        raise ConfigError(f"--framing must be reach, fit or metres, got {framing!r}")
    placed_body(float(framing))  # checks the range
    return float(framing), "given"


def frame_hands(
    hands: np.ndarray,
    framing: float | str = "reach",
    camera: RobotCamera | None = None,
) -> tuple[np.ndarray, Framing]:
    """Frame 3-D hands on the standard body (n, 2, 3) (motion capture): the sensory values (n,
    4), NaN where a hand is not known, and the framing (module doc)."""
    camera = camera or RobotCamera()
    distance, rule = resolve(framing, lambda d: projected(hands, d, camera), camera)
    sensory, outside = framed(projected(hands, distance, camera))
    return sensory, Framing(distance, rule, int(outside.sum()))
