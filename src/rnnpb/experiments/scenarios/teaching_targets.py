"""The teach study's targets measured from its runs (:mod:`rnnpb.experiments.studies.teach`
judges them by its exam): each target's measure gives its value and a line of detail, by the
exam target's parameters.

- ``taught_after_two_showings``: the share of runs that learned the movement from the first two
  showings (swapped in before the third began) and recognised its third showing;
- ``third_showing_recognised``: the mean share of the third showing recognised
  (:func:`third_showing_share`);
- ``patterns_from_random_movement`` and ``duplicate_patterns``: patterns learned from the
  unstructured movement, and beyond one from the shown movement;
- ``old_patterns_lock_on``: the learned patterns performed after the swap locked onto in time;
- ``no_missed_deadline``: the paced runs' missed deadlines and steps past their slot;
- ``consolidation_cpu``: the CPU seconds of the longest teaching consolidation.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Callable

from rnnpb.experiments.exams import ExamTarget
from rnnpb.experiments.reporting import fmt
from rnnpb.experiments.scenarios.teaching_measures import LATE_S, PacedRun, TeachRun
from rnnpb.experiments.scenarios.teaching_scenario import UNSTRUCTURED_MOVEMENTS, period_of

Measure = Callable[[ExamTarget], "tuple[float, str] | None"]


def target_measures(runs: list[TeachRun], paced: list[PacedRun]) -> dict[str, Measure]:
    """Each target's measure over ``runs`` and ``paced``, by the target's name (None: not
    measured, as the deadlines without a paced run)."""
    return {
        "taught_after_two_showings": lambda t: taught_after_two_showings(runs, t),
        "third_showing_recognised": lambda t: third_showing_recognised(runs, t),
        "patterns_from_random_movement": lambda t: patterns_from_random_movement(runs),
        "duplicate_patterns": lambda t: duplicate_patterns(runs),
        "old_patterns_lock_on": lambda t: old_patterns_lock_on(runs, t),
        "no_missed_deadline": lambda t: no_missed_deadline(paced) if paced else None,
        "consolidation_cpu": lambda t: consolidation_cpu(runs, paced),
    }


def third_showing_share(run: TeachRun, settle: float) -> float:
    """The share of the third showing's steps, from one cycle of the movement (at least
    ``settle`` steps) after it begins, recognised as the pattern learned from the showings
    (0 when nothing was learned)."""
    if not run.new_pattern:
        return 0.0
    start = run.timeline["third_showing"] + max(int(settle), period_of(run.shape))
    recognised = run.timeline["recognised"][start:]
    return sum(r == run.new_pattern for r in recognised) / len(recognised) if recognised else 0.0


def learned_in_time(run: TeachRun) -> bool:
    """Learned from the first two showings: a pattern of the movement swapped in before the
    third showing began."""
    return (
        bool(run.new_pattern) and bool(run.swaps) and run.swaps[0] <= run.timeline["third_showing"]
    )


def where(run: TeachRun) -> str:
    """A run's place in the study, as the details and the report name it."""
    return f"dt {run.dt:g} set {run.learning_set} {run.shape}"


def taught_after_two_showings(runs: list[TeachRun], target: ExamTarget) -> tuple[float, str]:
    settle, share = target.parameter("settle_steps"), target.parameter("recognised_share")
    good = [r for r in runs if learned_in_time(r) and third_showing_share(r, settle) >= share]
    late = [where(r) for r in runs if r.new_pattern and not learned_in_time(r)]
    none = [where(r) for r in runs if not r.new_pattern]
    low = [
        f"{where(r)} {100 * third_showing_share(r, settle):.0f} %"
        for r in runs
        if learned_in_time(r) and third_showing_share(r, settle) < share
    ]
    words = [f"{len(good)}/{len(runs)} runs"]
    for label, items in (
        ("learned after the third began", late),
        ("nothing learned", none),
        ("third showing recognised less", low),
    ):
        if items:
            words.append(f"{label}: {', '.join(items[:8])}" + (" …" if len(items) > 8 else ""))
    return len(good) / len(runs) if runs else math.nan, "; ".join(words)


def third_showing_recognised(runs: list[TeachRun], target: ExamTarget) -> tuple[float, str]:
    settle = target.parameter("settle_steps")
    shares = [third_showing_share(r, settle) for r in runs]
    mean = sum(shares) / len(shares) if shares else math.nan
    low = sorted((s, where(r)) for s, r in zip(shares, runs, strict=True))
    return mean, (
        f"mean {100 * mean:.1f} % over {len(runs)} runs; lowest: "
        + ", ".join(f"{where} {100 * s:.0f} %" for s, where in low[:4])
    )


def patterns_from_random_movement(runs: list[TeachRun]) -> tuple[float, str]:
    """Patterns learned whose data hold more unstructured movement than anything else."""
    found = [
        f"{where(r)}: {p}"
        for r in runs
        for p, movement in r.timeline.get("taught", {}).items()
        if movement in UNSTRUCTURED_MOVEMENTS
    ]
    kept = sum(r.episodes_unstructured for r in runs)
    return len(found), (
        f"{len(found)} pattern(s) learned from random movement"
        + (f" ({'; '.join(found)})" if found else "")
        + f"; {kept} episode(s) kept holding some random movement, over {len(runs)} runs"
    )


def duplicate_patterns(runs: list[TeachRun]) -> tuple[float, str]:
    """Patterns learned beyond one from the shown movement, over every run."""
    extra = {
        where(r): sorted(p for p, m in r.timeline.get("taught", {}).items() if m == r.shape)
        for r in runs
    }
    extra = {k: v for k, v in extra.items() if len(v) > 1}
    count = sum(len(v) - 1 for v in extra.values())
    return count, (
        f"{count} pattern(s) beyond one per run over {len(runs)} runs"
        + ("; " + "; ".join(f"{k}: {', '.join(v)}" for k, v in extra.items()) if extra else "")
    )


def old_patterns_lock_on(runs: list[TeachRun], target: ExamTarget) -> tuple[float, str]:
    """Learned patterns performed after the swap, locked onto within the target's steps."""
    lock = target.parameter("lock_steps")
    locks, misses = 0, []
    total = 0
    for r in runs:
        if not r.swaps:
            old = [m for m, _ in r.segments if m != r.shape and m not in UNSTRUCTURED_MOVEMENTS]
            total += len(old[-2:])
            misses += [f"{where(r)}: nothing learned"] * len(old[-2:])
            continue
        for segment, steps in r.lock_in_timeline.items():
            movement = segment.split(":", 1)[1]
            if movement == r.shape:
                continue
            total += 1
            if steps is not None and steps <= lock:
                locks += 1
            else:
                misses.append(f"{where(r)}: {segment} {fmt(steps)}")
    return locks / total if total else math.nan, (
        f"{locks}/{total} within {lock:g} steps"
        + (
            f"; missed: {'; '.join(misses[:10])}" + (" …" if len(misses) > 10 else "")
            if misses
            else ""
        )
    )


def no_missed_deadline(paced: list[PacedRun]) -> tuple[float, str]:
    """The paced steps that missed their deadline or whose late start plus work ran past the
    slot, over the paced runs."""
    count = sum(p.missed_deadlines + p.overrun_steps for p in paced)
    return count, "; ".join(
        f"dt {p.dt:g}: {p.missed_deadlines} missed, {p.overrun_steps} past their slot, "
        f"{p.late_steps} started > {LATE_S * 1e3:.0f} ms late over {p.steps} steps"
        + ("" if p.swap_step is not None else " (consolidation cut short)")
        for p in paced
    )


def consolidation_cpu(runs: list[TeachRun], paced: list[PacedRun]) -> tuple[float, str]:
    """The CPU seconds of the longest teaching consolidation (its process), over every run."""
    times = [c.cpu_s for r in runs for c in r.consolidations]
    times += [p.consolidation.cpu_s for p in paced if p.consolidation is not None]
    if not times:
        return math.nan, "no consolidation ran"
    unknown = sum(1 for t in times if not math.isfinite(t))
    if unknown:
        return math.nan, f"{unknown} of {len(times)} consolidations ended without their CPU time"
    ordered = sorted(times)
    return ordered[-1], (
        f"longest {ordered[-1]:.1f} s CPU, median {statistics.median(ordered):.1f} s, over "
        f"{len(times)} consolidations"
    )
