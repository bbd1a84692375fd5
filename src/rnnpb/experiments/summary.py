"""The demo's measures over all its jobs, and the paper's targets they meet.

Every object here is frozen and has ``to_json()``: the values ``results.json`` holds, in the
order it holds them. The targets' limits are the measures' own
(:mod:`rnnpb.analysis.metrics`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field, fields
from typing import Any

import numpy as np

from rnnpb.analysis import metrics
from rnnpb.analysis.statistics import Interval, bootstrap_interval, median_interval, share_within
from rnnpb.experiments.jobs import ExperimentConfig, LargerSetRun, LearningSetResult
from rnnpb.experiments.paper import Draw, FollowsEveryPattern, NovelResponse
from rnnpb.experiments.reporting import sci

# Per learning set, per pattern: a synchronization measure.
PerPattern = dict[str, dict[str, Any]]


def flat(nested: Mapping[str, Mapping[str, Any]]) -> list[Any]:
    """The values of a per-set, per-pattern table, set after set."""
    return [v for inner in nested.values() for v in inner.values()]


def within(values: Sequence[Any], limit: float) -> int:
    """How many of ``values`` are at most ``limit`` (None, never, is not)."""
    return sum(v is not None and v <= limit for v in values)


@dataclass(frozen=True)
class Target:
    """One of the paper's figures: met or not, and by how much. ``value``: the measured figure
    the verdict compared with its limit, where there is one number (an exam's targets: what
    the exam ledger records); None where the verdict reads several."""

    met: bool
    detail: str
    value: float | None = None

    def __post_init__(self) -> None:
        # A figure that could not be taken (NaN, an infinity) is none: a verdict recomputed
        # from results.json then equals the one first given.
        if self.value is not None and not math.isfinite(self.value):
            object.__setattr__(self, "value", None)

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"met": self.met, "detail": self.detail}
        if self.value is not None:
            out["value"] = self.value
        return out


@dataclass(frozen=True)
class StepTarget:
    """A step count the paper gives: ``measure`` (a :class:`Summary` field) within ``limit``
    steps for every run."""

    measure: str
    name: str  # the target's key in results.json
    limit: int

    def judge(self, values: Sequence[Any]) -> Target:
        worst = _max_or_none(list(values))
        return Target(
            worst is not None and worst <= self.limit,
            f"{within(values, self.limit)}/{len(values)} within {self.limit:g}",
        )


STEP_TARGETS = (
    StepTarget("sync_steps_to_lock", f"lock_within_{metrics.LOCK_LIMIT}", metrics.LOCK_LIMIT),
    StepTarget(
        "pb_settle_steps", f"pb_settles_within_{metrics.SETTLE_LIMIT}", metrics.SETTLE_LIMIT
    ),
    StepTarget(
        "pause_steps_to_relock", f"relock_within_{metrics.RELOCK_LIMIT}", metrics.RELOCK_LIMIT
    ),
    StepTarget("switch_steps", f"switch_within_{metrics.SWITCH_LIMIT}", metrics.SWITCH_LIMIT),
)
TRAIN_TARGET = f"train_mse_below_{sci(metrics.TRAIN_ERROR_TARGET)}"
NOVEL_TARGET = "all_three_novel_cases"
LARGER_TARGET = f"larger_set_{metrics.LARGER_SET_FOLLOWS}_of_{metrics.LARGER_SET_RUNS}"


def _max_or_none(values: list[Any]) -> Any:
    """The largest value; None (never) counts as the worst."""
    if any(v is None for v in values):
        return None
    return max(values) if values else None


def larger_target(success: int, runs: int) -> Target:
    return Target(metrics.larger_set_share_met(success, runs), f"{success}/{runs}")


@dataclass(frozen=True)
class Summary:
    """The measures of one configuration (the default or the paper's regression), per
    learning set (and per pattern)."""

    train_mse: dict[str, float]
    train_rms: dict[str, float]
    train_mse_per_output: dict[str, list[float]]
    train_seconds: dict[str, float]
    sync_steps_to_lock: PerPattern
    pb_settle_steps: PerPattern
    phase_lag_steps: PerPattern
    recognized_pattern: PerPattern
    pause_relative_motion: PerPattern
    pause_steps_to_relock: PerPattern
    switch_steps: dict[str, dict[str, int | None]]
    recognized_correctly: int
    recognition_runs: int

    def to_json(self) -> dict[str, Any]:
        return {f.name: getattr(self, f.name) for f in fields(self)}


def _per_pattern(draws: Mapping[str, Draw], measure: str) -> PerPattern:
    return {
        name: {s.pattern: getattr(s, measure) for s in d.synchronization}
        for name, d in draws.items()
    }


def summarize(results: Mapping[str, LearningSetResult]) -> Summary:
    """The measures of one configuration, learning sets in order."""
    ordered = {k: results[k] for k in sorted(results)}
    runs = {k: Draw(r.synchronization, r.switching) for k, r in ordered.items()}
    recognized = _per_pattern(runs, "recognized_pattern")
    patterns = [p for r in ordered.values() for p in r.patterns]
    return Summary(
        train_mse={k: r.train_mse_max for k, r in ordered.items()},
        train_rms={k: r.train_rms_max for k, r in ordered.items()},
        train_mse_per_output={k: r.train_mse_per_output for k, r in ordered.items()},
        train_seconds={k: r.train_seconds for k, r in ordered.items()},
        sync_steps_to_lock=_per_pattern(runs, "steps_to_lock"),
        pb_settle_steps=_per_pattern(runs, "pb_settle_steps"),
        phase_lag_steps=_per_pattern(runs, "phase_lag_steps"),
        recognized_pattern=recognized,
        pause_relative_motion=_per_pattern(runs, "pause_relative_motion"),
        pause_steps_to_relock=_per_pattern(runs, "pause_steps_to_relock"),
        switch_steps={k: r.switching.pairs for k, r in ordered.items()},
        recognized_correctly=int(
            sum(a == b for a, b in zip(flat(recognized), patterns, strict=True))
        ),
        recognition_runs=len(patterns),
    )


def targets(
    summary: Summary, larger: Sequence[LargerSetRun], novel_cases: Sequence[int]
) -> dict[str, Target]:
    """The paper's figures met or not by one configuration."""
    mse = list(summary.train_mse.values())
    out = {
        TRAIN_TARGET: Target(
            all(v < metrics.TRAIN_ERROR_TARGET for v in mse), f"max {max(mse):.2e}"
        )
    }
    for target in STEP_TARGETS:
        out[target.name] = target.judge(flat(getattr(summary, target.measure)))
    if novel_cases:
        seen = sorted(set(novel_cases))
        every = seen == list(metrics.RESPONSE_CASES)
        out[NOVEL_TARGET] = Target(
            every,
            f"cases seen: {seen}"
            + ("" if every else "; the report explains why, from the attractor analysis"),
        )
    if larger:
        out[LARGER_TARGET] = larger_target(sum(r.follows_all for r in larger), len(larger))
    return out


@dataclass(frozen=True)
class DrawSummary:
    """The lock-on, pause, switching and larger-set measures of one draw of the user's
    imperfection, and the targets they meet."""

    sync_steps_to_lock: PerPattern
    pb_settle_steps: PerPattern
    pause_steps_to_relock: PerPattern
    switch_steps: dict[str, dict[str, int | None]]
    larger_set_success: int
    larger_set_steps_to_follow: list[dict[str, int | None]]
    targets: dict[str, Target]

    def to_json(self) -> dict[str, Any]:
        out = {f.name: getattr(self, f.name) for f in fields(self)}
        out["targets"] = {k: t.to_json() for k, t in self.targets.items()}
        return out


@dataclass(frozen=True)
class DrawsSummary:
    """Every draw of the user's imperfection (the report's first), and the targets over all
    draws pooled."""

    scenario_seeds: list[int]
    by_seed: dict[str, DrawSummary]
    targets: dict[str, Target]

    def to_json(self) -> dict[str, Any]:
        return {
            "scenario_seeds": self.scenario_seeds,
            "by_seed": {k: d.to_json() for k, d in self.by_seed.items()},
            "targets": {k: t.to_json() for k, t in self.targets.items()},
        }


def draws_summary(
    sets: Mapping[str, Mapping[int, Draw]],
    larger: Sequence[Mapping[int, FollowsEveryPattern]],
    scenario_seeds: Sequence[int],
) -> DrawsSummary:
    """The measures for every draw of the user's imperfection (``scenario_seeds``, the
    report's first), each draw's target counts, and the targets over all draws pooled.

    ``sets`` holds each learning set's draws by scenario seed
    (:meth:`LearningSetResult.draws_by_seed`), ``larger`` each larger-set run's
    (:meth:`LargerSetRun.draws_by_seed`).
    """
    ordered = {k: sets[k] for k in sorted(sets)}
    by_seed: dict[str, DrawSummary] = {}
    for seed in scenario_seeds:
        runs = {k: draws[seed] for k, draws in ordered.items()}
        follows = [draws[seed] for draws in larger]
        measures: dict[str, Any] = {
            "sync_steps_to_lock": _per_pattern(runs, "steps_to_lock"),
            "pb_settle_steps": _per_pattern(runs, "pb_settle_steps"),
            "pause_steps_to_relock": _per_pattern(runs, "pause_steps_to_relock"),
            "switch_steps": {k: d.switching.pairs for k, d in runs.items()},
        }
        success = int(sum(f.follows_all for f in follows))
        judged = {t.name: t.judge(flat(measures[t.measure])) for t in STEP_TARGETS}
        if larger:
            judged[LARGER_TARGET] = larger_target(success, len(follows))
        by_seed[str(seed)] = DrawSummary(
            **measures,
            larger_set_success=success,
            larger_set_steps_to_follow=[f.steps_to_follow for f in follows],
            targets=judged,
        )
    pooled = {
        t.name: t.judge([v for d in by_seed.values() for v in flat(getattr(d, t.measure))])
        for t in STEP_TARGETS
    }
    if larger:
        pooled[LARGER_TARGET] = larger_target(
            sum(d.larger_set_success for d in by_seed.values()), len(larger) * len(by_seed)
        )
    return DrawsSummary([int(s) for s in by_seed], by_seed, pooled)


# --- distributions over training seeds and draws of the user --------------------------------

# The synchronization measures of 3.1 (a Synchronization field each) and their limits.
SYNC_MEASURES: dict[str, float | None] = {
    "steps_to_lock": metrics.LOCK_LIMIT,
    "pb_settle_steps": metrics.SETTLE_LIMIT,
    "phase_lag_steps": None,
    "pause_relative_motion": None,
    "pause_steps_to_relock": metrics.RELOCK_LIMIT,
}
NOVEL_INPUTS = ("repeated cycle", "by hand")


@dataclass(frozen=True)
class Distribution:
    """One measure over every network, draw and pattern (or pair): its median over the runs
    where the event happened, and its share within the paper's limit, each with its 95 %
    bootstrap interval (:mod:`rnnpb.analysis.statistics`)."""

    measure: str
    n: int
    never: int  # runs where the event never happened
    median: Interval
    limit: float | None
    within: Interval | None  # share at most ``limit``; never counts as outside

    def to_json(self) -> dict[str, Any]:
        return {
            "measure": self.measure,
            "n": self.n,
            "never": self.never,
            "median": asdict(self.median),
            "limit": self.limit,
            "within": asdict(self.within) if self.within else None,
        }


def distribution(measure: str, values: Sequence[Any], limit: float | None) -> Distribution:
    return Distribution(
        measure,
        len(values),
        sum(v is None for v in values),
        median_interval(values),
        limit,
        None if limit is None else share_within(values, limit),
    )


@dataclass(frozen=True)
class Distributions:
    """Every measure of section 3 over the training seeds (per learning set) and the draws of
    the user, for one on-line regression."""

    training_seeds: list[int]
    scenario_seeds: list[int]
    measures: dict[str, Distribution]
    recognised: Interval  # share of synchronization runs whose nearest learned PB is right
    train_below_target: Interval  # share of networks whose final error meets the paper's
    novel_cases: dict[str, dict[int, int]]  # input (NOVEL_INPUTS) -> case -> count
    closed_loop_periodic: tuple[int, int]  # learned attractors that are cycles, of all
    larger_set_follows: Interval | None  # share of larger-set (seed, draw) runs that follow all

    def to_json(self) -> dict[str, Any]:
        return {
            "training_seeds": self.training_seeds,
            "scenario_seeds": self.scenario_seeds,
            "measures": {k: d.to_json() for k, d in self.measures.items()},
            "recognised": asdict(self.recognised),
            "train_below_target": asdict(self.train_below_target),
            "novel_cases": self.novel_cases,
            "closed_loop_periodic": list(self.closed_loop_periodic),
            "larger_set_follows": (
                asdict(self.larger_set_follows) if self.larger_set_follows else None
            ),
        }


def distributions(
    by_seed: Mapping[int, Mapping[str, LearningSetResult]],
    larger: Sequence[LargerSetRun],
    scenario_seeds: Sequence[int],
) -> Distributions:
    """Pool every learning set's results over training seeds and draws (each result's
    :meth:`~LearningSetResult.draws_by_seed`) and the larger set's over seeds and draws."""
    sync: dict[str, list[Any]] = {m: [] for m in SYNC_MEASURES}
    switches: list[Any] = []
    recognised: list[float] = []
    errors: list[float] = []
    cases: dict[str, dict[int, int]] = {
        k: dict.fromkeys(metrics.RESPONSE_CASES, 0) for k in NOVEL_INPUTS
    }
    periods: list[Any] = []
    for results in by_seed.values():
        for result in results.values():
            errors.append(result.train_mse_max)
            for draw in result.draws_by_seed().values():
                for run in draw.synchronization:
                    for measure in SYNC_MEASURES:
                        value = getattr(run, measure)
                        sync[measure].append(
                            None if isinstance(value, float) and math.isnan(value) else value
                        )
                    recognised.append(float(run.recognized_pattern == run.pattern))
                switches.extend(draw.switching.pairs.values())
            for response in result.novel:
                kind = NOVEL_INPUTS[1] if response.user_draw is not None else NOVEL_INPUTS[0]
                cases[kind][response.case] += 1
            periods.extend(a.period for a in result.attractors.values())
    measures = {m: distribution(m, v, SYNC_MEASURES[m]) for m, v in sync.items()}
    measures["switch_steps"] = distribution("switch_steps", switches, metrics.SWITCH_LIMIT)
    follows = [f for run in larger for f in run.draws_by_seed().values()]
    if follows:
        measures["steps_to_follow"] = distribution(
            "steps_to_follow",
            [v for f in follows for v in f.steps_to_follow.values()],
            metrics.SWITCH_LIMIT,
        )
    return Distributions(
        training_seeds=list(by_seed),
        scenario_seeds=list(scenario_seeds),
        measures=measures,
        recognised=bootstrap_interval(recognised, np.mean),
        train_below_target=bootstrap_interval(
            [float(e < metrics.TRAIN_ERROR_TARGET) for e in errors], np.mean
        ),
        novel_cases=cases,
        closed_loop_periodic=(sum(p is not None for p in periods), len(periods)),
        larger_set_follows=(
            bootstrap_interval([float(f.follows_all) for f in follows], np.mean)
            if follows
            else None
        ),
    )


@dataclass(frozen=True)
class LearningSetFiles:
    patterns: list[str]
    data: str  # folder of the sequence CSVs, relative to the output folder


@dataclass(frozen=True)
class OutputFiles:
    """Which file is which, relative to the output folder."""

    models: dict[str, str]
    learning_sets: dict[str, LearningSetFiles]
    figures: list[str]

    def to_json(self) -> dict[str, Any]:
        return {
            "models": self.models,
            "learning_sets": {k: asdict(v) for k, v in self.learning_sets.items()},
            "figures": self.figures,
        }


@dataclass(frozen=True)
class DemoResults:
    """Everything ``rnnpb demo`` measured; ``to_json()`` is ``results.json``."""

    rnnpb_version: str
    versions: dict[str, str]
    config: ExperimentConfig
    default: Summary
    novel: list[NovelResponse]  # learning sets in order, then sizes
    closed_loop_periods: dict[str, dict[str, float | None]]
    switch_sequence_steps_to_follow: list[int | None]
    larger: list[LargerSetRun]  # by seed
    targets: dict[str, Target]
    draws: DrawsSummary
    files: OutputFiles
    paper: Summary | None  # the paper's on-line regression on the same models
    paper_targets: dict[str, Target] | None
    runtime_s: float
    # Over every training seed and draw of the user (the fields above: the first seed's).
    distributions: Distributions | None = None
    paper_distributions: Distributions | None = None
    novel_all: list[NovelResponse] = field(default_factory=list)  # every seed's and draw's

    @property
    def novel_cases_seen(self) -> list[int]:
        return sorted({r.case for r in self.novel})

    @property
    def larger_set_success(self) -> int:
        return int(sum(r.follows_all for r in self.larger))

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "rnnpb_version": self.rnnpb_version,
            "versions": self.versions,
            "config": asdict(self.config),
            **self.default.to_json(),
            "novel_case": [r.to_json() for r in self.novel],
            "novel_cases_seen": self.novel_cases_seen,
            "closed_loop_periods": self.closed_loop_periods,
            "switch_sequence_steps_to_follow": self.switch_sequence_steps_to_follow,
            "larger_set_success": self.larger_set_success,
            "larger_set_runs": [r.to_json() for r in self.larger],
            "targets": {k: t.to_json() for k, t in self.targets.items()},
            "draws": self.draws.to_json(),
            "files": self.files.to_json(),
        }
        if self.paper is not None:
            out["paper_regression"] = {
                **self.paper.to_json(),
                "targets": {k: t.to_json() for k, t in (self.paper_targets or {}).items()},
            }
        if self.distributions is not None:
            out["distributions"] = {
                "default": self.distributions.to_json(),
                "novel_case": [r.to_json() for r in self.novel_all],
            }
            if self.paper_distributions is not None:
                out["distributions"]["paper_regression"] = self.paper_distributions.to_json()
        out["runtime_s"] = self.runtime_s
        return out
