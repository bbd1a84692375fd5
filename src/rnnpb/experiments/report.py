"""The demo's report, ``report.md``: measure | paper | ours, with the figures, as one small
function per section, each reading the :class:`~rnnpb.experiments.summary.DemoResults` that
:func:`rnnpb.experiments.demo.run_demo` gathers (:func:`report_lines`, :func:`write_report`).
"""

from __future__ import annotations

import os
from collections.abc import Sequence

from rnnpb.analysis import metrics
from rnnpb.experiments.jobs import ExperimentConfig
from rnnpb.experiments.paper import PAUSE_STEPS, SWITCH_STEPS_EACH, NovelResponse
from rnnpb.experiments.reporting import (
    embed,
    fmt,
    median_and_worst,
    row,
    sci,
    table,
    write_lines,
)
from rnnpb.experiments.summary import (
    STEP_TARGETS,
    DemoResults,
    Distribution,
    Summary,
    Target,
    flat,
    within,
)
from rnnpb.model import OnlineConfig, TrainConfig


def missing_cases_explanation(
    novel: Sequence[NovelResponse], closed_loop_periods: dict[str, dict[str, float | None]]
) -> list[str]:
    """Why a response case did not occur, from the attractor analysis's own numbers."""
    seen = {r.case for r in novel}
    missing = [c for c in metrics.RESPONSE_CASES if c not in seen]
    if not missing or not novel:
        return []
    periods = sorted({f"{r.period:.1f}" for r in novel if r.period is not None}, key=float)
    worst_return = max(r.return_error for r in novel)
    closed = [p for periods_ in closed_loop_periods.values() for p in periods_.values()]
    learned = sorted({f"{p:.1f}" for p in closed if p is not None}, key=float)
    cycles = sum(p is not None for p in closed)
    if cycles == len(closed):
        autonomous = (
            f"The closed-loop attractors of the learned patterns are limit cycles too "
            f"(periods {', '.join(learned)}), and with on-line regression "
            "the network entrains to the period it is shown."
        )
    else:
        autonomous = (
            f"Of the learned patterns' closed-loop attractors, {cycles} of "
            f"{len(closed)} are limit cycles (periods "
            f"{', '.join(learned) or '–'}) and the others do not repeat "
            f"within {metrics.MAX_PERIOD} steps; yet driven by a repeated input and "
            "with on-line regression, the network entrains to the period it is shown."
        )
    lines = ["", f"**Why case {' and '.join(map(str, missing))} did not occur here.**"]
    if 3 in missing:
        lines.append(
            f"Every response settled on a limit cycle: the largest return error over all "
            f"{len(novel)} runs is {worst_return:.3f} (a response counts as unsteady above "
            f"{metrics.PERIODIC_TOLERANCE:g}), at period(s) {', '.join(periods)} — "
            "the period of the input cycle or a multiple of it. "
            f"{autonomous} "
            + (
                "Even demonstrated by hand, with imperfect cycles, the novel pattern is close "
                "enough to a cycle that the PB, regressed every step, keeps the response on "
                "its period."
                if any(r.user_draw is not None for r in novel)
                else "The input here is one exactly repeated cycle (the paper's user demonstrated "
                "the novel patterns by hand), and the PB, regressed every step, keeps the "
                "response on that period."
            )
        )
    if 2 in missing:
        lines.append(
            f"Every periodic response lay within {metrics.SIMILAR_CYCLE:g} of a "
            "learned pattern's cycle: the novel patterns were drawn into the learned "
            "attractors."
        )
    if 1 in missing:
        lines.append(
            f"No periodic response lay within {metrics.SIMILAR_CYCLE:g} of a learned "
            "pattern's cycle."
        )
    return lines


def _describe_learning(train: TrainConfig) -> str:
    if train.optimizer == "momentum":
        how = "the paper's algorithm, gradient descent with momentum"
    else:
        how = "Adam with noise on the teacher-forced inputs (the fast preset)"
    return f"{how}, {train.iterations:,} iterations"


def describe_configuration(config: ExperimentConfig) -> str:
    """What **default** and **paper's regression** mean in this run, from its config."""

    def onset(online: OnlineConfig) -> str:
        return "optimised with the PB" if online.optimize_onset else "carried over"

    online = config.online
    phase = (
        f", phase restarts from the learned cycles (scored on the last "
        f"{online.phase_restarts} steps)"
        if online.phase_restarts
        else ""
    )
    gate = (
        f", the surprise gate at {online.surprise_gate} RMS (power {online.gate_power:g})"
        if online.surprise_gate > 0
        else ", no surprise gate"
    )
    text = (
        f"**default** is this run's configuration. Learning: "
        f"{_describe_learning(config.train)} (the larger set: "
        f"{config.larger_train.iterations:,} iterations). On-line: "
        f"L = {online.window}, {online.iterations} iterations, integration length "
        f"{online.pb.integration_length}, onset state {onset(online)}"
        f"{', restarts at the learned PBs' if online.restart_span else ''}"
        f"{phase}{gate}."
    )
    if config.compare_paper:
        paper = config.paper_online
        text += (
            f" **paper's regression** runs the same models with the paper's on-line "
            f"regression (L = {paper.window}, l = {paper.pb.integration_length}, "
            f"{paper.iterations} iterations, onset state {onset(paper)})."
        )
    return text


def _header(results: DemoResults) -> list[str]:
    config = results.config
    return [
        "# rnnpb — the experiments of Ito & Tani (2004), reproduced",
        "",
        f"rnnpb {results.rnnpb_version}, {'quick' if config.quick else 'full'} run, "
        f"{results.runtime_s:.0f} s on {results.versions['cpus']} CPU(s) "
        f"(jax {results.versions['jax']}, mujoco {results.versions['mujoco']}). "
        "Every number below is in `results.json`; the definitions of the measures are in "
        "`rnnpb.analysis.metrics` and docs/experiments.md.",
        "",
        describe_configuration(config),
        "",
        f"Every learning set holds {config.samples_per_pattern} demonstrations of each of its "
        f"patterns (the paper: 2), from the synthetic demonstrator with data seed "
        f"{config.data_seed}.",
    ]


def _summary_section(results: DemoResults) -> list[str]:
    ours, theirs = results.default, results.paper
    absent = "not run (quick)" if results.config.quick else "–"

    def spread(measure: str, per_pattern: bool = True) -> tuple[str, str]:
        def cell(summary: Summary | None) -> str:
            if summary is None:
                return absent
            value = getattr(summary, measure)
            return median_and_worst(flat(value) if per_pattern else list(value.values()))

        return cell(ours), cell(theirs)

    def worst(measure: str, prefix: str, none: str) -> tuple[str, str]:
        def cell(summary: Summary | None) -> str:
            if summary is None:
                return none
            return f"{prefix}{max(getattr(summary, measure).values()):.2e}"

        return cell(ours), cell(theirs)

    def recognised(summary: Summary | None) -> str:
        return f"{summary.recognized_correctly}/{summary.recognition_runs}" if summary else "–"

    target = sci(metrics.TRAIN_ERROR_TARGET)
    cases = [r.case for r in results.novel]
    rows = [
        (
            "final training error (MSE per output, worst of sets 1–4)",
            f"< {target} (RMS, read as MSE)",
            *worst("train_mse", "max ", absent),
        ),
        ("final training error as RMS (worst)", f"< {target}", *worst("train_rms", "", "–")),
        (
            "steps until locked on a learned pattern",
            f"about {metrics.LOCK_LIMIT}",
            *spread("sync_steps_to_lock"),
        ),
        ("steps until the PB settles", f"about {metrics.SETTLE_LIMIT}", *spread("pb_settle_steps")),
        (
            "phase lag once locked (steps; + = robot behind)",
            "mostly synchronous",
            *spread("phase_lag_steps"),
        ),
        (
            f"robot motion during a {PAUSE_STEPS}-step pause (relative to before)",
            "keeps moving",
            *spread("pause_relative_motion"),
        ),
        ("steps to re-lock after the pause", "a few", *spread("pause_steps_to_relock")),
        (
            "steps until the robot follows a switch (every ordered pair, sets 1–4)",
            "several",
            *spread("switch_steps"),
        ),
        (
            "learned pattern recognised (nearest learned PB)",
            "all",
            recognised(ours),
            recognised(theirs),
        ),
        (
            "novel-pattern responses (case 1 / 2 / 3)",
            "all three occur",
            " / ".join(str(cases.count(c)) for c in metrics.RESPONSE_CASES),
            "–",
        ),
        (
            "larger set: runs that follow every pattern",
            f"{metrics.LARGER_SET_FOLLOWS} of {metrics.LARGER_SET_RUNS}",
            f"{results.larger_set_success} of {len(results.larger)}",
            "–",
        ),
    ]
    return [
        "",
        "## Summary",
        "",
        *table(("measure", "paper", "ours (default)", "ours (paper's regression)"), rows),
    ]


def _verdict(target: Target | None) -> str:
    if target is None:
        return "–"
    return f"{'met' if target.met else 'NOT met'} ({target.detail})"


def _targets_section(results: DemoResults) -> list[str]:
    seeds = results.draws.scenario_seeds
    pooled, theirs = results.draws.targets, results.paper_targets
    rows = [
        (
            key,
            _verdict(value),
            _verdict(pooled.get(key)),
            _verdict(theirs.get(key) if theirs else None),
        )
        for key, value in results.targets.items()
    ]
    return [
        "",
        "### Targets",
        "",
        f"For the report's draw of the user's imperfection (scenario seed {seeds[0]}) and "
        f"over all {len(seeds)} draws ({', '.join(map(str, seeds))}; see "
        '"Other draws of the user\'s imperfection" below):',
        "",
        *table(("target", "default", "default, all draws", "paper's regression"), rows),
    ]


def _patterns_section(results: DemoResults) -> list[str]:
    return [
        "",
        "## The four movement patterns (Figure 4)",
        "",
        embed("patterns", "figure4_patterns.png"),
    ]


def _learning_section(results: DemoResults) -> list[str]:
    ours = results.default
    rows = [
        (k, f"{ours.train_mse[k]:.2e}", f"{ours.train_rms[k]:.2e}", f"{ours.train_seconds[k]:.0f}")
        for k in sorted(ours.train_mse)
    ]
    return [
        "",
        "## Learning",
        "",
        *table(("learning set", "MSE (worst output)", "RMS", "seconds"), rows),
        "",
        embed("training", "training.png"),
    ]


def _synchronization_section(results: DemoResults) -> list[str]:
    ours = results.default
    rows = [
        (
            k,
            p,
            fmt(ours.sync_steps_to_lock[k][p]),
            fmt(ours.pb_settle_steps[k][p]),
            fmt(ours.phase_lag_steps[k][p], 2),
            ours.recognized_pattern[k][p],
            fmt(ours.pause_relative_motion[k][p], 2),
            fmt(ours.pause_steps_to_relock[k][p]),
        )
        for k in sorted(ours.sync_steps_to_lock)
        for p in ours.sync_steps_to_lock[k]
    ]
    return [
        "",
        "## 3.1 Synchronization and pause (Figure 5)",
        "",
        *table(
            (
                "set",
                "pattern",
                "steps to lock",
                "PB settles",
                "phase lag",
                "recognised",
                "motion in pause",
                "re-lock",
            ),
            rows,
        ),
        "",
        embed("synchronization", "figure5_synchronization.png"),
    ]


def _switching_section(results: DemoResults) -> list[str]:
    return [
        "",
        "## 3.2 Switching (Figures 6 and 7)",
        "",
        "Steps from the user's switch until the robot follows the new pattern, for "
        "every ordered pair of learned patterns in every learning set (the user performs "
        f"{SWITCH_STEPS_EACH} steps of the first pattern, then the second):",
        "",
        embed("switching matrix", "switching_matrix.png"),
        "",
        embed("switching", "figure6_switching.png"),
        "",
        embed("switching zoom", "figure7_switching_zoom.png"),
    ]


def _novel_section(results: DemoResults) -> list[str]:
    rows = [
        (r.learning_set, r.novel_pattern, f"x{r.amplitude:g}", r.description) for r in results.novel
    ]
    periods = "; ".join(
        f"set {k}: " + ", ".join(f"{p}→{fmt(v)}" for p, v in found.items())
        for k, found in results.closed_loop_periods.items()
    )
    return [
        "",
        "## 3.3 Novel patterns and attractors (Figures 8 and 9)",
        "",
        "One cycle of the pattern a learning set left out is repeated while the PB is "
        "regressed on-line; the robot's response after the transient is classified "
        "(case 1: a limit cycle like a learned one; 2: a new limit cycle; 3: unsteady).",
        "",
        *table(("set", "novel pattern", "size", "response"), rows),
        *missing_cases_explanation(results.novel_all or results.novel, results.closed_loop_periods),
        "",
        embed("novel", "figure8_novel.png"),
        "",
        embed("attractors", "figure9_attractors.png"),
        "",
        "Closed-loop periods of the learned patterns (steps; none = not periodic): " + periods,
        "",
        "Whether the robot itself tells a novel movement from a learned one, or from noise "
        "(section 4.1): `rnnpb study novelty --out DIR` (docs/experiments.md).",
    ]


def _larger_set_section(results: DemoResults) -> list[str]:
    rows = [
        (
            r.seed,
            f"{r.train_mse_max:.2e}",
            " / ".join(fmt(v) for v in r.steps_to_follow.values()),
            "yes" if r.follows_all else "no",
        )
        for r in results.larger
    ]
    return [
        "",
        "## 3.4 The larger set",
        "",
        *table(("seed", "training MSE", "steps to follow 1 / 2 / 3 / 4", "follows all"), rows),
    ]


DISTRIBUTION_NAMES = {
    "steps_to_lock": ("steps until locked on a learned pattern", f"about {metrics.LOCK_LIMIT}"),
    "pb_settle_steps": ("steps until the PB settles", f"about {metrics.SETTLE_LIMIT}"),
    "phase_lag_steps": ("phase lag once locked (steps)", "mostly synchronous"),
    "pause_relative_motion": ("robot motion during the pause (relative)", "keeps moving"),
    "pause_steps_to_relock": (
        "steps to re-lock after the pause",
        f"a few (≤ {metrics.RELOCK_LIMIT})",
    ),
    "switch_steps": (
        "steps until the robot follows a switch",
        f"several (≤ {metrics.SWITCH_LIMIT})",
    ),
    "steps_to_follow": (
        "larger set: steps until the robot follows each pattern",
        f"≤ {metrics.SWITCH_LIMIT}",
    ),
}


def _share(interval) -> str:
    if interval is None or interval.n == 0:
        return "–"
    return f"{interval.value:.0%} [{interval.low:.0%}, {interval.high:.0%}]"


def _distribution_cells(found: Distribution | None) -> tuple[str, str]:
    if found is None:
        return "–", "–"
    digits = 2 if found.measure in ("phase_lag_steps", "pause_relative_motion") else 1
    never = f", never {found.never}/{found.n}" if found.never else ""
    return f"{found.median.describe(digits)}{never}", _share(found.within)


def _distributions_section(results: DemoResults) -> list[str]:
    ours, theirs = results.distributions, results.paper_distributions
    if ours is None:
        return []
    rows = []
    for measure, (name, paper) in DISTRIBUTION_NAMES.items():
        if measure not in ours.measures:
            continue
        compared = theirs.measures.get(measure) if theirs else None
        rows.append(
            (
                name,
                paper,
                *_distribution_cells(ours.measures[measure]),
                *_distribution_cells(compared),
            )
        )
    rows.append(
        (
            "learned pattern recognised (nearest learned PB)",
            "all",
            "–",
            _share(ours.recognised),
            "–",
            _share(theirs.recognised) if theirs else "–",
        )
    )
    rows.append(
        (
            f"networks whose final error is below {sci(metrics.TRAIN_ERROR_TARGET)}",
            "all",
            "–",
            _share(ours.train_below_target),
            "–",
            "–",
        )
    )
    if ours.larger_set_follows is not None:
        rows.append(
            (
                "larger set: (seed, draw) runs that follow every pattern",
                f"{metrics.LARGER_SET_FOLLOWS} of {metrics.LARGER_SET_RUNS}",
                "–",
                _share(ours.larger_set_follows),
                "–",
                "–",
            )
        )
    cases = []
    for label, found in (("default", ours), ("paper's regression", theirs)):
        if found is None:
            continue
        for kind, counts in found.novel_cases.items():
            if sum(counts.values()):
                cases.append((label, kind, *(counts[c] for c in metrics.RESPONSE_CASES)))
    periodic, total = ours.closed_loop_periodic
    return [
        "",
        "## Over every network and draw of the user",
        "",
        f"Every measure of section 3 over {len(ours.training_seeds)} networks per learning "
        f"set (training seeds {', '.join(map(str, ours.training_seeds))}) and "
        f"{len(ours.scenario_seeds)} draws of the user's imperfection (scenario seeds "
        f"{', '.join(map(str, ours.scenario_seeds))}), every pattern and ordered pair pooled; "
        f"the larger set over its {len(results.larger)} seeds and the same draws. Medians "
        "are over the runs where the event happened (never: how many it did not); the "
        "share counts values within the paper's limit (never counts as outside). "
        "Brackets: 95 % percentile bootstrap intervals (`rnnpb.analysis.statistics`). The "
        "sections above show the first seed's networks."
        + (
            f" The paper's regression ran on the networks of training seed(s) "
            f"{', '.join(map(str, theirs.training_seeds))} only (`compare_seeds`)."
            if theirs is not None and len(theirs.training_seeds) < len(ours.training_seeds)
            else ""
        ),
        "",
        *table(
            (
                "measure",
                "paper",
                "default: median [95 % CI]",
                "default: within",
                "paper's regression: median",
                "paper's regression: within",
            ),
            rows,
        ),
        "",
        "Novel-pattern responses over every network and draw (the repeated cycle is "
        "one exact cycle at each size; by hand, the user demonstrates the novel pattern "
        "with imperfect cycles, one demonstration per draw, as in the paper's interaction "
        f"experiment). Learned attractors that are limit cycles: {periodic} of {total} "
        "(the period may be fractional, `metrics.periodicity`).",
        "",
        *table(("regression", "input", "case 1", "case 2", "case 3"), cases),
    ]


def _draws_section(results: DemoResults) -> list[str]:
    draws = results.draws
    first = draws.scenario_seeds[0]
    lines = [
        "",
        "## Other draws of the user's imperfection",
        "",
        "The user's imperfection (period, size and shape from cycle to cycle, drift, "
        "sensor noise) is drawn at random; the figures above use one draw. The same "
        "models, driven by other draws, give (counts within the target; median and worst "
        "steps):",
        "",
    ]
    names = {
        "sync_steps_to_lock": "lock on",
        "pb_settle_steps": "PB settles",
        "pause_steps_to_relock": "re-lock",
        "switch_steps": "switch",
    }
    header = (
        "scenario seed",
        *(f"{names[t.measure]} ≤ {t.limit}" for t in STEP_TARGETS),
        "larger set",
    )
    lines += table(header, [])
    for seed, draw in draws.by_seed.items():
        cells: list[str] = [f"{seed}{' (above)' if int(seed) == first else ''}"]
        for target in STEP_TARGETS:
            values = flat(getattr(draw, target.measure))
            cells.append(
                f"{within(values, target.limit)}/{len(values)} ({median_and_worst(values)})"
            )
        n_larger = len(draw.larger_set_steps_to_follow)
        cells.append(f"{draw.larger_set_success}/{n_larger}" if n_larger else "–")
        lines.append(row(cells))
    return lines


def _files_section(results: DemoResults) -> list[str]:
    return [
        "",
        "## Files",
        "",
        "Models (reuse them with `rnnpb interact --model …`): "
        + ", ".join(f"`{v}`" for v in results.files.models.values())
        + ".",
        "Learning sets as sequence CSVs: `data/set1/` … `data/set4/`, `data/full/`.",
        "",
    ]


SECTIONS = (
    _header,
    _summary_section,
    _targets_section,
    _distributions_section,
    _patterns_section,
    _learning_section,
    _synchronization_section,
    _switching_section,
    _novel_section,
    _larger_set_section,
    _draws_section,
    _files_section,
)


def report_lines(results: DemoResults) -> list[str]:
    """``report.md``, section after section, as lines."""
    return [line for section in SECTIONS for line in section(results)]


def write_report(path: str | os.PathLike[str], results: DemoResults) -> None:
    """Write the report of ``results`` to ``path`` (``run_demo`` writes it with the
    results)."""
    write_lines(path, report_lines(results))
