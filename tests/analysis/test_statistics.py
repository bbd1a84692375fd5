"""The bootstrap intervals against answers known in closed form."""

import math

import numpy as np
import pytest
from scipy.stats import binom

from rnnpb.analysis import statistics


def test_share_interval_matches_the_binomial_quantiles():
    # Resampling 400 draws of which 100 are hits gives Binomial(400, 1/4) / 400 hits: the
    # percentile interval is that distribution's 2.5 % and 97.5 % quantiles.
    values = [1] * 100 + [50] * 300
    found = statistics.share_within(values, limit=10)
    assert found.value == 0.25 and found.n == 400
    assert found.low == pytest.approx(binom.ppf(0.025, 400, 0.25) / 400, abs=0.006)
    assert found.high == pytest.approx(binom.ppf(0.975, 400, 0.25) / 400, abs=0.006)


def test_mean_interval_of_a_normal_sample_is_about_two_standard_errors():
    sample = np.random.default_rng(1).normal(5.0, 2.0, size=2000)
    found = statistics.bootstrap_interval(sample, np.mean)
    half = 1.96 * sample.std(ddof=1) / math.sqrt(len(sample))
    assert found.low == pytest.approx(sample.mean() - half, abs=0.2 * half)
    assert found.high == pytest.approx(sample.mean() + half, abs=0.2 * half)


def test_median_leaves_out_events_that_never_happened_and_repeats():
    values = [3, 4, None, 5, 4, 6, None, 2]
    first = statistics.median_interval(values)
    assert first.value == 4.0 and first.n == 6 and first.low <= 4.0 <= first.high
    assert statistics.median_interval(values) == first  # seeded


def test_constant_and_empty_samples():
    assert statistics.median_interval([7, 7, 7]) == statistics.Interval(7.0, 7.0, 7.0, 3)
    empty = statistics.median_interval([None, None])
    assert empty.n == 0 and math.isnan(empty.value) and empty.describe() == "–"
