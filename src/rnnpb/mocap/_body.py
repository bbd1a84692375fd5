"""A captured person's hands, relative to their own body, on the standard user's body.

Any skeleton: the hands are the shallowest joints whose names say hand (or wrist) and a side
(``LeftHand``, ``Hand_L``, ``l_wrist``, ``mixamorig:RightHand`` …), or the two joints
``hands=(LEFT, RIGHT)`` names. Each arm's elbow is the hand's parent and its shoulder the
elbow's parent (joints at the same place as their parent — twist or helper joints — are
skipped).

From the motion, per file:

- the **up axis**: the file axis along which the shoulders sit highest above the root joint
  (or given: ``x``, ``y``, ``z``, ``-y`` …);
- the **facing**: the person's left is the mean horizontal direction from the right shoulder to
  the left one; forward is left × up (the file's axes are taken to be right-handed, as BVH's
  are);
- the **arm length**: shoulder to elbow plus elbow to hand (wrist), the median over frames;
  the **shoulder width**: the median distance between the two shoulders;
- the **units**: the first of metres, centimetres, millimetres and inches in which that arm
  length is a person's (0.25 to 1.2 m), or given.

Each hand is then taken relative to its own shoulder, turned into the robot's frame (the person
faces the robot: their forward is the robot's ``-x``, their left the robot's ``-y``), scaled by
``body.arm_reach / arm length`` and placed at the same shoulder of the standard user
(:class:`rnnpb.demonstrator.UserBody`), which is what the mirror mapping expects. So a child, a
tall adult and a motion-capture actor who make the same movement give the same hands, and the
units cancel out.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from rnnpb.demonstrator import UserBody
from rnnpb.errors import ConfigError, DataFileError

from ._bvh import Bvh

UNITS: dict[str, float] = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254}
"""Length units a file may be in, metres per unit, in the order they are tried."""
ARM_LENGTH_RANGE_M = (0.25, 1.2)
"""Shoulder-to-wrist lengths of people, from a small child to a very tall adult (metres)."""
UP_AXES = ("x", "y", "z", "-x", "-y", "-z")

_LEFT = {"l", "left", "lft"}
_RIGHT = {"r", "right", "rt", "rgt"}
_HAND = ("hand", "wrist")


@dataclass(frozen=True)
class BodyScale:
    """How a captured body was measured and put on the standard user's.

    Attributes
    ----------
    hands, elbows, shoulders : tuple of 2 str
        The joints used, (left, right).
    units : str
        One of :data:`UNITS`; ``units_detected`` says whether it was read from the body.
    up_axis : str
        The file's up axis (:data:`UP_AXES`); ``up_detected`` as for the units.
    arm_length_m, shoulder_width_m : float
        Measured, in metres.
    scale : float
        Standard arm reach / measured arm length: metres of the standard user per metre of
        the person.
    """

    hands: tuple[str, str]
    elbows: tuple[str, str]
    shoulders: tuple[str, str]
    units: str
    units_detected: bool
    up_axis: str
    up_detected: bool
    arm_length_m: float
    shoulder_width_m: float
    scale: float

    def to_json(self) -> dict:
        return {
            "hands": list(self.hands),
            "elbows": list(self.elbows),
            "shoulders": list(self.shoulders),
            "units": self.units,
            "units_detected": self.units_detected,
            "up_axis": self.up_axis,
            "up_detected": self.up_detected,
            "arm_length_m": round(self.arm_length_m, 4),
            "shoulder_width_m": round(self.shoulder_width_m, 4),
            "scale": round(self.scale, 4),
        }


def _words(name: str) -> list[str]:
    """``"mixamorig:LeftHand"`` → ``["mixamorig", "left", "hand"]``; ``"Hand_L"`` →
    ``["hand", "l"]``."""
    return [w.lower() for w in re.findall(r"[A-Z]+(?![a-z])|[A-Z]?[a-z]+|\d+", name)]


def _side(name: str) -> str | None:
    words = set(_words(name))
    left, right = bool(words & _LEFT), bool(words & _RIGHT)
    return "left" if left and not right else "right" if right and not left else None


def find_hands(bvh: Bvh, hands: tuple[str, str] | None = None) -> tuple[int, int]:
    """The left and right hand joints' indices (see the module doc)."""
    if hands is not None:
        found = (bvh.index(hands[0]), bvh.index(hands[1]))
        if found[0] == found[1]:
            raise ConfigError(f"--hands names the same joint twice ({hands[0]!r})")
        return found
    depth = [len(bvh.ancestors(i)) for i in range(len(bvh.joints))]
    out = []
    for side in ("left", "right"):
        for word in _HAND:
            candidates = [
                i
                for i, joint in enumerate(bvh.joints)
                if word in _words(joint.name) and _side(joint.name) == side
            ]
            if candidates:
                out.append(min(candidates, key=lambda i: depth[i]))
                break
        else:
            raise DataFileError(
                f"{bvh.path}: no joint named as the {side} hand (joints: "
                f"{', '.join(bvh.names)[:200]}); name them with --hands LEFT,RIGHT"
            )
    return out[0], out[1]


def _arm(bvh: Bvh, hand: int, positions: np.ndarray) -> tuple[int, int]:
    """(elbow, shoulder) of a hand: the next two ancestors not at the same place as their
    child."""
    chain, current = [], hand
    for ancestor in bvh.ancestors(hand):
        gap = np.median(np.linalg.norm(positions[:, ancestor] - positions[:, current], axis=-1))
        if gap > 1e-9:
            chain.append(ancestor)
            current = ancestor
            if len(chain) == 2:
                return chain[0], chain[1]
    raise DataFileError(
        f"{bvh.path}: joint {bvh.joints[hand].name!r} has no elbow and shoulder above it "
        "(is it a hand? name the hands with --hands LEFT,RIGHT)"
    )


def _up_vector(axis: str) -> np.ndarray:
    vector = np.zeros(3)
    vector["xyz".index(axis[-1])] = -1.0 if axis.startswith("-") else 1.0
    return vector


def body_hands(
    bvh: Bvh,
    *,
    hands: tuple[str, str] | None = None,
    units: str | None = None,
    up_axis: str | None = None,
    body: UserBody | None = None,
) -> tuple[np.ndarray, BodyScale]:
    """The person's hands on the standard user's body, robot frame, metres.

    Returns
    -------
    hands : array, shape (n_frames, 2, 3)
        Left hand (index 0), right hand (index 1) per frame.
    scale : BodyScale
        What was measured and chosen.
    """
    body = body or UserBody()
    if units is not None and units not in UNITS:
        raise ConfigError(f"units must be one of {', '.join(UNITS)}, got {units!r}")
    if up_axis is not None and up_axis not in UP_AXES:
        raise ConfigError(f"up axis must be one of {', '.join(UP_AXES)}, got {up_axis!r}")
    positions = bvh.world_positions()
    hand_index = find_hands(bvh, hands)
    arms = [_arm(bvh, h, positions) for h in hand_index]
    elbow_index = (arms[0][0], arms[1][0])
    shoulder_index = (arms[0][1], arms[1][1])
    hand_p = positions[:, list(hand_index)]
    elbow_p = positions[:, list(elbow_index)]
    shoulder_p = positions[:, list(shoulder_index)]
    arm_length = float(
        np.median(
            np.linalg.norm(elbow_p - shoulder_p, axis=-1)
            + np.linalg.norm(hand_p - elbow_p, axis=-1)
        )
    )
    shoulder_width = float(np.median(np.linalg.norm(shoulder_p[:, 0] - shoulder_p[:, 1], axis=-1)))
    if arm_length <= 0:
        raise DataFileError(f"{bvh.path}: the arms have no length")
    units_detected = units is None
    if units is None:
        low, high = ARM_LENGTH_RANGE_M
        units = next((u for u, m in UNITS.items() if low <= arm_length * m <= high), None)
        if units is None:
            raise DataFileError(
                f"{bvh.path}: an arm {arm_length:.4g} file units long is no person's in "
                f"{', '.join(UNITS)}; give the units with --units"
            )
    up_detected = up_axis is None
    if up_axis is None:
        rise = np.median(shoulder_p.mean(axis=1) - positions[:, 0], axis=0)
        k = int(np.argmax(np.abs(rise)))
        if abs(rise[k]) < 1e-9:
            raise DataFileError(
                f"{bvh.path}: the shoulders are not above the root joint; give --up-axis"
            )
        up_axis = ("-" if rise[k] < 0 else "") + "xyz"[k]
    up = _up_vector(up_axis)
    across = shoulder_p[:, 0] - shoulder_p[:, 1]
    across = across - np.outer(across @ up, up)
    left = across.mean(axis=0)
    if np.linalg.norm(left) < 1e-9 * max(shoulder_width, 1e-300):
        raise DataFileError(f"{bvh.path}: the shoulders are level on the up axis {up_axis}")
    left = left / np.linalg.norm(left)
    forward = np.cross(left, up)
    scale = body.arm_reach / arm_length
    relative = hand_p - shoulder_p
    # The person faces the robot: their forward is the robot's -x, their left the robot's -y.
    robot = np.stack([-(relative @ forward), -(relative @ left), relative @ up], axis=-1)
    out = body.shoulders + scale * robot
    metres = UNITS[units]
    names = bvh.names
    return out, BodyScale(
        hands=(names[hand_index[0]], names[hand_index[1]]),
        elbows=(names[elbow_index[0]], names[elbow_index[1]]),
        shoulders=(names[shoulder_index[0]], names[shoulder_index[1]]),
        units=units,
        units_detected=units_detected,
        up_axis=up_axis,
        up_detected=up_detected,
        arm_length_m=arm_length * metres,
        shoulder_width_m=shoulder_width * metres,
        scale=body.arm_reach / (arm_length * metres),
    )
