"""The robot's own geometry as a safety question: does a pose put an arm through the torso, the
head or the other arm, and is a step faster than the servos can move?

The simulated robot's parts do not collide (``humanoid.xml``: contype 0, the arms move in free
space as in the paper, and rendering is unchanged). For the safety checks a second, query-only
copy of the model adds explicit contact pairs between each arm and the body and between the
arms; :class:`SelfCollision` sets a pose, runs ``mj_kinematics`` and ``mj_collision`` on that
copy and reads the penetration of each pair. No physics is stepped.

The speed limit comes from a real small-humanoid servo: the Robotis Dynamixel AX-12A (the
servo of the Bioloid humanoids), whose e-Manual gives a no-load speed of 59 rev/min at 12 V,
i.e. 0.169 s per 60 degrees, 6.18 rad/s. One network step may move a joint by at most
that speed times ``dt`` (:func:`joint_step_limit`); a command asking for more is one the servo
could not follow.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from rnnpb.robot._gl import import_mujoco
from rnnpb.robot._interface import as_joint_vector
from rnnpb.robot._kinematics import clip_to_limits
from rnnpb.robot._mujoco import joint_addresses, model_xml

if TYPE_CHECKING:
    import mujoco

SERVO_NAME = "Robotis Dynamixel AX-12A"
SERVO_NO_LOAD_SPEED = 59.0 * 2.0 * math.pi / 60.0
"""No-load speed of the AX-12A, rad/s (e-Manual: 59 rev/min at 12 V = 0.169 s/60 deg)."""

# Each arm's moving parts (left, right), and the body they must not pass through. The shoulder
# ball sits in the chest's corner by design and the upper arm hangs along the chest's side, so
# the upper arm counts against the head and the other arm only.
_ARM_PARTS = {
    "left": ("lupper_arm_geom", "lelbow_geom", "lforearm_geom", "lhand_geom"),
    "right": ("rupper_arm_geom", "relbow_geom", "rforearm_geom", "rhand_geom"),
}
_DISTAL = {
    "left": ("lelbow_geom", "lforearm_geom", "lhand_geom"),
    "right": ("relbow_geom", "rforearm_geom", "rhand_geom"),
}
_BODY = ("chest", "pelvis", "left_leg", "right_leg", "neck", "head_geom", "visor")
_HEAD = ("neck", "head_geom", "visor")

COLLISION_DEPTH = 0.008
"""Penetration (metres) beyond which two parts count as passing through each other: the
capsules are the shells' outlines, and a few millimetres of touching (a straight arm's hand
against the hip reaches 6 mm) is contact, not a hand inside the torso."""


_QUERY_MARGIN = 0.02
"""Pairs closer than this (metres) are reported by the query model's collision pass."""


def collision_pairs() -> tuple[tuple[str, str], ...]:
    """The geom pairs checked: each arm's elbow, forearm and hand against the body, each upper
    arm against the head, and every part of one arm against every part of the other."""
    pairs: list[tuple[str, str]] = []
    for side in ("left", "right"):
        pairs += [(part, body) for part in _DISTAL[side] for body in _BODY]
        pairs += [(_ARM_PARTS[side][0], head) for head in _HEAD]
    pairs += [(a, b) for a in _ARM_PARTS["left"] for b in _ARM_PARTS["right"]]
    return tuple(pairs)


def joint_step_limit(dt: float, speed: float = SERVO_NO_LOAD_SPEED) -> float:
    """The largest change of one joint angle (radians) in one network step of ``dt`` seconds
    that the servo (``speed`` rad/s, default the AX-12A's no-load speed) can make."""
    return float(speed * dt)


def _query_xml() -> str:
    root = ET.fromstring(model_xml())
    contact = ET.SubElement(root, "contact")
    for a, b in collision_pairs():
        ET.SubElement(contact, "pair", {"geom1": a, "geom2": b, "margin": str(_QUERY_MARGIN)})
    return ET.tostring(root, encoding="unicode")


@dataclass(frozen=True)
class Contact:
    """One pair of the robot's parts in contact: their geom names and the penetration depth
    (metres, > 0 inside each other)."""

    part: str
    other: str
    depth: float


class SelfCollision:
    """Self-collision queries on the humanoid's own geometry (a query-only MuJoCo model).

    >>> collisions = SelfCollision()              # doctest: +SKIP
    >>> collisions.contacts(joints)               # doctest: +SKIP
    """

    def __init__(self, depth: float = COLLISION_DEPTH) -> None:
        mj = import_mujoco()
        self._mj = mj
        self.model: mujoco.MjModel = mj.MjModel.from_xml_string(_query_xml())
        self.data: mujoco.MjData = mj.MjData(self.model)
        self._qadr = joint_addresses(self.model)
        self.depth = float(depth)

    def penetrations(self, joints: np.ndarray) -> list[Contact]:
        """Every checked pair closer than the margin at ``joints`` (8,) radians, with its
        penetration depth (negative: apart)."""
        joints = clip_to_limits(as_joint_vector(joints))
        self.data.qpos[self._qadr] = joints
        self._mj.mj_kinematics(self.model, self.data)
        self._mj.mj_collision(self.model, self.data)
        found = []
        for i in range(self.data.ncon):
            c = self.data.contact[i]
            found.append(
                Contact(
                    self.model.geom(int(c.geom1)).name,
                    self.model.geom(int(c.geom2)).name,
                    float(-c.dist),
                )
            )
        return found

    def clearance(self, joints: np.ndarray) -> float:
        """Smallest distance (metres) between the checked pairs at ``joints`` (8,) radians;
        negative when two parts are inside each other, and 0.02 (the query margin) when every
        pair is at least that far apart."""
        self.data.qpos[self._qadr] = clip_to_limits(as_joint_vector(joints))
        self._mj.mj_kinematics(self.model, self.data)
        self._mj.mj_collision(self.model, self.data)
        if self.data.ncon == 0:
            return _QUERY_MARGIN
        return float(min(_QUERY_MARGIN, np.min(self.data.contact.dist[: self.data.ncon])))

    def contacts(self, joints: np.ndarray) -> list[Contact]:
        """The pairs passing through each other (deeper than ``depth``) at ``joints``."""
        return [c for c in self.penetrations(joints) if c.depth > self.depth]

    def collides(self, joints: np.ndarray) -> bool:
        return bool(self.contacts(joints))

    def first_contact(self, joints: np.ndarray) -> str:
        """``"part-other"`` of the deepest collision at ``joints``, or ``""`` when none."""
        hits = self.contacts(joints)
        if not hits:
            return ""
        deepest = max(hits, key=lambda c: c.depth)
        return f"{deepest.part}-{deepest.other}"
