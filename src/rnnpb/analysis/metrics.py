"""The measures of the paper's section 3, computed from arrays (no plotting, no I/O).

Definitions (written down once, used everywhere):

* **motor error** of a step: RMS over the 8 joints of (robot command − the joints that imitate
  the user), each joint normalized by its range of motion — 0 is perfect, 1 the whole range;
* **sensory error** of a step: RMS over the 4 hand coordinates of (prediction made one step
  before − observation), in view-plane units ([0, 1] spans the image);
* **locked** at step t: motor and sensory errors both stay below their thresholds for ``hold``
  consecutive steps starting at t (default thresholds 0.05 and 0.03, hold 6 steps = half of a
  12-step cycle); **steps to lock** from a start step s is t − s for the first such t;
* **phase lag**: the shift (in steps, sub-step by parabolic interpolation) that best aligns the
  robot's joints with the imitating joints; positive = the robot is behind the user;
* **PB settled** at step t: the PB changes by less than ``bound`` (max over units, per step)
  for ``hold`` consecutive steps from t;
* **periodicity** of a trajectory: the smallest period P ≤ ``max_period`` whose return error
  ``RMS(x[t+P] − x[t]) / RMS(x − mean)`` is below ``tolerance``. P need not be a whole number
  of steps (a cycle of 11.5 steps returns only every 23): at each local minimum of the return
  error over whole periods, the period is refined by parabolic interpolation and
  ``x[t+P]`` read off a cubic spline through the trajectory;
* **response case** to a novel pattern (paper section 3.3): 3 (unsteady) if the motor
  trajectory is not periodic; else 1 (a limit cycle like a learned one) if its cycle lies
  within ``similar`` of a learned pattern's closed-loop cycle in the cycle distance, else 2
  (a new limit cycle);
* **cycle distance**: both cycles sampled at 60 points of one period, the RMS difference
  minimized over circular shifts.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rnnpb import structure
from rnnpb.structure import Periodicity as Periodicity
from rnnpb.structure import return_error as return_error

MOTOR_LOCK_THRESHOLD = 0.05
SENSORY_LOCK_THRESHOLD = 0.03
LOCK_HOLD = 6
# Periodicity and the response cases: a trajectory repeats within ``MAX_PERIOD`` steps with a
# return error below ``PERIODIC_TOLERANCE``; a cycle within ``SIMILAR_CYCLE`` of a learned one
# (cycle distance) is "like" it.
MAX_PERIOD = 60
PERIODIC_TOLERANCE = 0.1
SIMILAR_CYCLE = 0.05

# --- the paper's figures, as the targets the measures are held to (section 3) ---------------
# Final training error (the paper: RMS below 3e-4; read as mean squared error per output).
TRAIN_ERROR_TARGET = 3e-4
LOCK_LIMIT = 10  # steps until locked on a learned pattern ("about 10")
SETTLE_LIMIT = 20  # steps until the PB settles ("about 20")
RELOCK_LIMIT = 5  # steps to re-lock after the pause ("a few")
SWITCH_LIMIT = 15  # steps until the robot follows a switch ("several")
# The larger set: 9 of the paper's 10 seeds followed every pattern.
LARGER_SET_FOLLOWS = 9
LARGER_SET_RUNS = 10
# The three response cases to a novel pattern, all of which the paper observes.
RESPONSE_CASES = (1, 2, 3)


def larger_set_share_met(success: int, runs: int) -> bool:
    """At least the paper's share (9 of 10) of ``runs`` followed every pattern."""
    return success >= math.ceil(LARGER_SET_FOLLOWS / LARGER_SET_RUNS * runs)


def motor_error(motor: np.ndarray, truth: np.ndarray, joint_limits: np.ndarray) -> np.ndarray:
    """Per-step normalized RMS joint error; shapes (T, 8), (T, 8), (8, 2) → (T,)."""
    span = joint_limits[:, 1] - joint_limits[:, 0]
    return np.sqrt(np.mean(((np.asarray(motor) - np.asarray(truth)) / span) ** 2, axis=1))


def sensory_error(predicted: np.ndarray, observed: np.ndarray) -> np.ndarray:
    """Per-step RMS of prediction − observation over the seen values; (T, 4) → (T,).

    NaN where nothing was seen or nothing predicted.
    """
    diff = np.asarray(predicted, dtype=np.float64) - np.asarray(observed, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        count = np.sum(np.isfinite(diff), axis=1)
        total = np.nansum(diff**2, axis=1)
        return np.where(count > 0, np.sqrt(total / np.maximum(count, 1)), np.nan)


def steps_to_lock(
    motor_errors: np.ndarray,
    sensory_errors: np.ndarray | None = None,
    start: int = 0,
    end: int | None = None,
    motor_threshold: float = MOTOR_LOCK_THRESHOLD,
    sensory_threshold: float = SENSORY_LOCK_THRESHOLD,
    hold: int = LOCK_HOLD,
) -> int | None:
    """Steps from ``start`` until the first step that begins ``hold`` locked steps (before
    ``end``); ``None`` if never. NaN sensory errors (nothing seen) do not count against."""
    motor_errors = np.asarray(motor_errors, dtype=np.float64)
    end = len(motor_errors) if end is None else min(end, len(motor_errors))
    ok = motor_errors < motor_threshold
    if sensory_errors is not None:
        sensory_errors = np.asarray(sensory_errors, dtype=np.float64)
        ok &= ~(sensory_errors >= sensory_threshold)  # NaN passes
    for t in range(start, end - hold + 1):
        if ok[t : t + hold].all():
            return t - start
    return None


def phase_lag(produced: np.ndarray, target: np.ndarray, max_lag: int = 6) -> float:
    """Lag in steps (positive: ``produced`` behind ``target``) minimizing the mean squared
    difference between ``produced[t]`` and ``target[t - lag]``; shapes (T, D)."""
    produced = np.asarray(produced, dtype=np.float64)
    target = np.asarray(target, dtype=np.float64)
    n = len(produced)
    if n < 2 * max_lag + 3:
        raise ValueError("phase_lag needs at least 2 * max_lag + 3 steps")
    lags = np.arange(-max_lag, max_lag + 1)
    costs = []
    for lag in lags:
        if lag >= 0:
            a, b = produced[lag:], target[: n - lag]
        else:
            a, b = produced[: n + lag], target[-lag:]
        costs.append(np.mean((a - b) ** 2))
    costs = np.asarray(costs)
    i = int(np.argmin(costs))
    if 0 < i < len(costs) - 1:
        denominator = costs[i - 1] - 2 * costs[i] + costs[i + 1]
        if denominator > 0:
            return float(lags[i] + 0.5 * (costs[i - 1] - costs[i + 1]) / denominator)
    return float(lags[i])


def pb_settle_step(
    pbs: np.ndarray, bound: float = 0.02, hold: int = 5, start: int = 0
) -> int | None:
    """Steps from ``start`` until the PB stays within ``bound`` per step for ``hold`` steps."""
    pbs = np.asarray(pbs, dtype=np.float64)
    change = np.r_[np.inf, np.max(np.abs(np.diff(pbs, axis=0)), axis=1)]
    for t in range(start, len(pbs) - hold + 1):
        if np.all(change[t : t + hold] < bound):
            return t - start
    return None


def periodicity(
    x: np.ndarray, max_period: int = MAX_PERIOD, tolerance: float = PERIODIC_TOLERANCE
) -> Periodicity:
    """The smallest period, whole or fractional, whose return error is below ``tolerance``
    (see module doc and :func:`rnnpb.structure.periodicity`); shape (T, D) or (T,)."""
    return structure.periodicity(x, max_period, tolerance)


def last_cycle(x: np.ndarray, period: float, n: int = 60) -> np.ndarray:
    """The last ``period`` steps of ``x`` (shape (T, D)) sampled at ``n`` evenly spaced
    points, shape (n, D); a fractional period is read off a cubic spline."""
    from scipy.interpolate import CubicSpline

    x = np.asarray(x, dtype=np.float64)
    end = len(x) - 1
    times = end - period + np.arange(n) * period / n
    return CubicSpline(np.arange(len(x)), x, axis=0)(times)


def _resample_cycle(cycle: np.ndarray, n: int = 60) -> np.ndarray:
    cycle = np.asarray(cycle, dtype=np.float64)
    if len(cycle) == n:
        return cycle
    period = len(cycle)
    closed = np.concatenate([cycle, cycle[:1]])
    positions = np.linspace(0, period, n, endpoint=False)
    out = np.empty((n, cycle.shape[1]))
    for j in range(cycle.shape[1]):
        out[:, j] = np.interp(positions, np.arange(period + 1), closed[:, j])
    return out


def cycle_distance(a: np.ndarray, b: np.ndarray, n: int = 60) -> float:
    """RMS difference of two cycles (P_a, D) and (P_b, D) after resampling both to ``n``
    points of one period (a cycle of ``n`` points, as :func:`last_cycle` gives, is taken as
    sampled already), minimized over circular shifts."""
    ra, rb = _resample_cycle(a, n), _resample_cycle(b, n)
    return float(min(np.sqrt(np.mean((ra - np.roll(rb, k, axis=0)) ** 2)) for k in range(n)))


def attractor_distance(a: np.ndarray, b: np.ndarray) -> float:
    """RMS distance (per value) of two runs (T_a, D) and (T_b, D) as sets of points: every
    point's distance to the nearest point of the other run, both ways. For generations that
    are no limit cycle, where one period's window (:func:`cycle_distance`) depends on where
    the run stops: a quasi-periodic run against itself stopped 10-30 steps later is 0.013-0.035
    apart by cycle distance (docs/model.md, "Consolidation")."""
    from scipy.spatial import cKDTree

    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if a.ndim != 2 or b.ndim != 2 or a.shape[1] != b.shape[1] or not len(a) or not len(b):
        raise ValueError(f"attractor_distance needs two runs (T, D), got {a.shape} and {b.shape}")
    to_b = cKDTree(b).query(a)[0]
    to_a = cKDTree(a).query(b)[0]
    return float(np.sqrt(np.mean(np.concatenate([to_b, to_a]) ** 2) / a.shape[1]))


@dataclass(frozen=True)
class ResponseCase:
    case: int  # 1 like a learned limit cycle, 2 new limit cycle, 3 unsteady
    period: float | None
    return_error: float
    nearest_pattern: str | None
    distance: float  # cycle distance to the nearest learned cycle (nan when unsteady)

    def describe(self) -> str:
        if self.case == 3:
            return f"case 3: unsteady (return error {self.return_error:.2f} at best period)"
        if self.case == 1:
            return (
                f"case 1: limit cycle of period {self.period:g} like learned pattern "
                f"{self.nearest_pattern} (distance {self.distance:.3f})"
            )
        return (
            f"case 2: new limit cycle of period {self.period:g} (nearest learned pattern "
            f"{self.nearest_pattern} at distance {self.distance:.3f})"
        )


def classify_response(
    response: np.ndarray,
    learned_cycles: dict[str, np.ndarray],
    tolerance: float = PERIODIC_TOLERANCE,
    similar: float = SIMILAR_CYCLE,
    max_period: int = MAX_PERIOD,
) -> ResponseCase:
    """Classify a (normalized) motor trajectory after its transient, shape (T, D)."""
    found = periodicity(response, max_period=max_period, tolerance=tolerance)
    if found.period is None:
        return ResponseCase(3, None, found.return_error, None, math.nan)
    cycle = last_cycle(response, found.period)
    distances = {name: cycle_distance(cycle, learned) for name, learned in learned_cycles.items()}
    nearest = min(distances, key=distances.get)
    case = 1 if distances[nearest] < similar else 2
    return ResponseCase(case, found.period, found.return_error, nearest, distances[nearest])
