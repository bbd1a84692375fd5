"""The nearest movement the robot can make: a person faster than the robot's servos.

A person's arm swings faster than a small robot's servos turn (the AX-12A's 6.2 rad/s at no
load: :func:`rnnpb.robot.joint_step_limit`). The safe retargeting alone would then hold each
joint to the servo's step and let the arm fall behind the person, later each cycle, its shape
bent. Synchrony is what the paper's robot is for, so the learning phase keeps the person's
tempo and makes the movement smaller instead:

1. The person's hands become the robot's hand targets (the mirror mapping) and the safe
   retargeting finds the joint angles at the step, each joint held to :data:`SERVO_MARGIN` of
   its servo's step: where it had to hold a joint, the robot fell behind the person.
2. Where a joint was held on more than :data:`HELD_SHARE` of the steps of a window of
   ``window`` steps (the movement's cycle: a held step now and then is a turn through an awkward
   posture, an arm straight up, not a movement too fast), the arm's swing in that window is
   made smaller by :data:`SHRINK`: each hand target's direction from the robot's shoulder
   turns towards the window's mean direction (an arm keeps its length; an arm swung from the
   hips to above the head swings over a smaller angle about the middle of its swing), and the
   joint angles are found again, for at most
   :data:`ROUNDS` rounds. A window shrinks as one, so a cycle keeps its shape; each window
   keeps the largest amplitude at which it held a joint least often (a smaller swing that does
   not help is not taken).

Each cycle so keeps its timing — the robot moves in step with the person — and the person's
hands stay what the camera saw: the network learns to answer this person's movement with the
robot's smaller one. The report says on how many steps and by how much the movement was made
smaller, and on how many a joint was still held to its servo.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rnnpb.demonstrator import MirrorMapping
from rnnpb.robot import SHOULDERS, joint_step_limit, retarget

SERVO_MARGIN = 0.75
"""Share of the servo's step a learned step may use: the rest is headroom for what the network
makes of it — its own overshoot, and a follower a little faster than the person it learned
from."""
ROUNDS = 6
"""Rounds of shrinking at most: to 26 % of the swing."""
SHRINK = 0.8
"""The amplitude factor of one round: a fifth smaller, a change a cycle's shape survives."""
HELD_SHARE = 0.1
"""Share of a window's steps (at least one step) that may hold a joint before it is made
smaller."""


@dataclass(frozen=True)
class ServoFit:
    """Joint angles the robot's servos can follow, and what was changed to get them.

    Attributes
    ----------
    motor : array, shape (n, 8)
        Radians; NaN where the hands were not known.
    amplitude : array, shape (n,)
        The factor each step's hand targets were drawn towards their centre by (1: as the
        person moved).
    held : array of bool, shape (n,)
        Steps where the final retargeting still held a joint to its servo's step.
    adjusted : array of bool, shape (n,)
        Steps where the paper's inverse kinematics was unsafe and a safe posture was searched.
    residual : array, shape (n, 2)
        Metres from each robot hand to its (unshrunk) target.
    """

    motor: np.ndarray
    amplitude: np.ndarray
    held: np.ndarray
    adjusted: np.ndarray
    residual: np.ndarray

    @property
    def reduced_steps(self) -> int:
        return int(np.sum(self.amplitude < 0.999))

    def describe(self) -> str:
        if not self.reduced_steps and not self.held.any():
            return "the movement is within the servos' speed: kept as performed"
        words = []
        if self.reduced_steps:
            reduced = self.amplitude[self.amplitude < 0.999]
            words.append(
                f"made smaller to keep within the servos' speed at the person's tempo on "
                f"{self.reduced_steps} steps (to {float(np.median(reduced)):.0%} of its size, "
                f"{float(reduced.min()):.0%} at least)"
            )
        if self.held.any():
            words.append(f"a joint held to its servo's step on {int(self.held.sum())} steps")
        return "; ".join(words)

    def to_json(self) -> dict:
        reduced = self.amplitude[self.amplitude < 0.999]
        return {
            "reduced_steps": self.reduced_steps,
            "smallest_amplitude": round(float(self.amplitude.min()), 4)
            if len(self.amplitude)
            else 1.0,
            "median_reduced_amplitude": round(float(np.median(reduced)), 4)
            if len(reduced)
            else 1.0,
            "held_steps": int(self.held.sum()),
            "adjusted_steps": int(self.adjusted.sum()),
        }


def _swung(targets: np.ndarray, centre: np.ndarray, amplitude: np.ndarray) -> np.ndarray:
    """Hand targets (n, 2, 3) whose directions from the robot's shoulders are turned towards
    ``centre``'s (unit vectors, (n, 2, 3)) by ``amplitude`` (n,) (1: as they are, 0: the centre
    direction); each target's distance from its shoulder is kept."""
    relative = targets - SHOULDERS
    reach = np.linalg.norm(relative, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        direction = relative / reach
    cosine = np.clip(np.sum(direction * centre, axis=-1, keepdims=True), -1.0, 1.0)
    angle = np.arccos(cosine)
    a = amplitude[:, None, None]
    with np.errstate(invalid="ignore", divide="ignore"):
        sine = np.sin(angle)
        turned = np.where(
            sine > 1e-9,
            (np.sin((1 - a) * angle) * centre + np.sin(a * angle) * direction) / sine,
            direction,
        )
    return SHOULDERS + reach * turned


def _mean_direction(targets: np.ndarray, window: int) -> np.ndarray:
    """Each step's mean direction (unit, (n, 2, 3)) of the hand targets from the robot's
    shoulders over ``window`` steps about it."""
    relative = targets - SHOULDERS
    with np.errstate(invalid="ignore", divide="ignore"):
        direction = relative / np.linalg.norm(relative, axis=-1, keepdims=True)
    mean = _centred(direction, window)
    with np.errstate(invalid="ignore", divide="ignore"):
        return mean / np.linalg.norm(mean, axis=-1, keepdims=True)


def _centred(values: np.ndarray, window: int) -> np.ndarray:
    """Moving average along axis 0 over ``window`` steps, NaN-aware, edges held; (n, ...)."""
    n = len(values)
    flat = values.reshape(n, -1)
    out = np.full_like(flat, np.nan)
    half = max(1, window // 2)
    for t in range(n):
        chunk = flat[max(0, t - half) : t + half + 1]
        seen = np.isfinite(chunk).all(axis=1)
        if seen.any():
            out[t] = chunk[seen].mean(axis=0)
    return out.reshape(values.shape)


def _speed_ratio(joints: np.ndarray, limit: float) -> np.ndarray:
    """(n,) the largest joint change into each step over the servo's step (0 at a start)."""
    ratio = np.zeros(len(joints))
    change = np.abs(np.diff(joints, axis=0)).max(axis=1) / limit
    ratio[1:] = np.where(np.isfinite(change), change, 0.0)
    return ratio


def _spread(ratio: np.ndarray, window: int) -> np.ndarray:
    """The largest ratio within ``window`` steps around each step."""
    half = max(1, window // 2)
    return np.array([ratio[max(0, t - half) : t + half + 1].max() for t in range(len(ratio))])


def _held(joints: np.ndarray, step: float) -> np.ndarray:
    """(n,) steps where a joint moved by the whole of ``step``: the retargeting held it."""
    return _speed_ratio(joints, step) >= 1.0 - 1e-9


def fit_to_servos(hands: np.ndarray, mapping: MirrorMapping, window: int) -> ServoFit:
    """Joint angles for the person's hands (n, 2, 3) that the robot's servos can follow at
    ``mapping.dt`` (module doc); ``window``: steps over which the amplitude is one (the
    movement's cycle)."""
    hands = np.asarray(hands, dtype=np.float64)
    targets = mapping.robot_hand_targets(hands)
    step = joint_step_limit(mapping.dt) * SERVO_MARGIN
    window = max(2, int(window))
    centre = _mean_direction(targets, window)
    allowed = max(1.0, HELD_SHARE * window)
    amplitude = np.ones(len(hands))
    best = amplitude.copy()
    fewest = np.full(len(hands), np.inf)
    final = retarget(_swung(targets, centre, amplitude), mapping.dt * SERVO_MARGIN)
    for round_ in range(ROUNDS + 1):
        held = _count(_held(final.joints, step), window).astype(float)
        better = held < fewest
        best, fewest = np.where(better, amplitude, best), np.where(better, held, fewest)
        crowded = held > allowed
        if not crowded.any() or round_ == ROUNDS:
            break
        amplitude = np.where(
            _spread(crowded.astype(float), window) > 0, amplitude * SHRINK, amplitude
        )
        final = retarget(_swung(targets, centre, amplitude), mapping.dt * SERVO_MARGIN)
    if not np.array_equal(best, amplitude):
        amplitude = best
        final = retarget(_swung(targets, centre, amplitude), mapping.dt * SERVO_MARGIN)
    held = _held(final.joints, step)
    reached = np.full((len(hands), 2), np.nan)
    finite = np.isfinite(final.joints).all(axis=1)
    if finite.any():
        from rnnpb.robot import forward_kinematics

        hands_reached, _ = forward_kinematics(final.joints[finite])
        reached[finite] = np.linalg.norm(hands_reached - targets[finite], axis=-1)
    return ServoFit(final.joints, amplitude, held, final.adjusted, reached)


def _count(flags: np.ndarray, window: int) -> np.ndarray:
    """(n,) how many flagged steps lie within ``window`` steps around each step."""
    half = max(1, window // 2)
    return np.array([int(flags[max(0, t - half) : t + half + 1].sum()) for t in range(len(flags))])
