"""One structure detector: the metrics' periodicity, on-line novelty's structure and the
recording's cycle cutter all read the lagged self-difference of :mod:`rnnpb.structure`.

The metrics' periodicity must give what it gave before, bit for bit (the demo's results depend
on it); the reference below is its implementation before the shared module, kept here only to
hold the new one to it. Novelty's structure is held to a step-by-step reference. The cutter's
period is held to its earlier autocorrelation on random signals and on every pattern and shape
the demonstrator performs.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rnnpb import structure
from rnnpb.analysis import metrics
from rnnpb.demonstrator import (
    NEW_SHAPES,
    PATTERNS,
    UNSTRUCTURED,
    Imperfection,
    PatternConfig,
    make_scenario,
)
from rnnpb.learning_phase import cycle_bounds
from rnnpb.model.recognition import RecognitionConfig, _structure

# The range the old cycle cutter looked for a period in (its references below).
MIN_PERIOD, MAX_PERIOD = 4, 60


# --- the references: the three detectors as they were ---------------------------------------
def _reference_shifted(x, period):
    whole = int(math.floor(period))
    if period == whole:
        return x[whole:]
    from scipy.interpolate import CubicSpline

    n = len(x) - int(math.ceil(period))
    return CubicSpline(np.arange(len(x)), x, axis=0)(np.arange(n) + period)


def _reference_return_error(x, period):
    x = np.asarray(x, dtype=np.float64)
    if x.ndim == 1:
        x = x[:, None]
    spread = np.sqrt(np.mean((x - x.mean(axis=0)) ** 2))
    if spread < 1e-9:
        return 0.0
    ahead = _reference_shifted(x, period)
    return float(np.sqrt(np.mean((ahead - x[: len(ahead)]) ** 2)) / spread)


def _reference_periodicity(x, max_period=60, tolerance=0.1):
    x = np.asarray(x, dtype=np.float64)
    if x.ndim == 1:
        x = x[:, None]
    max_period = min(max_period, len(x) // 3)
    errors = {p: _reference_return_error(x, p) for p in range(1, max_period + 1)}
    best_period, best_error = float(min(errors, key=errors.__getitem__)), min(errors.values())
    for p in sorted(errors):
        if not (
            errors[p] <= errors.get(p - 1, math.inf) and errors[p] <= errors.get(p + 1, math.inf)
        ):
            continue
        refined = float(p)
        if p - 1 in errors and p + 1 in errors:
            left, mid, right = errors[p - 1], errors[p], errors[p + 1]
            curvature = left - 2 * mid + right
            if curvature > 0:
                refined = p + float(np.clip(0.5 * (left - right) / curvature, -0.5, 0.5))
        refined_error = _reference_return_error(x, refined) if refined != p else errors[p]
        period, error = (
            (refined, refined_error) if refined_error < errors[p] else (float(p), errors[p])
        )
        if error < best_error:
            best_period, best_error = period, error
        if error < tolerance:
            return period, error, period
    return None, best_error, best_period


def _reference_structure(history, config):
    """Each period's cycle against the one before, step by step (no shared sums)."""
    low, high = config.lags
    gap = np.isnan(history).any(axis=1)
    clean = len(history) - 1 - int(np.flatnonzero(gap)[-1]) if gap.any() else len(history)
    values = []
    for lag in range(low, high + 1):
        window = max(lag, config.structure_steps)
        if lag + window > clean:
            break
        last, before = (
            history[len(history) - window :],
            history[len(history) - window - lag : len(history) - lag],
        )
        compared = history[len(history) - window - lag :]
        variance = float(np.mean(np.var(compared, axis=0)))
        values.append(
            np.mean((last - before) ** 2) / (2 * variance) if variance > 1e-12 else np.nan
        )
    if not values or np.isnan(values).all():
        return float("nan"), False
    return float(np.nanmin(values)), len(values) == high - low + 1


def _reference_dominant_period(signal, min_period=MIN_PERIOD, max_period=MAX_PERIOD):
    x = np.asarray(signal, dtype=np.float64)
    x = x - x.mean()
    energy = float(x @ x)
    max_period = min(max_period, len(x) // 2)
    if energy <= 1e-12 or max_period < min_period + 2:
        return None
    lags = np.arange(1, max_period + 2)
    correlation = np.array([x[:-k] @ x[k:] / energy * len(x) / (len(x) - k) for k in lags])
    peaks = [
        i
        for i in range(min_period - 1, len(lags) - 1)
        if correlation[i] >= correlation[i - 1]
        and correlation[i] >= correlation[i + 1]
        and correlation[i] > 0.3
        and correlation[i] - correlation[:i].min() >= 0.6
    ]
    if not peaks:
        return None
    best = max(correlation[i] for i in peaks)
    return int(lags[next(i for i in peaks if correlation[i] >= 0.8 * best)])


# --- signals ----------------------------------------------------------------------------------
def _signals(seed: int, count: int):
    """Random walks, noise, noisy cycles of whole and fractional periods, flat stretches."""
    rng = np.random.default_rng(seed)
    for k in range(count):
        steps = int(rng.integers(10, 200))
        dims = int(rng.integers(1, 5))
        kind = k % 5
        t = np.arange(steps)[:, None]
        if kind == 0:
            x = rng.normal(size=(steps, dims))
        elif kind == 1:
            x = np.cumsum(rng.normal(size=(steps, dims)), axis=0)
        elif kind == 2:
            period = rng.uniform(3, 40)
            x = np.sin(2 * np.pi * t / period + rng.uniform(0, 6, dims))
            x = x + rng.uniform(0, 0.3) * rng.normal(size=(steps, dims))
        elif kind == 3:
            period = int(rng.integers(4, 30))
            x = np.tile(rng.uniform(size=(period, dims)), (steps // period + 1, 1))[:steps]
            x = x + rng.uniform(0, 0.05) * rng.normal(size=(steps, dims))
        else:
            x = np.full((steps, dims), rng.uniform())
            x[rng.integers(0, steps) :] += rng.uniform(0, 1e-3)
        yield x


def _performed():
    """Every pattern, new shape and unstructured movement the demonstrator performs, with
    and without its imperfections."""
    for imperfect in (True, False):
        config = PatternConfig() if imperfect else PatternConfig(imperfection=Imperfection.none())
        for movement in (*PATTERNS, *NEW_SHAPES, *UNSTRUCTURED):
            for seed in (0, 1):
                yield movement, make_scenario([(movement, 96)], seed=seed, config=config).sensory


# --- the metrics' periodicity: bit for bit ------------------------------------------------------
def test_periodicity_gives_what_it_gave_before_bit_for_bit():
    signals = [*_signals(0, 120), *(x for _, x in _performed())]
    for x in signals:
        for max_period, tolerance in ((60, 0.1), (8, 0.3)):
            new = metrics.periodicity(x, max_period, tolerance)
            old = _reference_periodicity(x, max_period, tolerance)
            assert (new.period, new.return_error, new.best_period) == old
        for period in (1, 3, 4.5, 7.25):
            if period < len(x) - 1:
                assert metrics.return_error(x, period) == _reference_return_error(x, period)


# --- novelty's structure: the cycle differences, step by step -----------------------------------
def test_recognitions_structure_is_each_periods_cycle_against_the_one_before():
    config = RecognitionConfig()
    rng = np.random.default_rng(1)
    histories = [x[-config.history :] for x in _signals(2, 300) if len(x) >= 40]
    histories += [x[-config.history :] for _, x in _performed()]
    cases = 0
    for history in histories:
        history = np.array(history[:, :4] if history.shape[1] >= 4 else history)
        for gaps in (0, 1, 3):
            gapped = history.copy()
            for _ in range(gaps):  # a hand lost somewhere in the past
                gapped[rng.integers(0, len(gapped)), rng.integers(0, gapped.shape[1])] = np.nan
            new, old = _structure(gapped, config), _reference_structure(gapped, config)
            assert new[1] == old[1]
            assert new[0] == pytest.approx(old[0], rel=1e-9, abs=1e-12) or (
                math.isnan(new[0]) and math.isnan(old[0])
            )
            cases += not math.isnan(old[0])
    assert cases > 300  # most cases measured a structure


# --- the recording's period: the same on signals and on every performed movement ----------------
def test_the_cutters_period_is_the_autocorrelations():
    for x in _signals(3, 400):
        signal = x[:, 0]
        assert structure.first_period(signal, MIN_PERIOD, MAX_PERIOD) == (
            _reference_dominant_period(signal)
        )


def test_every_performed_movement_is_cut_at_the_same_periods():
    """On the demonstrator's patterns, new shapes and unstructured movements, over the
    growing windows the episode cutter sees, the period found and the cycles cut are those of
    the autocorrelation computed directly."""
    checked = 0
    for movement, sensory in _performed():
        for end in range(2 * MIN_PERIOD, len(sensory) + 1, 3):
            x = sensory[:end]
            centred = x - x.mean(axis=0)
            _, _, vt = np.linalg.svd(centred, full_matrices=False)
            component = centred @ vt[0]
            component = np.convolve(np.pad(component, 1, mode="edge"), np.ones(3) / 3, "valid")
            period = structure.first_period(component, MIN_PERIOD, MAX_PERIOD)
            assert period == _reference_dominant_period(component), (movement, end)
            checked += period is not None
        if movement in PATTERNS or movement in NEW_SHAPES:
            assert cycle_bounds(sensory), movement
    assert checked > 200


def test_the_self_difference_is_zero_at_the_period_and_twice_the_variance_without_one():
    t = np.arange(240)
    cycle = np.sin(2 * np.pi * t / 12)
    assert structure.self_difference(cycle, 12) == pytest.approx(0.0, abs=1e-20)
    noise = np.random.default_rng(5).normal(size=(4000, 2))
    assert structure.self_difference(noise, 7) == pytest.approx(2 * noise.var(), rel=0.05)
    recent = structure.cycle_differences(cycle[:, None], np.arange(6, 19), 12)
    assert int(np.argmin(recent)) + 6 == 12 and recent.min() < 1e-20
    assert structure.periodicity(cycle, 60, 0.1).period == 12
    assert structure.first_period(cycle, 4, 60) == 12
