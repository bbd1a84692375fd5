"""Scripted interactions: what the user does in front of the robot in the paper's experiments.

A :class:`Scenario` holds, per step, the user's 3-D hands, the sensory vector the robot
perceives, the motor vector a perfect imitator would produce (the mirror mapping + IK of the
user's hands: "what the robot should do") and the ground truth (pattern label or ``"pause"``,
whether the pattern is novel, the switch steps).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.robot.camera import RobotCamera

from ._datasets import learning_set_patterns, novel_pattern
from ._mapping import MirrorMapping
from ._user import PAUSE, PatternConfig, perform, resolve_pattern


@dataclass(frozen=True)
class Scenario:
    """An interaction script with its ground truth.

    Attributes
    ----------
    name : str
    hands : array, shape (n_steps, 2, 3)
        The user's hands as moved (robot frame, metres; left hand first).
    sensory : array, shape (n_steps, 4)
        ``lhy lhz rhy rhz`` as the robot's camera measures them (with sensor noise).
    motor : array, shape (n_steps, 8)
        The robot joint angles (radians) that imitate the user (mirror mapping + IK).
    labels : tuple of str
        Per step: the pattern being performed, or ``"pause"``.
    switch_steps : tuple of int
        Steps at which the label changes (the first step of each new segment).
    novel : tuple of str
        Patterns the robot has not learned (empty when unknown or none).
    phase : array, shape (n_steps,)
        The user's movement phase (radians, unwrapped).
    dt : float
        Seconds per step.
    """

    name: str
    hands: np.ndarray
    sensory: np.ndarray
    motor: np.ndarray
    labels: tuple[str, ...]
    switch_steps: tuple[int, ...]
    novel: tuple[str, ...]
    phase: np.ndarray
    dt: float

    @property
    def n_steps(self) -> int:
        return len(self.labels)

    def truth(self, step: int) -> dict[str, Any]:
        """Ground truth of one step, as an :class:`Observation` carries it."""
        label = self.labels[step]
        return {
            "step": step,
            "pattern": label,
            "pause": label == PAUSE,
            "novel": label in self.novel,
            "switch": step in self.switch_steps,
            "phase": float(self.phase[step]),
            "hands": self.hands[step].copy(),
            "motor": self.motor[step].copy(),
        }


def make_scenario(
    segments: list[tuple[str, int]],
    seed: int = 0,
    config: PatternConfig | None = None,
    name: str = "",
    novel: tuple[str, ...] = (),
    transition_steps: int = 2,
) -> Scenario:
    """A scenario from segments ``[(pattern or "pause", n_steps), ...]`` performed in order."""
    config = config or PatternConfig()
    rng = np.random.default_rng(seed)
    motion = perform(segments, config, rng, transition_steps=transition_steps)
    labels = motion.labels
    switches = tuple(t for t in range(1, len(labels)) if labels[t] != labels[t - 1])
    mapping = MirrorMapping(config.body, dt=config.dt)
    return Scenario(
        name=name or " -> ".join(f"{label} x{n}" for label, n in segments),
        hands=motion.hands,
        sensory=RobotCamera().sensory_from_hands(motion.measured),
        motor=mapping.motor_from_hands(motion.hands),
        labels=labels,
        switch_steps=switches,
        novel=tuple(resolve_pattern(p) for p in novel),
        phase=motion.phase,
        dt=config.dt,
    )


def held_scenario(
    pattern: str = "1", n_steps: int = 150, seed: int = 0, config: PatternConfig | None = None
) -> Scenario:
    """The user keeps performing one pattern."""
    pattern = resolve_pattern(pattern)
    return make_scenario([(pattern, n_steps)], seed, config, f"pattern {pattern} held")


def pause_scenario(
    pattern: str = "1",
    before: int = 75,
    pause: int = 5,
    after: int = 45,
    seed: int = 0,
    config: PatternConfig | None = None,
) -> Scenario:
    """The user performs a pattern, freezes the hands for ``pause`` steps, then goes on
    (paper section 3.1: steps 75-80 of pattern 1)."""
    pattern = resolve_pattern(pattern)
    return make_scenario(
        [(pattern, before), (PAUSE, pause), (pattern, after)],
        seed,
        config,
        f"pattern {pattern} with a {pause}-step pause",
    )


def switch_scenario(
    patterns: tuple[str, ...] = ("1", "2", "3"),
    steps_each: int = 50,
    seed: int = 0,
    config: PatternConfig | None = None,
) -> Scenario:
    """The user performs patterns one after another (paper section 3.2: 1, 2, 3, about 20 s
    each); any ordered pair is ``switch_scenario((a, b))``."""
    if len(patterns) < 1:
        raise ConfigError("switch_scenario needs at least one pattern")
    names = [resolve_pattern(p) for p in patterns]
    return make_scenario(
        [(p, steps_each) for p in names], seed, config, "switch " + " -> ".join(names)
    )


def novel_scenario(
    learning_set: str | int = "1",
    n_steps: int = 150,
    seed: int = 0,
    config: PatternConfig | None = None,
) -> Scenario:
    """The user performs the pattern a learning set left out (paper section 3.3)."""
    learning_set_patterns(learning_set)
    pattern = novel_pattern(learning_set)
    return make_scenario(
        [(pattern, n_steps)],
        seed,
        config,
        f"novel pattern {pattern} for learning set {learning_set}",
        novel=(pattern,),
    )


def routine_segments(
    routine: list[tuple[str, int]],
    seed: int = 0,
    config: PatternConfig | None = None,
    timing_jitter: float = 0.1,
) -> list[tuple[str, int]]:
    """The steps a person gives each part of a routine: ``routine`` is ``[(pattern, cycles),
    ...]``; each part lasts ``cycles`` periods, stretched or shortened by a factor drawn from
    ``1 + timing_jitter * N(0, 1)`` (clipped to [0.6, 1.4]): people do not count cycles
    exactly. Returns ``[(pattern, n_steps), ...]`` for :func:`make_scenario`."""
    config = config or PatternConfig()
    if not routine:
        raise ConfigError("a routine needs at least one part")
    if not 0 <= timing_jitter < 0.5:
        raise ConfigError(f"timing_jitter must be in [0, 0.5), got {timing_jitter}")
    rng = np.random.default_rng([seed, 7919])
    segments = []
    for pattern, cycles in routine:
        if int(cycles) < 1:
            raise ConfigError(f"routine part {pattern!r}: cycles must be >= 1, got {cycles}")
        factor = float(np.clip(1 + timing_jitter * rng.standard_normal(), 0.6, 1.4))
        steps = max(3, round(int(cycles) * config.period_steps * factor))
        segments.append((resolve_pattern(pattern), steps))
    return segments


def routine_scenario(
    routine: list[tuple[str, int]],
    seed: int = 0,
    config: PatternConfig | None = None,
    timing_jitter: float = 0.1,
    repeats: int = 1,
) -> Scenario:
    """The user performs a routine (``[(pattern, cycles), ...]``, :func:`routine_segments`),
    ``repeats`` times in a row, each time with its own timing; the patterns blend into each
    other over two steps as in every scenario."""
    if repeats < 1:
        raise ConfigError(f"repeats must be >= 1, got {repeats}")
    segments = []
    for r in range(repeats):
        segments += routine_segments(routine, seed * 1000 + r, config, timing_jitter)
    name = "routine " + ",".join(f"{resolve_pattern(p)}*{c}" for p, c in routine)
    return make_scenario(segments, seed, config, name)


def scenario_arrays(scenario: Scenario) -> tuple[np.ndarray, list[dict[str, Any]]]:
    """The sensory stream (n_steps, 4) and the per-step truth dicts of a scenario."""
    return scenario.sensory.copy(), [scenario.truth(t) for t in range(scenario.n_steps)]
