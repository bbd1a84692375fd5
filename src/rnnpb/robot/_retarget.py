"""Safe retargeting: the robot's joint angles for a stream of hand targets, never a posture that
hits the robot's own body, never a step faster than its servos.

Each step's plain inverse kinematics (:func:`rnnpb.robot.inverse_kinematics`, the paper's
coupled elbow) is taken as it is when it is safe: its posture keeps every checked part (each
arm's elbow, forearm and hand against the torso, legs and head; the upper arms against the
head; one arm against the other: :func:`rnnpb.robot.collision_pairs`) at least ``clearance``
apart, the straight joint-space way to it from the step before touches nothing, and no joint
moves further than the servo can in one step (:func:`rnnpb.robot.joint_step_limit`). Postures
of the demonstrator are all of this kind, so its data are unchanged.

Otherwise the posture is found by differential inverse kinematics with collision avoidance
(``mink``: a quadratic program per iteration over the eight joints, on the robot's own
collision geometry): starting from the step before (a safe posture) and moving toward the hand
targets, the program keeps every checked pair ``clearance`` apart, the joints inside their
limits, the whole step inside the servo's reach, and stays near the coupled posture. The
result is the reachable safe posture closest to the request from where the robot was; its
residual says how far each hand is from its target. If even that result fails the final check
(the program linearises the geometry), the robot holds the step before.

Steps whose targets are not finite (a lost hand) give NaN joints; the next finite step starts
again from the last safe posture.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.robot._collision import SelfCollision, collision_pairs, joint_step_limit
from rnnpb.robot._gl import import_mujoco
from rnnpb.robot._kinematics import (
    JOINT_LIMITS,
    forward_kinematics,
    inverse_kinematics,
)
from rnnpb.robot._mujoco import joint_addresses, model_xml
from rnnpb.vectors import MOTOR_NAMES, MOTOR_SIZE

if TYPE_CHECKING:
    import mujoco

RETARGET_CLEARANCE = 0.01
"""Distance (metres) every checked pair of parts keeps: one centimetre is a visible gap on a
0.6 m robot and covers the few millimetres by which a real arm's shells exceed the capsules."""

REST_POSTURE = np.array([0.2, 0.35, 0.0, 0.6, 0.2, 0.35, 0.0, 0.6])
"""Where the search starts when there is no step before: arms a little forward and out, elbows
bent, 3 cm or more from every part of the body."""
REST_POSTURE.setflags(write=False)

_ITERATIONS = 60
_ITERATION_STEP = 0.04
"""Largest joint change (radians) per search iteration: the program linearises the distances,
so each iteration moves every part by a few centimetres at most, less than the distance at
which pairs are watched."""
_PATH_POINTS = 3


@dataclass(frozen=True)
class Retargeted:
    """The outcome of :func:`retarget`.

    Attributes
    ----------
    joints : array, shape (n, 8)
        Joint angles (radians), safe and within the speed limit from step to step; NaN where
        the target was not finite.
    residual : array, shape (n, 2)
        Distance (metres) from each reached hand to its target.
    adjusted : array of bool, shape (n,)
        The plain inverse kinematics was unsafe at the step and a safe posture was searched.
    held : array of bool, shape (n,)
        No safe posture toward the target was found and the step before was held.
    clearance : array, shape (n,)
        Smallest distance (metres) between checked parts at the posture, capped at 2 cm.
    """

    joints: np.ndarray
    residual: np.ndarray
    adjusted: np.ndarray
    held: np.ndarray
    clearance: np.ndarray

    @property
    def n_adjusted(self) -> int:
        return int(self.adjusted.sum())


def _retarget_xml() -> str:
    # mink only avoids pairs whose geoms may collide by contype/conaffinity; the simulated
    # robot's geoms are contype 0 (its parts never touch in the physics), so the checked ones
    # are switched on in this query-only copy.
    root = ET.fromstring(model_xml())
    names = {name for pair in collision_pairs() for name in pair}
    for geom in root.iter("geom"):
        if geom.get("name") in names:
            geom.set("contype", "1")
            geom.set("conaffinity", "1")
    return ET.tostring(root, encoding="unicode")


class Retargeter:
    """Safe retargeting of hand targets to joint angles (see the module doc); holds the
    collision model and the differential-IK problem, made once.

    Parameters
    ----------
    clearance : float
        Distance every checked pair of parts keeps, metres.
    """

    def __init__(self, clearance: float = RETARGET_CLEARANCE) -> None:
        if not 0.0 <= clearance <= 0.02:
            raise ConfigError(f"retargeting clearance must be in [0, 0.02] m, got {clearance}")
        import mink

        mj = import_mujoco()
        self.clearance = float(clearance)
        self._collision = SelfCollision()
        self._mink = mink
        self.model: mujoco.MjModel = mj.MjModel.from_xml_string(_retarget_xml())
        self._qadr = joint_addresses(self.model)
        self._configuration = mink.Configuration(self.model)
        self._hands = [
            mink.FrameTask(site, "site", position_cost=1.0, orientation_cost=0.0)
            for site in ("left_hand", "right_hand")
        ]
        self._posture = mink.PostureTask(self.model, cost=1e-3)
        self._limits = [
            mink.ConfigurationLimit(self.model),
            mink.CollisionAvoidanceLimit(
                self.model,
                [([a], [b]) for a, b in collision_pairs()],
                minimum_distance_from_collisions=1.5 * self.clearance,
                collision_detection_distance=1.5 * self.clearance + 0.03,
            ),
        ]

    def clearance_at(self, joints: np.ndarray) -> float:
        """Smallest distance (metres) between checked parts at ``joints`` (8,), capped at 2 cm
        (negative: inside each other)."""
        return self._collision.clearance(joints)

    def _path_clear(self, start: np.ndarray, target: np.ndarray) -> bool:
        ways = np.arange(1, _PATH_POINTS + 1) / (_PATH_POINTS + 1)
        return all(self._collision.clearance(start + w * (target - start)) >= 0.0 for w in ways)

    def _safe_step(self, previous: np.ndarray | None, joints: np.ndarray, step: float) -> bool:
        if self._collision.clearance(joints) < self.clearance - 1e-9:
            return False
        if previous is None:
            return True
        if np.any(np.abs(joints - previous) > step + 1e-12):
            return False
        return self._path_clear(previous, joints)

    def _search(
        self, start: np.ndarray, targets: np.ndarray, near: np.ndarray, step: float | None
    ) -> np.ndarray:
        mink = self._mink
        q = self._configuration.q.copy()
        q[self._qadr] = start
        self._configuration.update(q)
        for task, target in zip(self._hands, targets, strict=True):
            task.set_target(mink.SE3.from_translation(target))
        posture = q.copy()
        posture[self._qadr] = near
        self._posture.set_target(posture)
        # Small iterations keep the linearised distances valid; with a step before, the whole
        # search moves each joint by at most one servo step.
        speed = _ITERATION_STEP if step is None else min(_ITERATION_STEP, step / _ITERATIONS)
        limits = [*self._limits, mink.VelocityLimit(self.model, dict.fromkeys(MOTOR_NAMES, speed))]
        for _ in range(_ITERATIONS):
            velocity = mink.solve_ik(
                self._configuration,
                [*self._hands, self._posture],
                1.0,
                "daqp",
                damping=1e-6,
                limits=limits,
            )
            self._configuration.integrate_inplace(velocity, 1.0)
        found = np.asarray(self._configuration.q[self._qadr], dtype=np.float64)
        found = np.clip(found, JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1])
        if step is not None:
            found = start + np.clip(found - start, -step, step)
        return found

    def __call__(
        self, targets: np.ndarray, dt: float = 0.4, previous: np.ndarray | None = None
    ) -> Retargeted:
        """Safe joint angles for robot hand targets.

        Parameters
        ----------
        targets : array, shape (n, 2, 3)
            The robot's left and right hand targets per step, robot frame, metres.
        dt : float
            Seconds per step: a joint moves at most the servo's speed times ``dt`` per step.
        previous : array, shape (8,), optional
            The posture before the first step (the robot's present one); None: the first step
            has no speed limit.
        """
        targets = np.asarray(targets, dtype=np.float64)
        if targets.ndim != 3 or targets.shape[1:] != (2, 3):
            raise ConfigError(f"hand targets must have shape (n, 2, 3), got {targets.shape}")
        if not dt > 0:
            raise ConfigError(f"dt must be > 0, got {dt}")
        step = joint_step_limit(dt)
        n = len(targets)
        joints = np.full((n, MOTOR_SIZE), np.nan)
        adjusted = np.zeros(n, bool)
        held = np.zeros(n, bool)
        clearance = np.full(n, np.nan)
        finite = np.isfinite(targets).all(axis=(1, 2))
        plain = np.full((n, MOTOR_SIZE), np.nan)
        if finite.any():
            plain[finite] = inverse_kinematics(targets[finite]).joints
        before = None if previous is None else np.asarray(previous, dtype=np.float64)
        if before is not None and (before.shape != (MOTOR_SIZE,) or not np.isfinite(before).all()):
            raise ConfigError(f"previous posture must be 8 finite angles, got {before}")
        last_safe = before
        for t in range(n):
            if not finite[t]:
                before = None  # a gap: the next step is a new start, from the last safe posture
                continue
            q = plain[t]
            if not self._safe_step(before, q, step):
                adjusted[t] = True
                start = REST_POSTURE if last_safe is None else last_safe
                limit = None if before is None else step
                q = self._search(np.array(start), targets[t], plain[t], limit)
                if not self._safe_step(before, q, step):
                    held[t] = True
                    q = np.array(start)
            joints[t] = q
            clearance[t] = self._collision.clearance(q)
            before = last_safe = q
        residual = np.full((n, 2), np.nan)
        if finite.any():
            reached, _ = forward_kinematics(joints[finite])
            residual[finite] = np.linalg.norm(reached - targets[finite], axis=-1)
        return Retargeted(joints, residual, adjusted, held, clearance)


_DEFAULT: dict[float, Retargeter] = {}


def retarget(
    targets: np.ndarray,
    dt: float = 0.4,
    previous: np.ndarray | None = None,
    clearance: float = RETARGET_CLEARANCE,
) -> Retargeted:
    """Safe joint angles for robot hand targets (n, 2, 3); see :class:`Retargeter`. The
    retargeter for each ``clearance`` is made once per process."""
    if clearance not in _DEFAULT:
        _DEFAULT[clearance] = Retargeter(clearance)
    return _DEFAULT[clearance](targets, dt, previous)
