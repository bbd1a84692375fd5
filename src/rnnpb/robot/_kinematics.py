"""Arm kinematics of the simulated humanoid: joint limits, forward and inverse kinematics.

Frames (see ``camera.py``): robot frame origin on the floor under the torso, ``x`` forward
(towards the user), ``y`` to the robot's left, ``z`` up; metres and radians.

Each arm is a spherical shoulder (pitch, roll, yaw, applied in that order from the torso
outwards) and an elbow pitch. With all angles zero the arm hangs straight down. The joint
senses of the right arm mirror those of the left, so a pose that is symmetric about the robot's
mid-plane has the same four angles on both arms:

- shoulder pitch ``shp`` > 0 raises the arm forward (towards the user), up to overhead;
- shoulder roll ``shr`` > 0 lifts the arm sideways, away from the body;
- shoulder yaw ``shy`` > 0 turns the upper arm about its own axis, forearm towards the body;
- elbow pitch ``elp`` > 0 bends the forearm forward.

The hand position, with ``S`` the shoulder centre, ``L1``/``L2`` the upper arm and forearm
lengths and ``m`` = +1 (left arm) or -1 (right arm)::

    hand = S + R_y(-shp) R_x(m shr) R_z(m shy) [ (0, 0, -L1) + R_y(-elp) (0, 0, -L2) ]

Inverse kinematics (:func:`inverse_kinematics`) follows the paper (section 2.1): the elbow
pitch depends on the shoulder pitch, so that each 3-D hand position has one posture. We use the
linear coupling ``elp = ELBOW_AT_ZERO_PITCH + ELBOW_PER_PITCH * shp`` (the arm straightens as it
swings back, bends as it lifts forward: the elbow of a person holding the hands in front of the
chest). Because the shoulder-to-hand distance depends on the elbow angle alone, the coupling
makes the reach set the shoulder pitch; shoulder roll and yaw then point the hand.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rnnpb.vectors import MOTOR_NAMES

# --- geometry (a Sony QRIO sized upper body, about 0.6 m tall) ------------------------------
UPPER_ARM_LENGTH = 0.10
"""Shoulder centre to elbow axis, metres."""
FOREARM_LENGTH = 0.11
"""Elbow axis to the hand centre (a ball in the fist), metres."""
SHOULDER_HEIGHT = 0.40
SHOULDER_HALF_WIDTH = 0.095
SHOULDERS = np.array(
    [[0.0, SHOULDER_HALF_WIDTH, SHOULDER_HEIGHT], [0.0, -SHOULDER_HALF_WIDTH, SHOULDER_HEIGHT]]
)
"""Shoulder centres (left arm, right arm) in the robot frame, shape (2, 3)."""
ARM_SIDES = ("left", "right")
_MIRROR = np.array([1.0, -1.0])  # m in the module docstring, per arm

# --- joint limits (radians), order of MOTOR_NAMES -------------------------------------------
_ARM_LIMITS = np.array(
    [
        [-1.0, 3.0],  # shoulder pitch: 57 deg backwards to 172 deg forward/overhead
        [-0.25, 1.65],  # shoulder roll: 14 deg across the body to 95 deg sideways
        [-1.6, 1.6],  # shoulder yaw: +-92 deg about the upper arm
        [0.0, 2.4],  # elbow pitch: straight to 138 deg bent
    ]
)
JOINT_LIMITS = np.concatenate([_ARM_LIMITS, _ARM_LIMITS])
"""Joint limits, shape (8, 2): (lower, upper) radians per joint in MOTOR_NAMES order."""
JOINT_LIMITS.setflags(write=False)
assert len(MOTOR_NAMES) == JOINT_LIMITS.shape[0]

# --- the elbow/shoulder-pitch coupling used by the inverse kinematics -----------------------
ELBOW_AT_ZERO_PITCH = 1.4
"""Elbow pitch (rad) of the coupled posture when the shoulder pitch is zero."""
ELBOW_PER_PITCH = 0.8
"""Elbow pitch gained per radian of shoulder pitch in the coupled posture."""


def coupled_pitch_range() -> tuple[float, float]:
    """Shoulder pitch interval (rad) where the coupled elbow pitch stays inside its limits."""
    (p_lo, p_hi), (e_lo, e_hi) = _ARM_LIMITS[0], _ARM_LIMITS[3]
    lo = max(p_lo, (e_lo - ELBOW_AT_ZERO_PITCH) / ELBOW_PER_PITCH)
    hi = min(p_hi, (e_hi - ELBOW_AT_ZERO_PITCH) / ELBOW_PER_PITCH)
    return float(lo), float(hi)


def coupled_elbow(shoulder_pitch: np.ndarray) -> np.ndarray:
    """Elbow pitch of the coupled posture for a shoulder pitch (any shape), radians."""
    return ELBOW_AT_ZERO_PITCH + ELBOW_PER_PITCH * np.asarray(shoulder_pitch, dtype=np.float64)


def clip_to_limits(joints: np.ndarray) -> np.ndarray:
    """Clip joint angles, shape (..., 8), to :data:`JOINT_LIMITS`."""
    return np.clip(np.asarray(joints, dtype=np.float64), JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1])


# --- rotations, batched over leading axes --------------------------------------------------
def _rot(axis: int, angle: np.ndarray) -> np.ndarray:
    """Rotation matrices about a coordinate axis, shape (..., 3, 3)."""
    c, s = np.cos(angle), np.sin(angle)
    o, z = np.ones_like(c), np.zeros_like(c)
    if axis == 0:
        rows = [[o, z, z], [z, c, -s], [z, s, c]]
    elif axis == 1:
        rows = [[c, z, s], [z, o, z], [-s, z, c]]
    else:
        rows = [[c, -s, z], [s, c, z], [z, z, o]]
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


def _arm_points(arm_joints: np.ndarray, side: np.ndarray | int) -> tuple[np.ndarray, np.ndarray]:
    """Elbow and hand of one arm relative to its shoulder; arm_joints (..., 4) → (..., 3) each."""
    q = np.asarray(arm_joints, dtype=np.float64)
    m = _MIRROR[side]
    shoulder = _rot(1, -q[..., 0]) @ _rot(0, m * q[..., 1]) @ _rot(2, m * q[..., 2])
    upper = np.array([0.0, 0.0, -UPPER_ARM_LENGTH])
    fore = np.stack(
        [
            FOREARM_LENGTH * np.sin(q[..., 3]),
            np.zeros_like(q[..., 3]),
            -FOREARM_LENGTH * np.cos(q[..., 3]),
        ],
        axis=-1,
    )  # R_y(-elp) (0, 0, -L2)
    elbow = shoulder @ upper
    hand = elbow + (shoulder @ fore[..., None])[..., 0]
    return elbow, hand


def forward_kinematics(joints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Hand and elbow positions of both arms.

    Parameters
    ----------
    joints : array, shape (..., 8)
        Joint angles in radians, MOTOR_NAMES order.

    Returns
    -------
    hands : array, shape (..., 2, 3)
        Hand centres (left arm, right arm) in the robot frame, metres.
    elbows : array, shape (..., 2, 3)
        Elbow centres (left arm, right arm).
    """
    q = np.asarray(joints, dtype=np.float64)
    arms = q.reshape(*q.shape[:-1], 2, 4)
    side = np.array([0, 1])
    elbow, hand = _arm_points(arms, side)
    return hand + SHOULDERS, elbow + SHOULDERS


@dataclass(frozen=True)
class IKResult:
    """The outcome of :func:`inverse_kinematics`.

    Attributes
    ----------
    joints : array, shape (..., 8)
        Joint angles in radians, inside :data:`JOINT_LIMITS`, with the coupled elbow.
    residual : array, shape (..., 2)
        Distance (metres) from each arm's reached hand position to its target.
    reachable : array of bool, shape (..., 2)
        Per arm: the target was reached (residual below ``tolerance``).
    """

    joints: np.ndarray
    residual: np.ndarray
    reachable: np.ndarray

    @property
    def all_reachable(self) -> bool:
        return bool(np.all(self.reachable))


def _closed_form(target: np.ndarray, side: int) -> list[np.ndarray]:
    """Exact coupled solutions (two yaw branches) for targets relative to the shoulder, (n, 3).

    Returns candidate (n, 4) joint arrays; entries may violate limits or be NaN when no exact
    solution exists; the caller refines and projects them.
    """
    l1, l2 = UPPER_ARM_LENGTH, FOREARM_LENGTH
    d2 = np.sum(target**2, axis=-1)
    cos_e = np.clip((d2 - l1**2 - l2**2) / (2 * l1 * l2), -1.0, 1.0)
    p_lo, p_hi = coupled_pitch_range()
    pitch = np.clip((np.arccos(cos_e) - ELBOW_AT_ZERO_PITCH) / ELBOW_PER_PITCH, p_lo, p_hi)
    elbow = coupled_elbow(pitch)
    # w: the target in the frame turned by the shoulder pitch; v: the hand in the upper arm frame.
    w = (np.swapaxes(_rot(1, -pitch), -1, -2) @ target[..., None])[..., 0]
    v_x = l2 * np.sin(elbow)
    v_z = -l1 - l2 * np.cos(elbow)
    with np.errstate(divide="ignore", invalid="ignore"):
        yaw_abs = np.arccos(np.clip(w[:, 0] / v_x, -1.0, 1.0))
    m = _MIRROR[side]
    candidates = []
    # The branch with the forearm turned outwards (negative yaw) comes first: it is the
    # posture people use for hands in front of the chest, and ties go to the first branch,
    # which keeps trajectories on one branch instead of jumping between equal solutions.
    for yaw_sign in (-1.0, 1.0):
        yaw = m * yaw_sign * yaw_abs  # the angle R_z turns by (m * shy), so shy = yaw_sign * |.|
        a = v_x * np.sin(yaw)
        roll = np.arctan2(w[:, 2], w[:, 1]) - np.arctan2(v_z, a)  # the angle R_x turns by
        roll = (roll + np.pi) % (2 * np.pi) - np.pi
        candidates.append(np.stack([pitch, m * roll, m * yaw, elbow], axis=-1))
    return candidates


def _refine(q: np.ndarray, target: np.ndarray, side: int, iterations: int) -> np.ndarray:
    """Projected Levenberg-Marquardt on (pitch, roll, yaw) with the coupled elbow, (n, 4)."""
    p_lo, p_hi = coupled_pitch_range()
    lo = np.array([p_lo, *_ARM_LIMITS[1:3, 0]])
    hi = np.array([p_hi, *_ARM_LIMITS[1:3, 1]])
    x = np.clip(q[:, :3], lo, hi)
    eps = 1e-7

    def hand(x3: np.ndarray) -> np.ndarray:
        full = np.concatenate([x3, coupled_elbow(x3[:, :1])], axis=-1)
        return _arm_points(full, side)[1]

    lam = np.full(x.shape[0], 1e-3)
    h = hand(x)
    cost = np.sum((h - target) ** 2, -1)
    for _ in range(iterations):
        r = h - target
        jac = np.stack([(hand(x + eps * np.eye(3)[k]) - h) / eps for k in range(3)], axis=-1)
        jtj = np.swapaxes(jac, -1, -2) @ jac
        jtr = (np.swapaxes(jac, -1, -2) @ r[..., None])[..., 0]
        # Levenberg-Marquardt: damping grows after a failed step and shrinks after a good one.
        scale = lam * (np.trace(jtj, axis1=-2, axis2=-1) + 1e-12)
        step = np.linalg.solve(jtj + scale[:, None, None] * np.eye(3), jtr[..., None])[..., 0]
        x_new = np.clip(x - step, lo, hi)
        h_new = hand(x_new)
        cost_new = np.sum((h_new - target) ** 2, -1)
        better = cost_new < cost
        x = np.where(better[:, None], x_new, x)
        h = np.where(better[:, None], h_new, h)
        cost = np.where(better, cost_new, cost)
        lam = np.clip(np.where(better, lam * 0.3, lam * 10.0), 1e-9, 1e6)
    return np.concatenate([x, coupled_elbow(x[:, :1])], axis=-1)


def inverse_kinematics(
    hands: np.ndarray, tolerance: float = 1e-4, iterations: int = 40
) -> IKResult:
    """Joint angles that put both hands at 3-D targets, with the elbow coupled to the shoulder.

    Parameters
    ----------
    hands : array, shape (..., 2, 3)
        Targets for the robot's left hand (index 0) and right hand (index 1), robot frame.
    tolerance : float
        Residual (metres) below which a target counts as reached.
    iterations : int
        Refinement iterations used for targets without an exact solution inside the limits.

    Returns
    -------
    IKResult
        Joint angles always inside the limits. An unreachable target gives the reachable
        posture nearest to it (a local least-squares optimum) and ``reachable`` False.
    """
    hands = np.asarray(hands, dtype=np.float64)
    if hands.shape[-2:] != (2, 3):
        raise ValueError(f"hands must have shape (..., 2, 3), got {hands.shape}")
    lead = hands.shape[:-2]
    flat = hands.reshape(-1, 2, 3)
    joints = np.empty((flat.shape[0], 2, 4))
    residual = np.empty((flat.shape[0], 2))
    for side in (0, 1):
        target = flat[:, side] - SHOULDERS[side]
        best_q = None
        best_err = None
        for cand in _closed_form(target, side):
            cand = np.nan_to_num(cand)
            inside = np.all(
                (cand >= _ARM_LIMITS[:, 0] - 1e-12) & (cand <= _ARM_LIMITS[:, 1] + 1e-12), axis=-1
            )
            err = np.linalg.norm(_arm_points(cand, side)[1] - target, axis=-1)
            err = np.where(inside, err, np.inf)
            if best_q is None:
                best_q, best_err = cand, err
            else:
                take = err < best_err - tolerance * 1e-3
                best_q = np.where(take[:, None], cand, best_q)
                best_err = np.where(take, err, best_err)
        todo = ~(best_err < tolerance * 1e-2)
        if np.any(todo):
            starts = list(_closed_form(target[todo], side))
            # A coarse grid of postures as further starts: the nearest reachable point of a
            # far target need not lie near either closed-form branch.
            p_lo, p_hi = coupled_pitch_range()
            for pitch in (p_lo + 0.25 * (p_hi - p_lo), p_hi - 0.25 * (p_hi - p_lo)):
                for roll in (0.0, 1.2):
                    for yaw in (-1.0, 1.0):
                        starts.append(np.tile([pitch, roll, yaw, 0.0], (int(todo.sum()), 1)))
            refined_q, refined_err = None, None
            for start in starts:
                q = _refine(np.nan_to_num(start), target[todo], side, iterations)
                err = np.linalg.norm(_arm_points(q, side)[1] - target[todo], axis=-1)
                if refined_q is None:
                    refined_q, refined_err = q, err
                else:
                    take = err < refined_err
                    refined_q = np.where(take[:, None], q, refined_q)
                    refined_err = np.where(take, err, refined_err)
            best_q[todo], best_err[todo] = refined_q, refined_err
        joints[:, side] = best_q
        residual[:, side] = best_err
    joints = clip_to_limits(joints.reshape(-1, 8))
    return IKResult(
        joints=joints.reshape(*lead, 8),
        residual=residual.reshape(*lead, 2),
        reachable=(residual < tolerance).reshape(*lead, 2),
    )
