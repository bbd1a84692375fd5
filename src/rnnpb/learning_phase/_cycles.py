"""Whole cycles of a real movement: where it repeats, at which period, and where each cycle
begins.

People do not move like a metronome: they rest between gestures, raise their hands before they
wave and lower them after, slow down and speed up, and a motion-capture take often holds a
single gesture. The cutter therefore first finds where the movement repeats itself, at which
period (:func:`rnnpb.structure.repeating_stretches`, the on-line novelty detector's measure:
each cycle against the one before, relative to their spread, so it is the same for a small and
a large movement, a slow and a fast one), and cuts cycles only there:

1. **Stretches.** Each part of the recording that repeats is a stretch with its own period
   (4–80 steps); what lies between (a raise before a wave, a lowering after it, the join of
   two takes, a long rest, a hand out of view) is in none and is dropped.
2. **Cycles.** In a stretch, the movement minus its local mean (a moving average one period
   wide: a slow drift of the whole posture, a raise before a wave) is projected on its first
   principal component, smoothed over a sixth of the period; a cycle runs from the middle of
   one trough of that component to the middle of the next (a trough's middle, not its lowest
   point: a rest at the bottom of a gesture is flat), taking the component's sign whose
   troughs bound the most of the stretch (a gesture's cycle is not symmetric). A trough cut
   off by the stretch's start or end counts when it is at least half as deep as the typical
   one; a stream still being watched (``growing``) counts a trough only once it has risen out
   of it a quarter period before the last step (the local mean is not known nearer the end).
   Cycles from half to twice the period long are kept: a person's cycles are uneven, a trough
   missed or doubled is not a cycle.

A gesture with a rest in each cycle (rest, raise, hold, lower) is one cycle, rest included; a
take of one gesture joined to others of the same is a stretch of single gestures.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rnnpb.structure import Stretch, repeating_stretches

MIN_PERIOD = 4
"""Fewest steps a cycle may have: fewer cannot show its shape (up, down and both turns)."""
MAX_PERIOD = 80
"""Most steps a cycle may have: 8 s at 0.1 s a step (a slow gesture), 32 s at the paper's 0.4 s."""
REPEAT_LEVEL = 0.33
"""A cycle repeats when it differs from the one before by less than this, relative to twice
their variance: the on-line detector's ``structure_level`` (the paper preset's value), so that
what is cut as a cycle is what the robot calls repeating."""
STRUCTURE_STEPS = MIN_PERIOD
"""Steps a cycle is judged over at the least: one cycle against the one before, so that a
recording of two or three gestures is cut (the on-line detector, which must not be fooled by a
moment's coincidence, judges a short period over 12 steps)."""


@dataclass(frozen=True)
class CycleCut:
    """Where a movement repeats and its whole cycles.

    Attributes
    ----------
    stretches : tuple of Stretch
        The repeating parts, each with its period (steps).
    cycles : tuple of (start, stop)
        Whole cycles (stop exclusive), in order; consecutive ones of a stretch share a bound.
    runs : tuple of tuple of (start, stop)
        The cycles grouped into runs of consecutive ones (no step between them).
    """

    stretches: tuple[Stretch, ...]
    cycles: tuple[tuple[int, int], ...]
    runs: tuple[tuple[tuple[int, int], ...], ...]

    @property
    def period(self) -> float | None:
        """The median cycle length (steps), None without cycles."""
        if not self.cycles:
            return None
        return float(np.median([b - a for a, b in self.cycles]))

    @property
    def covered(self) -> int:
        """Steps inside whole cycles."""
        return sum(b - a for a, b in self.cycles)


def _moving_average(x: np.ndarray, width: int) -> np.ndarray:
    """Centred moving average along axis 0 over ``width`` steps, edges held; (n, d)."""
    width = max(1, int(width))
    if width == 1:
        return x.copy()
    before = width // 2
    padded = np.pad(x, ((before, width - 1 - before), (0, 0)), mode="edge")
    sums = np.cumsum(np.vstack([np.zeros((1, x.shape[1])), padded]), axis=0)
    return (sums[width:] - sums[:-width]) / width


def _troughs(component: np.ndarray, period: int, growing: bool = False) -> list[tuple[int, float]]:
    """The troughs of a component that oscillates about zero: each run below zero (runs split
    by a rise above zero shorter than a quarter period are one), as (the middle of its lowest
    steps, its lowest value). The lowest steps are those within a tenth of the trough's depth
    of its lowest value: a rest at the bottom of a gesture is flat, and its single lowest point
    falls anywhere in it; its middle does not. ``growing``: the component goes on after its
    last step (a stream still being watched), so a trough it has not yet risen out of is not
    one yet."""
    below = component < 0
    edges = np.diff(np.concatenate([[0], below.astype(int), [0]]))
    runs = [
        [int(a), int(b)]
        for a, b in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True)
    ]
    merged: list[list[int]] = []
    for run in runs:
        if merged and run[0] - merged[-1][1] < period / 4:
            merged[-1][1] = run[1]
        else:
            merged.append(run)
    out = []
    for a, b in merged:
        values = component[a:b]
        lowest = float(values.min())
        near = np.flatnonzero(values <= 0.9 * lowest)
        if growing and b > len(component) - period / 4:
            # The trough is not over, or too near the end for the local mean (a period wide)
            # to be known about it: its middle is not certain yet.
            continue
        out.append((a + int(round((near[0] + near[-1]) / 2)), lowest))
    return out


def _refined_period(x: np.ndarray, period: int) -> int:
    """The stretch's own period: the lag near ``period`` (0.6 to 1.6 times it) where the
    stretch's autocorrelation, summed over its values, is highest; ``period`` if none is a
    peak. The local test that found the stretch prefers the shortest lag that repeats, which
    for a gesture with a hold can be a part of the gesture."""
    centred = x - x.mean(axis=0)
    energy = float(np.sum(centred * centred))
    low, high = max(2, int(0.6 * period)), min(len(x) - 2, int(np.ceil(1.6 * period)))
    if energy <= 1e-12 or high <= low:
        return period
    n = len(x)
    lags = np.arange(low, high + 1)
    correlation = np.array(
        [np.sum(centred[k:] * centred[: n - k]) / energy * n / (n - k) for k in lags]
    )
    return int(lags[int(np.argmax(correlation))])


def _stretch_cycles(x: np.ndarray, period: int, growing: bool = False) -> list[tuple[int, int]]:
    """Whole cycles of one stretch ``x`` (n, d) repeating every ``period`` steps (module doc,
    step 2); bounds relative to the stretch."""
    if len(x) < period + 2:
        return []
    period = _refined_period(x, period)
    detrended = x - _moving_average(x, period)
    centred = detrended - detrended.mean(axis=0)
    _, _, vt = np.linalg.svd(centred, full_matrices=False)
    component = centred @ vt[0]
    component = _moving_average(component[:, None], max(1, round(period / 6)))[:, 0]
    # The component's sign is arbitrary, and a gesture's cycle is not symmetric (a short dip
    # between long holds): the sign whose troughs bound the most of the stretch is taken.
    best: list[tuple[int, int]] = []
    for sign in (1.0, -1.0):
        cycles = _cycles_between_troughs(sign * component, period, growing)
        if sum(b - a for a, b in cycles) > sum(b - a for a, b in best):
            best = cycles
    return best


def _cycles_between_troughs(
    component: np.ndarray, period: int, growing: bool
) -> list[tuple[int, int]]:
    troughs = _troughs(component, period, growing)
    if len(troughs) < 2:
        return []
    # A trough cut off by the stretch's start or end is shallower than a whole one: only the
    # troughs at least half as deep as the typical one bound a cycle.
    depth = float(np.median([value for _, value in troughs]))
    bounds = [step for step, value in troughs if value <= 0.5 * depth]
    return [
        (a, b)
        for a, b in zip(bounds[:-1], bounds[1:], strict=True)
        if period / 2 <= b - a <= 2 * period
    ]


def whole_cycles(
    sensory: np.ndarray,
    min_period: int = MIN_PERIOD,
    max_period: int = MAX_PERIOD,
    level: float = REPEAT_LEVEL,
    growing: bool = False,
) -> CycleCut:
    """The repeating stretches and whole cycles of a movement (module doc).

    ``sensory`` shape (n_steps, 4); steps with a value not seen (NaN) split the recording and
    lie in no cycle. Empty when nothing repeats. ``growing``: the movement goes on after the
    last step (a stream watched on-line): the last cycle ends only where its end is certain.
    """
    x = np.asarray(sensory, dtype=np.float64)
    if x.ndim != 2 or len(x) < 2 * min_period:
        return CycleCut((), (), ())
    seen = np.isfinite(x).all(axis=1)
    edges = np.diff(np.concatenate([[0], seen.astype(int), [0]]))
    stretches: list[Stretch] = []
    cycles: list[tuple[int, int]] = []
    runs: list[tuple[tuple[int, int], ...]] = []
    for first, last in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True):
        first, last = int(first), int(last)
        part = x[first:last]
        for stretch in repeating_stretches(
            part, min_period, max_period, steps=STRUCTURE_STEPS, level=level
        ):
            shifted = Stretch(first + stretch.start, first + stretch.stop, stretch.period)
            stretches.append(shifted)
            found = [
                (shifted.start + int(a), shifted.start + int(b))
                for a, b in _stretch_cycles(
                    part[stretch.start : stretch.stop], stretch.period, growing
                )
            ]
            cycles += found
            run: list[tuple[int, int]] = []
            for cycle in found:
                if run and run[-1][1] != cycle[0]:
                    runs.append(tuple(run))
                    run = []
                run.append(cycle)
            if run:
                runs.append(tuple(run))
    return CycleCut(tuple(stretches), tuple(cycles), tuple(runs))


def cycle_bounds(sensory: np.ndarray, growing: bool = False) -> list[tuple[int, int]]:
    """Whole cycles of a movement as ``[(start, stop), …]`` (stop exclusive); see
    :func:`whole_cycles`. ``sensory`` shape (n_steps, 4). Empty when the movement does not
    repeat."""
    return list(whole_cycles(sensory, growing=growing).cycles)
