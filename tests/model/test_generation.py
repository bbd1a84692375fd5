"""Closed-loop generation from each learned PB falls onto that pattern's limit cycle."""

import numpy as np
import pytest

from rnnpb.errors import ConfigError
from rnnpb.model import generate

from .synthetic import PERIOD, pattern_values


def _period(signal: np.ndarray) -> int:
    """The lag (2..40) of the autocorrelation's highest peak."""
    x = signal - signal.mean(axis=0)
    scores = [np.sum(x[:-lag] * x[lag:]) / np.sum(x[:-lag] ** 2) for lag in range(2, 41)]
    return int(np.argmax(scores)) + 2


@pytest.mark.parametrize("pattern", ["0", "1", "2"])
def test_generation_from_a_learned_pb_is_that_patterns_limit_cycle(trained, pattern):
    generated = generate(
        trained,
        trained.pattern_pb[pattern],
        400,
        initial_context=trained.pattern_initial_context(pattern),
    )
    steady = generated.sensory[200:]
    # Same period as learned (12 steps) ...
    assert abs(_period(steady) - PERIOD) <= 1
    # ... and still cycling, not decayed to a fixed point.
    assert np.ptp(steady, axis=0).max() > 0.3
    # Shape: one steady cycle matches the true pattern at the best phase to RMS < 0.05.
    cycle = steady[:PERIOD]
    errors = []
    for shift in np.linspace(0, 2 * np.pi, 120, endpoint=False):
        truth, _ = pattern_values(int(pattern), 2 * np.pi * np.arange(PERIOD) / PERIOD + shift)
        errors.append(np.sqrt(np.mean((cycle - truth) ** 2)))
    assert min(errors) < 0.05
    # The limit cycle repeats itself: two consecutive cycles agree closely.
    assert np.sqrt(np.mean((steady[:PERIOD] - steady[PERIOD : 2 * PERIOD]) ** 2)) < 0.02


def test_generation_rejects_bad_pb(trained):
    with pytest.raises(ConfigError, match="PB must have 4 values"):
        generate(trained, [0.5, 0.5], 10)
    with pytest.raises(ConfigError, match="in \\[0, 1\\]"):
        generate(trained, [0.5, 1.5, 0.5, 0.5], 10)
    with pytest.raises(ConfigError, match="steps"):
        generate(trained, [0.5] * 4, 0)
