"""Judges of the robot's movement that share nothing with the code they judge.

The safety module decides what is unsafe (:class:`rnnpb.safety.SafetyChecker`: its own list of
checked pairs on a query copy of the model, its clearance, its speed limit). A study's figure
that says "0 colliding steps" is only as good as that decision, so these judges answer the same
questions from the robot's model alone, each by another route:

- :class:`CollisionJudge`: MuJoCo's own contact detection on the humanoid's MJCF (``humanoid.xml``)
  with every robot part made collidable. It sets the joint angles in an ``MjData``, runs
  ``mj_forward`` and reads ``data.contact[:data.ncon]``: every pair of geoms of *different*
  bodies that MuJoCo finds, except the pairs that touch by construction (below). A contact
  counts as a collision when the two parts are more than :data:`PASS_THROUGH_DEPTH` (8 mm)
  inside each other: capsules and spheres are the shells' outlines, and a few millimetres of
  touching is contact, not an arm through the body (the same clearance semantics as the
  safety module's, written down here, not imported). A path is judged at its postures and at
  :attr:`CollisionJudge.path_points` postures on the straight joint-space way from each step to
  the next (the servos' ramp).
- :func:`judge_speed`: the largest change of any joint from one step to the next against the
  servo's reach in one step: the no-load speed of the robot's servo (``rnnpb.robot``'s
  documented constant, the Dynamixel AX-12A's 59 rev/min; the MJCF holds no speed) times the
  step's ``dt``, computed here.
- :func:`judge_limits`: joint angles outside the ranges the MJCF gives its joints.
- :func:`judge_reach`: the hands' positions by MuJoCo's forward kinematics (the MJCF's
  ``left_hand`` and ``right_hand`` sites after ``mj_forward``), not ``rnnpb.robot``'s
  kinematics, against the positions asked for.

Each returns its counts and the offending steps.

**What touches by construction, and is not counted.** Looked at in the model at rest (every
joint 0, the arms hanging; the MuJoCo robot's rest with the elbows at 1.4 rad; the
retargeting's start posture), with every part collidable:

- MuJoCo's own filters: two geoms of one body, and a body's geoms against its parent's (the
  upper arm against the shoulder ball, the forearm, elbow and hand against the upper arm, the
  head against the torso) are never tested.
- The shoulder ball (``lshoulder_geom``, ``rshoulder_geom``) against the torso: the joint's
  housing sits 8 mm inside the chest's corner at every posture (a ball on the joint's axis does
  not move when the shoulder turns). Excluded (:data:`EXCLUDED_BODY_PAIRS`).
- Not excluded, because they stay within the clearance at rest: the upper arm along the
  chest's side (2 mm), the hanging hand against the hip (6 mm against the leg, 4 mm against the
  pelvis). They count when a posture pushes them deeper.

The floor and the user's hand balls are not robot parts: they never collide here.

**Where the judge and the safety checker differ** (tests/analysis/test_judges.py, 400 postures
drawn uniformly within the joint limits, seed 2026: they agree on 379, 94.75 %): the checker
tests the upper arm against the head and the other arm only, as it hangs along the chest's
side; the judge tests it against the whole body, and a shoulder rolled across the body (roll
between about -0.07 and the limit -0.25 rad, at any pitch) puts the upper arm 8-19 mm into the
chest's side, just past the clearance. Every disagreement of that sample is that pair, found by
the judge alone; the checker finds nothing the judge does not. The demonstrator's learning
data passes both.
"""

from __future__ import annotations

import sys
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from importlib import resources
from typing import TYPE_CHECKING, Any

import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.robot import SERVO_NAME, SERVO_NO_LOAD_SPEED, choose_gl
from rnnpb.vectors import MOTOR_NAMES, MOTOR_SIZE

if TYPE_CHECKING:
    import mujoco

PASS_THROUGH_DEPTH = 0.008
"""Metres two parts must be inside each other for a contact to count as a collision."""

PATH_POINTS = 3
"""Postures judged on the way from one step to the next, besides the step's own."""

EXCLUDED_BODY_PAIRS = (("torso", "left_shoulder_roll"), ("torso", "right_shoulder_roll"))
"""Body pairs whose contact is the robot's construction: each shoulder's joint housing in the
chest's corner (module docstring)."""

NOT_ROBOT = ("floor", "user_left_ball", "user_right_ball")
"""Geoms of the scene that are not the robot's parts."""

HAND_SITES = ("left_hand", "right_hand")
"""The MJCF's sites at the hand centres (left arm, right arm)."""

SERVO_SPEED = SERVO_NO_LOAD_SPEED
"""rad/s: the robot's servo's no-load speed, as ``rnnpb.robot`` documents it (``SERVO_NAME``)."""


def _motor(joints: Any, what: str) -> np.ndarray:
    """``joints`` as a (T, 8) float array (one posture (8,) becomes (1, 8))."""
    array = np.asarray(joints, dtype=np.float64)
    if array.ndim == 1:
        array = array[None]
    if array.ndim != 2 or array.shape[1] != MOTOR_SIZE:
        raise ConfigError(f"{what} must have shape (T, {MOTOR_SIZE}), got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ConfigError(f"{what} must be finite")
    return array


def _mujoco() -> Any:
    """MuJoCo, imported with rnnpb's choice of a headless OpenGL when it is the first import
    (the judges render nothing; the choice is MuJoCo's at import)."""
    if "mujoco" not in sys.modules:
        choose_gl()
    import mujoco

    return mujoco


def judge_model_xml() -> str:
    """The humanoid's MJCF with every robot part collidable, the scene's other geoms not, and
    the construction's contacts excluded."""
    text = resources.files("rnnpb.robot").joinpath("humanoid.xml").read_text(encoding="utf-8")
    root = ET.fromstring(text)
    default = root.find("default")
    geom = None if default is None else default.find("geom")
    if geom is None:
        raise ConfigError("humanoid.xml: no default geom class to make the parts collidable")
    geom.attrib.update(contype="1", conaffinity="1")
    for element in root.iter("geom"):
        if element.get("name") in NOT_ROBOT:
            element.attrib.update(contype="0", conaffinity="0")
    contact = root.find("contact")
    if contact is None:
        contact = ET.SubElement(root, "contact")
    for body1, body2 in EXCLUDED_BODY_PAIRS:
        ET.SubElement(contact, "exclude", {"body1": body1, "body2": body2})
    return ET.tostring(root, encoding="unicode")


@dataclass(frozen=True)
class PartContact:
    """Two robot parts (geom names) inside each other by ``depth`` metres, at ``where`` of
    the way from the step before (1.0: at the step's own posture)."""

    part: str
    other: str
    depth: float
    where: float = 1.0


@dataclass(frozen=True)
class CollisionVerdict:
    """A path judged for collisions: ``steps`` postures, the ``colliding`` ones (at the
    posture or on the way to it) and each one's contacts."""

    steps: int
    colliding: tuple[int, ...]
    contacts: dict[int, tuple[PartContact, ...]] = field(default_factory=dict)

    @property
    def count(self) -> int:
        return len(self.colliding)


class _Model:
    """The robot's MuJoCo model and data, made once, with the joints' qpos addresses."""

    def __init__(self) -> None:
        self.mj = _mujoco()
        self.model: mujoco.MjModel = self.mj.MjModel.from_xml_string(judge_model_xml())
        self.data: mujoco.MjData = self.mj.MjData(self.model)
        ids = [self.model.joint(name).id for name in MOTOR_NAMES]
        self.qpos = np.array([self.model.jnt_qposadr[i] for i in ids])
        self.ranges = np.array([self.model.jnt_range[i] for i in ids])

    def pose(self, joints: np.ndarray) -> None:
        self.data.qpos[:] = 0.0
        self.data.qpos[self.qpos] = joints
        self.mj.mj_forward(self.model, self.data)


class CollisionJudge:
    """Collisions of the robot's parts by MuJoCo's contact detection (module docstring).

    >>> judge = CollisionJudge()                  # doctest: +SKIP
    >>> judge.judge(motor).colliding              # doctest: +SKIP
    """

    def __init__(self, depth: float = PASS_THROUGH_DEPTH, path_points: int = PATH_POINTS) -> None:
        if depth < 0 or path_points < 0:
            raise ConfigError("depth and path_points must be >= 0")
        self.depth = float(depth)
        self.path_points = int(path_points)
        self._robot = _Model()

    def touching(self, joints: np.ndarray) -> list[PartContact]:
        """Every pair of parts of different bodies in contact at ``joints`` (8,), at any
        depth (negative: apart, within the geoms' margin), the construction's excluded."""
        robot = self._robot
        robot.pose(_motor(joints, "a posture")[0])
        model, data = robot.model, robot.data
        found = []
        for i in range(data.ncon):
            contact = data.contact[i]
            found.append(
                PartContact(
                    model.geom(int(contact.geom1)).name,
                    model.geom(int(contact.geom2)).name,
                    float(-contact.dist),
                )
            )
        return found

    def contacts(self, joints: np.ndarray) -> list[PartContact]:
        """The pairs more than :attr:`depth` inside each other at ``joints`` (8,)."""
        return [c for c in self.touching(joints) if c.depth > self.depth]

    def collides(self, joints: np.ndarray) -> bool:
        return bool(self.contacts(joints))

    def judge(self, motor: Any, previous: Any = None) -> CollisionVerdict:
        """Judge a path of postures ``motor`` (T, 8) radians, each at its posture and on the
        way from the one before (from ``previous`` (8,) for the first; None: the first is
        judged at its posture only)."""
        path = _motor(motor, "motor")
        before = None if previous is None else _motor(previous, "previous")[0]
        ways = np.arange(1, self.path_points + 1) / (self.path_points + 1)
        colliding, found = [], {}
        for t, posture in enumerate(path):
            hits = list(self.contacts(posture))
            if before is not None:
                for w in ways:
                    hits += [
                        PartContact(c.part, c.other, c.depth, float(w))
                        for c in self.contacts(before + w * (posture - before))
                    ]
            if hits:
                colliding.append(t)
                found[t] = tuple(hits)
            before = posture
        return CollisionVerdict(len(path), tuple(colliding), found)


@dataclass(frozen=True)
class SpeedVerdict:
    """A path judged for speed: the largest joint change of each step (radians; the first
    step's from ``previous``, 0 without it), the limit per step and the steps beyond it."""

    steps: int
    limit: float
    largest_change: np.ndarray = field(repr=False)
    too_fast: tuple[int, ...] = ()

    @property
    def count(self) -> int:
        return len(self.too_fast)


def servo_step_limit(dt: float, speed: float = SERVO_SPEED) -> float:
    """Radians a joint can turn in one step of ``dt`` seconds at the servo's ``speed``."""
    if not dt > 0 or not speed > 0:
        raise ConfigError(f"dt and the servo's speed must be > 0, got {dt} and {speed}")
    return float(speed * dt)


def judge_speed(
    motor: Any, dt: float, previous: Any = None, speed: float = SERVO_SPEED
) -> SpeedVerdict:
    """The steps of ``motor`` (T, 8) that ask a joint to turn further than the servo
    (``speed`` rad/s, default the robot's servo's no-load speed) can in ``dt`` seconds."""
    path = _motor(motor, "motor")
    start = path[:1] if previous is None else _motor(previous, "previous")
    changes = np.abs(np.diff(np.concatenate([start, path]), axis=0)).max(axis=1)
    limit = servo_step_limit(dt, speed)
    return SpeedVerdict(
        len(path), limit, changes, tuple(int(t) for t in np.flatnonzero(changes > limit))
    )


@dataclass(frozen=True)
class LimitVerdict:
    """A path judged against the MJCF's joint ranges: the steps with a joint outside."""

    steps: int
    outside: tuple[int, ...]

    @property
    def count(self) -> int:
        return len(self.outside)


@dataclass(frozen=True)
class ReachVerdict:
    """The hands a path reaches by MuJoCo's kinematics (``hands`` (T, 2, 3) metres, left arm
    then right, robot frame) and, when positions were asked for, each step's larger distance
    to them (``distances`` (T,)), their mean over the steps and hands (``mean_distance``), and
    the steps farther than the tolerance (``beyond``)."""

    steps: int
    hands: np.ndarray = field(repr=False)
    distances: np.ndarray | None = field(default=None, repr=False)
    mean_distance: float | None = None
    beyond: tuple[int, ...] = ()

    @property
    def count(self) -> int:
        return len(self.beyond)


class Kinematics:
    """The robot's joints and hands as MuJoCo computes them from the MJCF (made once)."""

    def __init__(self) -> None:
        self._robot = _Model()
        self._sites = [self._robot.model.site(name).id for name in HAND_SITES]

    @property
    def joint_ranges(self) -> np.ndarray:
        """(8, 2) radians: each joint's range as the MJCF gives it, in MOTOR_NAMES order."""
        return self._robot.ranges.copy()

    def hands(self, motor: Any) -> np.ndarray:
        """(T, 2, 3): the hand sites' positions at each posture of ``motor`` (T, 8)."""
        path = _motor(motor, "motor")
        out = np.empty((len(path), 2, 3))
        for t, posture in enumerate(path):
            self._robot.pose(posture)
            out[t] = self._robot.data.site_xpos[self._sites]
        return out


def judge_limits(motor: Any, kinematics: Kinematics | None = None) -> LimitVerdict:
    """The steps of ``motor`` (T, 8) with a joint outside the MJCF's range."""
    path = _motor(motor, "motor")
    ranges = (kinematics or Kinematics()).joint_ranges
    outside = (path < ranges[:, 0]) | (path > ranges[:, 1])
    return LimitVerdict(len(path), tuple(int(t) for t in np.flatnonzero(outside.any(axis=1))))


def judge_reach(
    motor: Any,
    requested: Any = None,
    tolerance: float = 0.01,
    kinematics: Kinematics | None = None,
) -> ReachVerdict:
    """Where ``motor`` (T, 8) puts the hands, by MuJoCo's forward kinematics; with
    ``requested`` (T, 2, 3) metres, how far from it (the steps farther than ``tolerance``
    metres for either hand)."""
    hands = (kinematics or Kinematics()).hands(motor)
    if requested is None:
        return ReachVerdict(len(hands), hands)
    asked = np.asarray(requested, dtype=np.float64)
    if asked.shape != hands.shape:
        raise ConfigError(f"requested hands must have shape {hands.shape}, got {asked.shape}")
    per_hand = np.linalg.norm(hands - asked, axis=2)
    distances = per_hand.max(axis=1)
    return ReachVerdict(
        len(hands),
        hands,
        distances,
        float(per_hand.mean()),
        tuple(int(t) for t in np.flatnonzero(distances > tolerance)),
    )


__all__ = [
    "EXCLUDED_BODY_PAIRS",
    "HAND_SITES",
    "PASS_THROUGH_DEPTH",
    "PATH_POINTS",
    "SERVO_NAME",
    "SERVO_SPEED",
    "CollisionJudge",
    "CollisionVerdict",
    "Kinematics",
    "LimitVerdict",
    "PartContact",
    "ReachVerdict",
    "SpeedVerdict",
    "judge_limits",
    "judge_model_xml",
    "judge_reach",
    "judge_speed",
    "servo_step_limit",
]
