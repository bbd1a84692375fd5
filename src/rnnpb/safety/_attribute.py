"""Every unsafe command has a cause: the seen movement or the network's generation.

While the robot imitates, its command follows the person's hands; when the posture those
hands ask for already puts an arm through the body (or asks a joint to move faster than its
servo), the unsafe command comes from the seen movement — the retargeting's and the command
filter's job. Otherwise the network generated it on its own — the meta-level's job.

The posture the hands ask for is the demonstrator's mirror mapping
(:class:`rnnpb.demonstrator.MirrorMapping`): the view-plane hands (``lhy lhz rhy rhz``) are
taken back along the camera's rays to the plane the user's hands move in
(``UserBody.hand_depth``), mirrored onto the robot's shoulders and solved by the paper's
inverse kinematics (:func:`rnnpb.robot.inverse_kinematics`) — without the safe retargeting,
which would make every posture safe.
"""

from __future__ import annotations

import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.robot import RobotCamera, inverse_kinematics
from rnnpb.safety._check import SafetyChecker

SEEN = "seen movement"
GENERATION = "generation"


def asked_posture(hands: np.ndarray) -> np.ndarray:
    """The joint angles (..., 8) the view-plane hands (..., 4) ask for; NaN where a hand
    was not seen."""
    from rnnpb.demonstrator import MirrorMapping, UserBody

    hands = np.asarray(hands, dtype=np.float64)
    if hands.shape[-1:] != (4,):
        raise ConfigError(f"hands must have shape (..., 4) (lhy lhz rhy rhz), got {hands.shape}")
    camera = RobotCamera()
    pixels = camera.pixels_from_normalized(hands.reshape(*hands.shape[:-1], 2, 2))
    origin = np.asarray(camera.position)
    direction = camera.back_project(pixels, np.ones(pixels.shape[:-1])) - origin
    with np.errstate(divide="ignore", invalid="ignore"):
        reach = (UserBody().hand_depth - origin[0]) / direction[..., 0]
    user_hands = origin + reach[..., None] * direction
    seen = np.isfinite(user_hands).all(axis=(-1, -2))
    targets = MirrorMapping().robot_hand_targets(np.where(seen[..., None, None], user_hands, 0.0))
    joints = inverse_kinematics(targets).joints
    return np.where(seen[..., None], joints, np.nan)


class Attribution:
    """Says whether a step's unsafe command came from the seen movement or the generation.

    Call :meth:`asks_unsafe` and :meth:`attribute` with each step's hands in order: the
    posture asked for at the step before is what a speed check is against.
    """

    def __init__(self, checker: SafetyChecker | None = None) -> None:
        self.checker = checker or SafetyChecker()
        self._previous: np.ndarray | None = None

    def reset(self) -> None:
        self._previous = None

    def asks_unsafe(self, hands: np.ndarray, posture: np.ndarray | None = None) -> str:
        """Why the posture the hands ask for is unsafe (a collision at it or on the way
        from the one asked before, or faster than a servo), ``""`` when it is safe or a hand
        was not seen. ``posture``: :func:`asked_posture` of ``hands`` when already known."""
        posture = asked_posture(hands) if posture is None else np.asarray(posture, float)
        previous, self._previous = self._previous, None
        if not np.isfinite(posture).all():
            return ""
        self._previous = posture
        reasons = self.checker.command_reasons(previous, posture)
        return " ".join(w for w in reasons if w.split(":")[0] in ("collision", "speed"))

    def attribute(self, hands: np.ndarray, unsafe: str) -> str:
        """The cause of a step's command, given why it was unsafe (``unsafe``, the filter's
        words; empty when safe): ``""`` for a safe command, :data:`SEEN` when the hands ask
        for an unsafe posture themselves, else :data:`GENERATION`."""
        return self._cause(self.asks_unsafe(hands), unsafe)

    def attribute_sequence(self, hands: np.ndarray, unsafe: list[str]) -> list[str]:
        """:meth:`attribute` for each step of ``hands`` (T, 4) and ``unsafe`` (T,) in turn;
        the postures asked for are solved in one call (much faster than step by step)."""
        postures = asked_posture(hands)
        return [
            self._cause(self.asks_unsafe(u, posture), why)
            for u, posture, why in zip(hands, postures, unsafe, strict=True)
        ]

    @staticmethod
    def _cause(asked: str, unsafe: str) -> str:
        if not any(w.split(":")[0] in ("collision", "speed") for w in unsafe.split()):
            return ""
        return SEEN if asked else GENERATION
