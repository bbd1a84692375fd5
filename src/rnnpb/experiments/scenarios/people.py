"""The people study's scenarios and measures: real motion capture through every path that makes
the robot's joint angles, learned from one performer and followed in another's.

A *movement* is a list of BVH takes played as one stream (:func:`rnnpb.mocap.capture_stream`):
the takes of one content by one performer (a style of the Bandai Namco dataset's naming,
``dataset-2_{content}_{style}_{id}.bvh``), in the order of their ids; ``raise-up-hands-in-turn``
alternates the ``raise-up-left-hand`` and ``raise-up-right-hand`` takes. Each movement is
played slower by the time scale that gives the learning performer's shortest period
:data:`PERIOD_STEPS` steps (the paper's 12-step cycle); the other performers are played at the
same time scale, so their own tempo stays theirs.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb.errors import ConfigError

PERIOD_STEPS = 12
DEVELOPMENT_LEARNER = "feminine"
DEVELOPMENT_FOLLOWED = ("exhausted",)
"""The performers (styles) of the full form without ``--exam``: the shared development takes'
styles, which the exam excludes."""
IN_TURN = "raise-up-hands-in-turn"
_NAME = re.compile(r"^dataset-2_(?P<content>[a-z-]+)_(?P<style>[a-z]+)_(?P<id>\d+)\.bvh$")


@dataclass(frozen=True)
class PeopleConfig:
    """``dt``: seconds per step; ``distance``: metres from the robot to the performer's
    shoulders (as `rnnpb record --distance`: where raised and wide hands stay in the robot
    camera's view); ``min_steps``: a stream plays its takes over again until it
    has at least this many steps; ``sequence_length``: steps per training sequence;
    ``settle_steps``: steps after a movement starts that are not judged."""

    dt: float = 0.4
    distance: float = 1.5
    min_steps: int = 96
    sequence_length: int = 48
    settle_steps: int = 24


def takes_of(root: Path, content: str, style: str, count: int) -> list[Path]:
    """The first ``count`` takes of ``content`` by ``style`` under ``root``, by id."""
    if content == IN_TURN:
        left = takes_of(root, "raise-up-left-hand", style, count)
        right = takes_of(root, "raise-up-right-hand", style, count)
        return [take for pair in zip(left, right, strict=True) for take in pair]
    found = []
    for path in root.glob(f"dataset-2_{content}_{style}_*.bvh"):
        match = _NAME.match(path.name)
        if match and match["content"] == content and match["style"] == style:
            found.append((int(match["id"]), path))
    found.sort()
    if len(found) < count:
        raise ConfigError(
            f"{root}: {len(found)} takes of {content!r} by {style!r}, the study needs {count}"
        )
    return [path for _, path in found[:count]]


def time_scale(files: list[Path], dt: float) -> float:
    """The time scale that makes the shortest period of ``files`` :data:`PERIOD_STEPS` steps."""
    from rnnpb.mocap import body_hands, movement_period, read_bvh

    periods = []
    for path in files:
        bvh = read_bvh(path)
        hands, _ = body_hands(bvh)
        periods.append(movement_period(hands, bvh.frame_time))
    return float(PERIOD_STEPS * dt / min(periods))


def placed_body(distance: float):
    """The standard user with the shoulders ``distance`` metres from the robot."""
    from rnnpb.demonstrator import UserBody

    return UserBody(distance=distance, hand_depth=min(UserBody().hand_depth, 0.9 * distance))


def stream_hands(files: list[Path], config: PeopleConfig, scale: float):
    """The takes played in order, over again until the stream has ``config.min_steps`` steps,
    resampled to the step, the performer at ``config.distance`` (a
    :class:`rnnpb.mocap.CaptureStream`)."""
    from rnnpb.mocap import capture_stream

    body = placed_body(config.distance)
    paths = [str(f) for f in files]
    once = capture_stream(paths, dt=config.dt, time_scale=scale, body=body)
    repeats = max(1, -(-config.min_steps // max(len(once.hands), 1)))
    if repeats == 1:
        return once
    return capture_stream(paths * repeats, dt=config.dt, time_scale=scale, body=body)


@dataclass(frozen=True)
class Recorded:
    """What the robot's camera sees of a stream of hands (NaN out of view) and its joint angles."""

    sensory: np.ndarray
    motor: np.ndarray


def record(hands: np.ndarray, config: PeopleConfig, name: str) -> Recorded:
    """A stream of 3-D hands (on the standard body placed at ``config.distance``) as the
    robot's camera sees it (a hand outside the view is not seen) and the robot's joint angles
    for it by the safe retargeting."""
    from rnnpb.demonstrator import MirrorMapping
    from rnnpb.robot.camera import RobotCamera

    sensory = RobotCamera().sensory_from_hands(hands).reshape(-1, 2, 2)
    with np.errstate(invalid="ignore"):
        sensory[((sensory < 0) | (sensory > 1)).any(axis=2)] = np.nan
    motor = MirrorMapping(placed_body(config.distance), dt=config.dt).retarget(hands).joints
    return Recorded(sensory.reshape(-1, 4), motor)


def length_sequences(recorded: Recorded, pattern: str, length: int):
    """Consecutive sequences of ``length`` steps with both hands seen."""
    from rnnpb.sequences import Sequence

    valid = np.isfinite(recorded.sensory).all(axis=1) & np.isfinite(recorded.motor).all(axis=1)
    edges = np.diff(np.concatenate([[0], valid.astype(int), [0]]))
    out = []
    for a, b in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True):
        for s in range(a, b - length + 1, length):
            out.append(
                Sequence(recorded.sensory[s : s + length], recorded.motor[s : s + length], pattern)
            )
    return out


def path_safety(motor: np.ndarray, dt: float, checker=None) -> dict[str, int]:
    """Steps of a recorded joint sequence by the robot's checker: colliding, too fast, outside
    the joint limits (not merely against them), of all."""
    from rnnpb.robot import JOINT_LIMITS
    from rnnpb.safety import SafetyChecker, SafetyLimits

    motor = motor[np.isfinite(motor).all(axis=1)]
    checker = checker or SafetyChecker(SafetyLimits(dt=dt))
    result = checker.check(motor)
    outside = (motor < JOINT_LIMITS[:, 0] - 1e-9) | (motor > JOINT_LIMITS[:, 1] + 1e-9)
    return {
        "steps": len(motor),
        "collision": result.count("collision"),
        "speed": result.count("speed"),
        "outside_limits": int(outside.any(axis=1).sum()),
    }


def taught_motor(hands: np.ndarray, sensory: np.ndarray, config: PeopleConfig) -> list[np.ndarray]:
    """The teaching path: the episode cutter told every step is novel, cutting the stream's
    episodes as the dashboard's and ``interact --learn``'s teaching does; their joint angles."""
    from rnnpb.demonstrator import MirrorMapping
    from rnnpb.interaction.episodes import EpisodeCutter

    mapping = MirrorMapping(placed_body(config.distance), dt=config.dt)
    cutter = EpisodeCutter(mapping=mapping)
    out = []
    for t, (u, h) in enumerate(zip(sensory, hands, strict=True)):
        episode = cutter.observe(t, u, "novel", h)
        if episode is not None:
            out.append(episode.motor)
            cutter.reset()
    return out


def follow(model, sensory: np.ndarray, labels: list[str]) -> dict[str, Any]:
    """Another performer's stream through the robot (default on-line settings, the command
    filter in the loop): what it recognised and which commands the filter changed."""
    from rnnpb.interaction import InteractionLoop
    from rnnpb.model import MirrorSystem, OnlineConfig
    from rnnpb.robot import ELBOW_AT_ZERO_PITCH
    from rnnpb.safety import CommandFilter
    from rnnpb.sources import ArraySensorySource

    rest = np.array([0.0, 0.0, 0.0, ELBOW_AT_ZERO_PITCH] * 2)
    records = []
    with ArraySensorySource(sensory) as source:
        choice = OnlineConfig.for_model(model)  # as `rnnpb interact` chooses
        mirror = MirrorSystem(model, choice.config, recognition=choice.recognition)
        InteractionLoop(mirror, source, command_filter=CommandFilter(initial=rest)).run(
            on_step=records.append
        )
    return {
        "labels": list(labels),
        "recognised": [r.recognised for r in records],
        "filtered": [bool(r.filtered) for r in records],
        "pb": np.array([r.pb for r in records]),
    }


def judged_steps(labels: list[str], settle_steps: int) -> np.ndarray:
    """(T,) bool: steps at least ``settle_steps`` after their movement began."""
    judged = np.ones(len(labels), bool)
    for t in range(len(labels)):
        if t == 0 or labels[t] != labels[t - 1]:
            judged[t : t + settle_steps] = False
    return judged


def measure(runs: list[dict[str, Any]], settle_steps: int) -> dict[str, Any]:
    """Recognised share of judged steps, per movement and overall; filtered share of commands."""
    right = judged = filtered = steps = 0
    per: dict[str, list[int]] = {}
    for run in runs:
        mask = judged_steps(run["labels"], settle_steps)
        for t in np.flatnonzero(mask):
            ok = run["recognised"][t] == run["labels"][t]
            per.setdefault(run["labels"][t], [0, 0])
            per[run["labels"][t]][0] += int(ok)
            per[run["labels"][t]][1] += 1
            right += int(ok)
            judged += 1
        filtered += sum(run["filtered"])
        steps += len(run["filtered"])
    return {
        "recognised_share": right / judged if judged else float("nan"),
        "judged_steps": judged,
        "per_movement": {k: v[0] / v[1] for k, v in per.items()},
        "filtered_share": filtered / steps if steps else float("nan"),
        "commands": steps,
    }


def demonstrator_reach(seed: int) -> dict[str, float]:
    """Mean distance (metres) from reached to requested robot hands over the learning sets:
    the safe retargeting and the paper's plain inverse kinematics on the same hands."""
    from rnnpb.demonstrator import LEARNING_SETS, MirrorMapping, learning_set
    from rnnpb.robot import forward_kinematics, inverse_kinematics

    safe, plain = [], []
    for name in LEARNING_SETS:
        for sequence in learning_set(name, seed=seed):
            targets = MirrorMapping().robot_hand_targets(sequence.meta["measured"])
            for joints, out in (
                (sequence.motor, safe),
                (inverse_kinematics(targets).joints, plain),
            ):
                reached, _ = forward_kinematics(joints)
                out.append(np.linalg.norm(reached - targets, axis=-1).ravel())
    mean_safe = float(np.mean(np.concatenate(safe)))
    mean_plain = float(np.mean(np.concatenate(plain)))
    if mean_plain > 0:
        ratio = mean_safe / mean_plain
    else:
        ratio = 1.0 if mean_safe == mean_plain else float("inf")
    return {"safe_m": mean_safe, "plain_m": mean_plain, "ratio": ratio}
