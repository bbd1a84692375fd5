"""Distributions over seeds and draws: medians, shares and their 95 % bootstrap intervals.

A measure taken over several trained networks and several draws of the user is a sample; the
report gives its median (or the share of runs within one of the paper's limits) with a
percentile bootstrap confidence interval (:func:`scipy.stats.bootstrap`, ``method=
"percentile"``, seeded so that a report repeats). A sample whose values are all equal has the
interval of zero width at that value; an empty sample has none (NaN).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

CONFIDENCE = 0.95
RESAMPLES = 2000
BOOTSTRAP_SEED = 0


@dataclass(frozen=True)
class Interval:
    """A statistic of a sample and its bootstrap confidence interval."""

    value: float
    low: float
    high: float
    n: int  # the sample's size

    def describe(self, digits: int = 1) -> str:
        """``4.0 [3.0, 5.0]``; ``–`` for an empty sample."""
        if self.n == 0 or math.isnan(self.value):
            return "–"
        return f"{self.value:.{digits}f} [{self.low:.{digits}f}, {self.high:.{digits}f}]"


def bootstrap_interval(
    sample: Sequence[float] | np.ndarray,
    statistic: Callable[[np.ndarray], float] = np.median,
    confidence: float = CONFIDENCE,
    resamples: int = RESAMPLES,
    seed: int = BOOTSTRAP_SEED,
) -> Interval:
    """``statistic`` of ``sample`` (shape (n,)) and its percentile bootstrap interval;
    ``statistic(x, axis=...)`` reduces along an axis, as :func:`numpy.median` does."""
    from scipy.stats import bootstrap

    values = np.asarray(sample, dtype=np.float64).ravel()
    n = len(values)
    if n == 0:
        return Interval(math.nan, math.nan, math.nan, 0)
    value = float(statistic(values, axis=0))
    if np.all(values == values[0]):
        # Every resample is the sample itself; scipy would warn of a degenerate distribution.
        return Interval(value, value, value, n)
    result = bootstrap(
        (values,),
        lambda x, axis: statistic(x, axis=axis),
        vectorized=True,
        confidence_level=confidence,
        n_resamples=resamples,
        method="percentile",
        rng=np.random.default_rng(seed),
    )
    low, high = result.confidence_interval
    return Interval(value, float(low), float(high), n)


def median_interval(values: Sequence[float | None]) -> Interval:
    """The median of the events that happened (``None``, never, left out) and its interval."""
    return bootstrap_interval([v for v in values if v is not None and not _nan(v)])


def share_within(values: Sequence[float | None], limit: float) -> Interval:
    """The share of ``values`` at most ``limit`` (``None``, never, is not) and its interval."""
    hits = [1.0 if v is not None and not _nan(v) and v <= limit else 0.0 for v in values]
    return bootstrap_interval(hits, np.mean)


def _nan(value: float) -> bool:
    return isinstance(value, float) and math.isnan(value)
