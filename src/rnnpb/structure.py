"""Whether a movement repeats, and with which period: one measure for recording, recognition
and the metrics.

The measure is the **self-difference** of a trajectory ``x`` (shape (T, D) or (T,)) at a lag
``k``: the mean squared difference between each step and the step ``k`` earlier,

    d(k) = mean_t |x[t] − x[t−k]|²,

over every step that has such a partner, or over the last ``steps`` steps only (what a
detector that looks at the recent past compares). It is 0 at the period of an exactly
periodic trajectory and about twice the variance where the movement does not repeat. Its
uses, each with its caller's thresholds:

* :func:`periodicity` (the metrics' periodicity, the attractor analysis): the smallest period,
  whole or fractional, whose return error ``sqrt(d(P)) / RMS(x − mean)`` is below a tolerance;
* :func:`first_period` (cutting a recording into cycles): the first strong peak of the
  autocorrelation of a centred signal, read off the self-difference through
  ``x[t]·x[t−k] = (x[t]² + x[t−k]² − (x[t] − x[t−k])²) / 2``;
* on-line novelty (:func:`cycle_differences`, for :mod:`rnnpb.model.recognition`): at each
  lag, the last cycle against the one before, relative to twice their variance.

NumPy (and SciPy's cubic spline for a fractional lag) only; nothing here knows a model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache

import numpy as np


def _as_steps(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, dtype=np.float64)
    return x[:, None] if x.ndim == 1 else x


def shifted(x: np.ndarray, lag: float) -> np.ndarray:
    """``x[t + lag]`` for every t it exists, shape (T - ceil(lag), D); between steps read off a
    cubic spline through ``x`` (shape (T, D))."""
    whole = int(math.floor(lag))
    if lag == whole:
        return x[whole:]
    from scipy.interpolate import CubicSpline

    n = len(x) - int(math.ceil(lag))
    return CubicSpline(np.arange(len(x)), x, axis=0)(np.arange(n) + lag)


def self_difference(x: np.ndarray, lag: float) -> float:
    """``d(lag)`` over every step that has a partner ``lag`` steps earlier; ``lag`` may be
    fractional (the partner read off a cubic spline). ``x`` shape (T, D) or (T,)."""
    x = _as_steps(x)
    ahead = shifted(x, lag)
    return float(np.mean((ahead - x[: len(ahead)]) ** 2))


def cycle_differences(x: np.ndarray, lags: np.ndarray, steps: int) -> np.ndarray:
    """How unlike the cycle before it the last cycle of ``x`` is, for a cycle of each whole
    lag ``k`` in ``lags`` (ascending; every ``k + max(k, steps) <= T``): ``d(k)`` of the last
    ``max(k, steps)`` steps against the same steps ``k`` earlier, relative to twice the
    variance (the mean over values) of all the steps compared; shape (len(lags),), NaN where
    those steps do not vary.

    The same movement at another speed gives the same value at its own period: one whole
    cycle (at least ``steps`` steps) is compared with the one before, and each lag is
    measured against the spread of its own steps. Near 0 at the period of a repeating
    movement; about 1 for one that does not repeat (uncorrelated steps), about 1.5 for a
    drift or a random walk.
    """
    x = _as_steps(x)
    rows, earlier, windows, spans = _cycle_layout(len(x), tuple(int(k) for k in lags), steps)
    difference = np.sum((x[rows] - x[earlier]) ** 2, axis=(1, 2)) / windows / x.shape[1]
    # The variance of the last n steps, for each lag's n = window + lag, from sums taken from
    # the newest step back (centred first, so that the sums stay exact).
    back = (x - x[len(x) - int(spans.max()) :].mean(axis=0))[::-1]
    first, second = np.cumsum(back, axis=0)[spans - 1], np.cumsum(back * back, axis=0)[spans - 1]
    n = spans[:, None]
    variance = np.mean(second / n - (first / n) ** 2, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(variance > 1e-12, difference / (2.0 * variance), np.nan)


@cache
def _cycle_layout(
    size: int, lags: tuple[int, ...], steps: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """For :func:`cycle_differences`: the steps each lag compares (L, W) and those ``k``
    earlier (outside a lag's window both the newest step, which adds nothing), each lag's
    window and the steps it spans (window + lag)."""
    k = np.asarray(lags, dtype=int)
    windows = np.maximum(k, steps)
    longest = int(windows.max())
    inside = np.arange(longest)[None] < windows[:, None]
    rows = np.where(inside, size - 1 - np.arange(longest)[None], size - 1)
    earlier = np.where(inside, rows - k[:, None], size - 1)
    return rows, earlier, windows, windows + k


def autocorrelation(signal: np.ndarray, lags: np.ndarray) -> np.ndarray:
    """The autocorrelation of the centred 1-D ``signal`` at each whole lag ``k`` in ``lags``:
    ``Σ x[t]·x[t−k] / Σ x²``, scaled by ``T / (T − k)`` for the pairs a lag leaves, each sum of
    products taken from the self-difference ``d(k)`` (module doc). NaN for a flat signal."""
    x = np.asarray(signal, dtype=np.float64)
    x = x - x.mean()
    n = len(x)
    energy = float(x @ x)
    squares = np.concatenate([[0.0], np.cumsum(x * x)])
    out = np.empty(len(lags))
    for i, k in enumerate(np.asarray(lags, dtype=int)):
        pairs = n - k
        head, tail = squares[pairs], squares[n] - squares[k]
        products = (head + tail - pairs * self_difference(x, k)) / 2
        out[i] = products / energy * n / pairs if energy > 0 else np.nan
    return out


def first_period(
    signal: np.ndarray,
    min_period: int,
    max_period: int,
    *,
    level: float = 0.3,
    rise: float = 0.6,
    share: float = 0.8,
) -> int | None:
    """The lag of the autocorrelation's first strong peak in [min_period, max_period], or None
    when the 1-D ``signal`` does not repeat.

    A peak is a local maximum inside the range, above ``level`` and at least ``rise`` above the
    lowest correlation at a shorter lag (a cycle's autocorrelation falls towards −1 at half
    its period and comes back, a drifting, shapeless movement's only decays); the first peak
    within ``share`` of the highest is taken, since later peaks are its multiples.
    """
    x = np.asarray(signal, dtype=np.float64)
    x = x - x.mean()
    energy = float(x @ x)
    max_period = min(max_period, len(x) // 2)
    if energy <= 1e-12 or max_period < min_period + 2:
        return None
    lags = np.arange(1, max_period + 2)
    correlation = autocorrelation(x, lags)
    peaks = [
        i
        for i in range(min_period - 1, len(lags) - 1)
        if correlation[i] >= correlation[i - 1]
        and correlation[i] >= correlation[i + 1]
        and correlation[i] > level
        and correlation[i] - correlation[:i].min() >= rise
    ]
    if not peaks:
        return None
    best = max(correlation[i] for i in peaks)
    first = next(i for i in peaks if correlation[i] >= share * best)
    return int(lags[first])


def return_error(x: np.ndarray, period: float) -> float:
    """``RMS(x[t+P] − x[t]) / RMS(x − mean)``, that is ``sqrt(d(P))`` relative to the
    trajectory's spread: 0 for an exactly periodic trajectory; ``P`` may be fractional."""
    x = _as_steps(x)
    spread = np.sqrt(np.mean((x - x.mean(axis=0)) ** 2))
    if spread < 1e-9:
        return 0.0
    return float(np.sqrt(self_difference(x, period)) / spread)


@dataclass(frozen=True)
class Periodicity:
    period: float | None  # steps, possibly fractional; None: not periodic within the tolerance
    return_error: float  # at the best period
    best_period: float


def _refined(errors: dict[int, float], p: int) -> float:
    """The whole period ``p`` at a local minimum of ``errors``, moved to the vertex of the
    parabola through its neighbours."""
    if p - 1 not in errors or p + 1 not in errors:
        return float(p)
    left, mid, right = errors[p - 1], errors[p], errors[p + 1]
    curvature = left - 2 * mid + right
    if curvature <= 0:
        return float(p)
    return p + float(np.clip(0.5 * (left - right) / curvature, -0.5, 0.5))


def periodicity(x: np.ndarray, max_period: int, tolerance: float) -> Periodicity:
    """The smallest period P ≤ ``max_period`` (and ≤ a third of the trajectory), whole or
    fractional, whose :func:`return_error` is below ``tolerance``; shape (T, D) or (T,).

    At each local minimum of the return error over whole periods, the period is refined by
    parabolic interpolation (a cycle of 11.5 steps returns only every 23 whole steps).
    """
    x = _as_steps(x)
    max_period = min(max_period, len(x) // 3)
    errors = {p: return_error(x, p) for p in range(1, max_period + 1)}
    best_period, best_error = float(min(errors, key=errors.__getitem__)), min(errors.values())
    for p in sorted(errors):
        at_minimum = errors[p] <= errors.get(p - 1, math.inf) and errors[p] <= errors.get(
            p + 1, math.inf
        )
        if not at_minimum:
            continue
        refined = _refined(errors, p)
        refined_error = return_error(x, refined) if refined != p else errors[p]
        period, error = (
            (refined, refined_error) if refined_error < errors[p] else (float(p), errors[p])
        )
        if error < best_error:
            best_period, best_error = period, error
        if error < tolerance:
            return Periodicity(period, error, period)
    return Periodicity(None, best_error, best_period)


def local_cycle_differences(x: np.ndarray, lags: np.ndarray, steps: int) -> np.ndarray:
    """:func:`cycle_differences` at every step: entry ``[t, i]`` is how unlike the cycle
    before it the cycle of lag ``lags[i]`` ending at step ``t`` is (the last
    ``max(k, steps)`` steps up to ``t`` against the same steps ``k`` earlier, relative to
    twice the variance of all the steps compared); shape (T, len(lags)), NaN where step ``t``
    has not enough history or those steps do not vary. ``x`` shape (T, D) or (T,)."""
    x = _as_steps(x)
    size, width = x.shape
    out = np.full((size, len(lags)), np.nan)
    # Sums from the start, centred first so that they stay exact.
    centred = x - x.mean(axis=0)
    first = np.concatenate([np.zeros((1, width)), np.cumsum(centred, axis=0)])
    second = np.concatenate([np.zeros((1, width)), np.cumsum(centred * centred, axis=0)])
    for i, k in enumerate(np.asarray(lags, dtype=int)):
        window = max(int(k), steps)
        span = window + int(k)
        if span > size:
            continue
        squared = np.zeros(size)
        squared[k:] = np.sum((x[k:] - x[:-k]) ** 2, axis=1)
        summed = np.concatenate([[0.0], np.cumsum(squared)])
        ends = np.arange(span - 1, size)
        difference = (summed[ends + 1] - summed[ends + 1 - window]) / window / width
        s1 = first[ends + 1] - first[ends + 1 - span]
        s2 = second[ends + 1] - second[ends + 1 - span]
        variance = np.mean(s2 / span - (s1 / span) ** 2, axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            out[ends, i] = np.where(variance > 1e-12, difference / (2.0 * variance), np.nan)
    return out


@dataclass(frozen=True)
class Stretch:
    """Steps ``start`` … ``stop - 1`` of a trajectory repeat themselves every ``period`` steps
    (a whole number: the median of the periods found along it)."""

    start: int
    stop: int
    period: int


def repeating_stretches(
    x: np.ndarray, min_period: int, max_period: int, *, steps: int = 12, level: float = 0.33
) -> list[Stretch]:
    """Where a trajectory repeats itself, and at which period (shape (T, D) or (T,)).

    At every step and every whole lag ``k`` in [``min_period``, ``max_period``] the last cycle
    is compared with the one before (:func:`local_cycle_differences`, the measure the on-line
    novelty detector uses); a step whose cycle of some lag differs by less than ``level``
    repeats, at the shortest such lag that is a local minimum of the difference (its
    multiples repeat too). The steps of both cycles compared are covered; covered steps next
    to each other form a stretch, whose period is the median of its steps' periods. A
    movement, a rest, another movement: each repeating part is its own stretch, and what lies
    between (a raise before a wave, the join of two takes) is in none.
    """
    x = _as_steps(x)
    lags = np.arange(max(2, min_period), max_period + 1)
    if len(x) < 2 * lags[0] or not len(lags):
        return []
    differences = local_cycle_differences(x, lags, steps)
    filled = np.where(np.isfinite(differences), differences, np.inf)
    period = np.zeros(len(x), dtype=int)
    for t in range(len(x)):
        row = filled[t]
        below = np.flatnonzero(row < level)
        if not below.size:
            continue
        i = int(below[0])
        while i + 1 < len(row) and row[i + 1] <= row[i]:
            i += 1  # down to the local minimum
        k = int(lags[i])
        first = t - max(k, steps) - k + 1
        period[max(first, 0) : t + 1] = np.where(
            period[max(first, 0) : t + 1] == 0, k, period[max(first, 0) : t + 1]
        )
    stretches: list[Stretch] = []
    covered = period > 0
    edges = np.diff(np.concatenate([[0], covered.astype(int), [0]]))
    for start, stop in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True):
        stretches.append(Stretch(int(start), int(stop), int(np.median(period[start:stop]))))
    return stretches
