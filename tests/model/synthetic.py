"""A small synthetic learning set of our own: three distinct cyclic sensory-motor patterns."""

import numpy as np

from rnnpb.sequences import Sequence

LIMITS = np.array([[-2.0, 2.0]] * 8)
PERIOD = 12


def pattern_values(kind: int, phase: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sensory (n, 4) and motor (n, 8, radians) of pattern ``kind`` at the given phases."""
    s, c = np.sin(phase), np.cos(phase)
    z = np.zeros_like(phase)
    if kind == 0:  # horizontal, opposite phase
        u = np.stack([0.5 + 0.3 * s, 0.5 + z, 0.5 - 0.3 * s, 0.5 + z], 1)
    elif kind == 1:  # vertical, in phase
        u = np.stack([0.5 + z, 0.5 + 0.3 * s, 0.5 + z, 0.5 + 0.3 * s], 1)
    else:  # rotation, in phase
        u = np.stack([0.5 + 0.25 * c, 0.5 + 0.25 * s, 0.5 + 0.25 * c, 0.5 + 0.25 * s], 1)
    motor = np.concatenate([(u - 0.5) * 3.0, (u[:, ::-1] - 0.5) * 2.0], axis=1)
    return u, motor


def make_sequences(
    n_samples: int = 2,
    n_steps: int = 50,
    noise: float = 0.01,
    seed: int = 0,
    kinds: tuple[int, ...] = (0, 1, 2),
) -> list[Sequence]:
    rng = np.random.default_rng(seed)
    sequences = []
    for kind in kinds:
        for sample in range(n_samples):
            phase = 2 * np.pi * np.arange(n_steps) / PERIOD + rng.uniform(0, 2 * np.pi)
            u, motor = pattern_values(kind, phase)
            u = u + noise * rng.standard_normal(u.shape)
            sequences.append(Sequence(u, motor, str(kind), f"synthetic {kind}/{sample}"))
    return sequences
