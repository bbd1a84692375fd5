"""From the user's hands to the robot's joints: a mirror image, scaled, then inverse kinematics.

The robot imitates the user like a mirror: the user's LEFT hand, which the robot sees on its
right, drives the robot's RIGHT arm. Each hand's position relative to the user's shoulder on
the same side is reflected through the plane between user and robot (``x`` flips, ``y`` and
``z`` stay), scaled by ``robot reach / human reach`` and placed at the robot's shoulder::

    robot_hand[right] = robot_shoulder[right] + scale * diag(-1, 1, 1) (user_hand[left]
                                                                  - user_shoulder[left])

The joint angles come from the safe retargeting (:func:`rnnpb.robot.retarget`): the paper's
inverse kinematics where its posture is safe, else the closest posture that keeps the robot's
parts clear of its own body, inside the joint limits and the servo's speed per step.

Why a mirror: a person facing a partner expects the partner's movement to appear on the same
side of the view (a hand raised on my left is answered on my left); it is also what makes the
paper's opposite-phase / in-phase patterns keep their names on the robot's side. Both arms use
mirror-symmetric joint senses, so a symmetric user pose gives equal angles on both robot arms.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.robot import FOREARM_LENGTH, SHOULDERS, UPPER_ARM_LENGTH, Retargeted, retarget

from ._user import UserBody

_REFLECT_X = np.array([-1.0, 1.0, 1.0])


@dataclass(frozen=True)
class MirrorMapping:
    """Maps the user's 3-D hands to the robot's hand targets and joint angles.

    Attributes
    ----------
    body : UserBody
        The user (its shoulders are the origin of each hand's movement).
    scale : float or None
        Robot hand displacement per metre of user hand displacement; None: the ratio of the
        robot's arm reach to the user's (``(L1 + L2) / body.arm_reach``).
    dt : float
        Seconds per step of the joint angles made: a joint moves at most the servo's speed
        times ``dt`` from one step to the next (0.4 s, the paper's step).
    """

    body: UserBody = field(default_factory=UserBody)
    scale: float | None = None
    dt: float = 0.4

    def __post_init__(self) -> None:
        if self.scale is not None and not 0.0 < self.scale <= 2.0:
            raise ConfigError(f"mirror mapping scale must be in (0, 2], got {self.scale}")
        if not self.dt > 0:
            raise ConfigError(f"mirror mapping dt must be > 0, got {self.dt}")

    @property
    def effective_scale(self) -> float:
        if self.scale is not None:
            return float(self.scale)
        return (UPPER_ARM_LENGTH + FOREARM_LENGTH) / self.body.arm_reach

    def robot_hand_targets(self, hands: np.ndarray) -> np.ndarray:
        """User hands (..., 2, 3) [left, right] → robot hand targets (..., 2, 3) [left, right]."""
        hands = np.asarray(hands, dtype=np.float64)
        relative = (hands - self.body.shoulders) * _REFLECT_X * self.effective_scale
        # The user's right hand (index 1, on the robot's left, +y) drives the robot's left arm.
        return SHOULDERS + relative[..., ::-1, :]

    def retarget(self, hands: np.ndarray, previous: np.ndarray | None = None) -> Retargeted:
        """User hands (n, 2, 3), one row per step, → the robot's safe joint angles
        (:func:`rnnpb.robot.retarget`); ``previous`` (8,) is the robot's posture before the
        first step, if known. NaN hands give NaN angles."""
        return retarget(self.robot_hand_targets(hands), self.dt, previous)

    def motor_from_hands(self, hands: np.ndarray) -> np.ndarray:
        """User hands (n, 2, 3) → robot joint angles (n, 8), radians (:meth:`retarget`)."""
        return self.retarget(hands).joints
