"""Training data as in the paper: per pattern, noisy demonstrations of 50 steps of 0.4 s.

Every sample has its own random stream, derived from ``(seed, pattern, sample index)``, so a
sample is the same whichever other patterns or learning sets are generated with it.
"""

from __future__ import annotations

import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.robot.camera import RobotCamera
from rnnpb.sequences import Sequence

from ._mapping import MirrorMapping
from ._user import MOVEMENTS, PATTERNS, PatternConfig, perform, resolve_pattern

LEARNING_SETS: dict[str, tuple[str, ...]] = {
    "1": ("1", "2", "3"),
    "2": ("2", "3", "4"),
    "3": ("1", "3", "4"),
    "4": ("1", "2", "4"),
    "full": ("1", "2", "3", "4"),
}
"""The paper's learning sets 1-4 (three patterns each; the fourth is the novel one) and the
larger set of section 3.4."""

DEFAULT_STEPS = 50
DEFAULT_SAMPLES = 2


def learning_set_patterns(name: str | int) -> tuple[str, ...]:
    """Pattern names of a learning set (``1``-``4`` or ``full``)."""
    key = str(name).strip().lower()
    if key not in LEARNING_SETS:
        raise ConfigError(f"unknown learning set {name!r} (known: {', '.join(LEARNING_SETS)})")
    return LEARNING_SETS[key]


def novel_pattern(learning_set: str | int) -> str:
    """The pattern a three-pattern learning set leaves out (the paper's novel pattern)."""
    learned = learning_set_patterns(learning_set)
    rest = [p for p in PATTERNS if p not in learned]
    if len(rest) != 1:
        raise ConfigError(f"learning set {learning_set!r} holds every pattern: none is novel")
    return rest[0]


def sample_rng(seed: int, pattern: str, sample: int) -> np.random.Generator:
    """The random stream of one demonstration."""
    return np.random.default_rng(
        [int(seed), MOVEMENTS.index(resolve_pattern(pattern)), int(sample)]
    )


def demonstration(
    pattern: str,
    rng: np.random.Generator,
    n_steps: int = DEFAULT_STEPS,
    config: PatternConfig | None = None,
    mapping: MirrorMapping | None = None,
    camera: RobotCamera | None = None,
    source: str = "",
) -> Sequence:
    """One demonstration of a pattern as a paired sensory/motor :class:`Sequence`.

    The sensory values are the measured hands as the robot camera sees them; the motor values
    are the robot's joint angles (radians) from the mirror mapping and the safe retargeting
    of the same measured hands (the paper's inverse kinematics where it is safe). ``meta``
    holds ``hands`` (n_steps, 2, 3), ``measured`` (n_steps, 2, 3), ``phase`` (n_steps,) and
    the retargeting's ``ik_residual`` (n_steps, 2).
    """
    pattern = resolve_pattern(pattern)
    config = config or PatternConfig()
    mapping = mapping or MirrorMapping(config.body, dt=config.dt)
    camera = camera or RobotCamera()
    if n_steps < 2:
        raise ConfigError(f"a demonstration needs at least 2 steps, got {n_steps}")
    motion = perform([(pattern, n_steps)], config, rng)
    ik = mapping.retarget(motion.measured)
    return Sequence(
        sensory=camera.sensory_from_hands(motion.measured),
        motor=ik.joints,
        pattern=pattern,
        source=source or f"synthetic pattern {pattern}",
        meta={
            "hands": motion.hands,
            "measured": motion.measured,
            "phase": motion.phase,
            "ik_residual": ik.residual,
            "dt": config.dt,
        },
    )


def pattern_dataset(
    seed: int = 0,
    patterns: tuple[str, ...] = PATTERNS,
    samples_per_pattern: int = DEFAULT_SAMPLES,
    n_steps: int = DEFAULT_STEPS,
    config: PatternConfig | None = None,
) -> list[Sequence]:
    """Demonstrations of each pattern (``samples_per_pattern`` each, pattern by pattern).

    Sample ``k`` of a pattern has ``meta["sample"] == k`` and ``source``
    ``"synthetic pattern P sample k seed S"``.
    """
    if samples_per_pattern < 1:
        raise ConfigError(f"samples_per_pattern must be >= 1, got {samples_per_pattern}")
    config = config or PatternConfig()
    mapping = MirrorMapping(config.body, dt=config.dt)
    camera = RobotCamera()
    out = []
    for pattern in (resolve_pattern(p) for p in patterns):
        for k in range(samples_per_pattern):
            seq = demonstration(
                pattern,
                sample_rng(seed, pattern, k),
                n_steps,
                config,
                mapping,
                camera,
                f"synthetic pattern {pattern} sample {k + 1} seed {seed}",
            )
            seq.meta["sample"] = k + 1
            out.append(seq)
    return out


def learning_set(
    name: str | int,
    seed: int = 0,
    samples_per_pattern: int = DEFAULT_SAMPLES,
    n_steps: int = DEFAULT_STEPS,
    config: PatternConfig | None = None,
) -> list[Sequence]:
    """The training sequences of a learning set (paper: 3 patterns x 2 samples of 50 steps)."""
    return pattern_dataset(seed, learning_set_patterns(name), samples_per_pattern, n_steps, config)
