"""``rnnpb study teach``: teaching by showing, end to end (paper 4.1; docs/teaching.md).

Per learning set (1–4 and the larger set) and new shape, a scripted user teaches the robot the
shape (:mod:`rnnpb.experiments.scenarios.teaching_scenario`); measured
(:mod:`~rnnpb.experiments.scenarios.teaching_measures`): the timeline, the detection delay,
the episodes kept, the consolidation's time, the lock-on to the shape's next performance and
the interaction time to follow it, the paper's measures of the old patterns before and after,
the episodes kept from unstructured movement, and the deadlines of a paced run at dt 0.4.

Models: ``--models DIR`` (``set1.npz`` … ``set4.npz`` and ``full.npz`` or ``full_seed0.npz``,
as ``rnnpb demo`` writes them; copied into ``OUT/runs/``, never written). Without it the full
form learns them with the paper's algorithm into ``OUT/models/``; the quick form teaches the
shipped fast-preset model of learning set 1 one shape.
"""

from __future__ import annotations

import math
import statistics
import time
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any

from rnnpb.analysis import metrics
from rnnpb.experiments.exams import Exam, ExamTarget, load_exam
from rnnpb.experiments.reporting import embed, fmt, table, versions, write_outputs
from rnnpb.experiments.scenarios.teaching_measures import (
    LATE_S,
    PacedRun,
    PaperMeasures,
    TeachRun,
    old_pattern_misses,
    worst,
)
from rnnpb.experiments.scenarios.teaching_runs import job_count, paced_job, study_jobs
from rnnpb.experiments.scenarios.teaching_scenario import TeachConfig, starting_models
from rnnpb.experiments.studies import StudyOptions, StudyOutcome
from rnnpb.experiments.studies._pool import study_pool
from rnnpb.experiments.summary import Target

NAME = "teach"
SUMMARY = "teach a new shape on-line: notice it, keep it, consolidate it while moving, follow it"


# --- the runner ------------------------------------------------------------------------------


def run(out: Path, options: StudyOptions) -> StudyOutcome:
    """``rnnpb study teach``: the models of ``--models DIR``, else the shipped model (quick)
    or models learned here with the paper's algorithm (full)."""
    return run_study(Path(out), study_config(options), exam=options.exam)


def study_config(options: StudyOptions) -> TeachConfig:
    """What the study runs for ``options``: the quick form, the exam's user, shapes and
    learning sets, or the full form with the user drawn from ``options.seed``."""
    exam = options.exam
    if options.quick:
        config = TeachConfig.quick_run(options.seed)
        if options.models is not None:
            config = replace(config, models=options.models, shipped=False)
        return config
    seed = exam.seed_list("user")[0] if exam is not None else 100 + options.seed
    config = TeachConfig(models=options.models, scenario_seed=seed, workers=options.workers)
    if exam is None:
        return config
    sets = exam.learning_sets or config.learning_sets
    return replace(config, shapes=exam.shapes or config.shapes, learning_sets=sets)


def run_study(out: Path, config: TeachConfig, log=print, exam: Exam | None = None) -> StudyOutcome:
    """Run the study and write ``out/report.md``, ``out/results.json`` and the figures; after
    every job, so that a run stopped early keeps what it measured, marked partial. ``exam``:
    the run is that exam (recorded in ``results.json``); the targets are judged by the exam
    file's definitions in any case."""
    from rnnpb.analysis.figures.teach import plot_taught_run

    definitions = exam or load_exam(NAME)
    began = time.perf_counter()
    out = Path(out)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    (out / "runs").mkdir(parents=True, exist_ok=True)
    runs: dict[tuple[str, str], TeachRun] = {}
    before: dict[str, PaperMeasures] = {}
    paced: PacedRun | None = None

    def write(done: int, total: int) -> StudyOutcome:
        ordered = [
            runs[(n, s)] for n in config.learning_sets for s in config.shapes if (n, s) in runs
        ]
        targets = judge(ordered, paced, definitions)
        runtime = time.perf_counter() - began
        progress = (done, total)
        measured = results(config, ordered, before, paced, targets, runtime, starts, progress)
        if exam is not None:
            measured["exam"] = exam.to_json()
        write_outputs(
            out,
            report(config, ordered, before, paced, targets, runtime, progress, definitions, exam),
            measured,
        )
        return StudyOutcome(runtime, targets)

    total, outcome = job_count(config), StudyOutcome(0.0)
    # One core here too: the jobs may run here, and the consolidations they start inherit it.
    # Models given are checked before any worker starts; those learned here, in the workers.
    given = config.shipped or config.models is not None
    starts = starting_models(config, out / "models") if given else {}
    with study_pool(config.workers, init_here=True) as pool:
        starts = starts or starting_models(config, out / "models", pool)
        jobs = study_jobs(pool, config, starts, out / "runs")
        for done, result in enumerate(jobs, start=1):
            if isinstance(result, TeachRun):
                runs[(result.learning_set, result.shape)] = result
                plot_taught_run(
                    result.timeline, out / "figures", result.learning_set, result.shape, config.dt
                )
                log(
                    f"  [{done}/{total}] set {result.learning_set} {result.shape}: "
                    f"{len(result.episodes)} episode(s), follow {fmt(result.follow_s)} s"
                )
            else:
                before[result[0]] = result[1]
                log(f"  [{done}/{total}] set {result[0]}: measured before teaching")
            outcome = write(done, total)
    if config.paced is not None and config.paced in runs and runs[config.paced].new_pattern:
        # Alone, after the others: the loop and the consolidation each have a core.
        paced = paced_job(*config.paced, starts[config.paced[0]], config, out / "runs")
        log(f"  paced run: {paced.missed_deadlines} missed deadline(s)")
        outcome = write(total, total)
    return outcome


# --- the judge -------------------------------------------------------------------------------


def judge(
    runs: list[TeachRun], paced: PacedRun | None, exam: Exam | None = None
) -> dict[str, Target]:
    """Every target measured, by ``exam``'s definitions (default: the study's exam file)."""
    exam = exam or load_exam(NAME)
    measures = {
        "follow_within_90s": lambda t: _follow(runs, t),
        "follow_next_performance": lambda t: _follow_next(runs, t),
        "next_performance_recognised": lambda t: _recognised_next(runs, t),
        "no_duplicate_patterns": lambda t: _duplicates(runs),
        "consolidation_cpu": lambda t: _consolidation_cpu(runs, paced),
        "no_missed_deadline": lambda t: _deadlines(paced) if paced is not None else None,
        "old_patterns_keep_paper_targets": lambda t: _old_patterns(runs, t),
        "old_patterns_within_limits": lambda t: _old_patterns_share(runs, t),
        "nothing_kept_from_unstructured": lambda t: _unstructured(runs),
    }
    # The exam's targets, each by its definition (an earlier version defines fewer).
    measured = {name: measures[name](exam.target(name)) for name in exam.targets}
    return {
        name: Target(exam.target(name).met(value), detail, value)
        for name, (value, detail) in ((k, m) for k, m in measured.items() if m is not None)
    }


def judge_results(results: dict[str, Any], exam: Exam) -> dict[str, Target]:
    """The targets judged by ``exam``'s definitions from a finished ``results.json``."""
    runs = [TeachRun.from_json(r) for r in results["runs"]]
    paced = PacedRun.from_json(results["paced"]) if results["paced"] else None
    return judge(runs, paced, exam)


def _follow(runs: list[TeachRun], target: ExamTarget) -> tuple[float, str]:
    """The share of runs that followed: locked on to the new shape's next performance within
    the target's steps, within its seconds of interaction counted to the step it locked on."""
    lock, seconds = target.parameter("lock_steps"), target.parameter("seconds")
    locked = [
        r.follow_s
        for r in runs
        if r.lock_next is not None and r.lock_next <= lock and r.follow_s is not None
    ]
    met = [f for f in locked if f <= seconds]
    late = [r.lock_next for r in runs if r.lock_next is not None and r.lock_next > lock]
    never = sum(r.lock_next is None or r.follow_s is None for r in runs)
    return len(met) / len(runs) if runs else math.nan, (
        f"{len(met)}/{len(runs)} runs locked on within {lock:g} steps of the "
        f"shape's next performance, within {seconds:.0f} s of interaction "
        f"(worst {fmt(max(locked)) if locked else 'none'} s"
        + (
            f"; {len(late)} locked on later ({', '.join(str(v) for v in sorted(late))} steps)"
            if late
            else ""
        )
        + (f"; {never} never followed" if never else "")
        + ")"
    )


def _follow_next(runs: list[TeachRun], target: ExamTarget) -> tuple[float, str]:
    """The share of runs that learned the new shape and locked on to its next performance
    within the target's steps."""
    lock = target.parameter("lock_steps")
    locked = [r for r in runs if r.new_pattern and r.lock_next is not None and r.lock_next <= lock]
    late = sorted(r.lock_next for r in runs if r.lock_next is not None and r.lock_next > lock)
    never = sum(not r.new_pattern or r.lock_next is None for r in runs)
    return len(locked) / len(runs) if runs else math.nan, (
        f"{len(locked)}/{len(runs)} runs locked on within {lock:g} steps of the shape's next "
        "performance"
        + (f"; later: {', '.join(str(v) for v in late)} steps" if late else "")
        + (f"; {never} never (or nothing learned)" if never else "")
    )


def next_performance_share(run: TeachRun, settle: int) -> float:
    """The share of the steps of the shape's next performance (the run's last segment), from
    its ``settle``-th step on, recognised as the pattern it was learned as (0 when none)."""
    if not run.new_pattern or not run.segments or "recognised" not in run.timeline:
        return 0.0
    steps = run.segments[-1][1]
    recognised = run.timeline["recognised"][-steps:][int(settle) :]
    return sum(r == run.new_pattern for r in recognised) / len(recognised) if recognised else 0.0


def _recognised_next(runs: list[TeachRun], target: ExamTarget) -> tuple[float, str]:
    """The next performance's settled steps recognised as the taught pattern, averaged over
    the runs (a run that learned nothing counts 0)."""
    settle = target.parameter("settle_steps")
    shares = [next_performance_share(r, settle) for r in runs]
    mean = sum(shares) / len(shares) if shares else math.nan
    low = sorted((s, f"set {r.learning_set} {r.shape}") for s, r in zip(shares, runs, strict=True))
    return mean, (
        f"mean {100 * mean:.1f} % of the settled steps (from step {settle:g}) over {len(runs)} "
        "runs; lowest: " + ", ".join(f"{where} {100 * s:.0f} %" for s, where in low[:3])
    )


def _duplicates(runs: list[TeachRun]) -> tuple[float, str]:
    """Patterns learned beyond one for the shape, over every run (a repeat learned again)."""
    extra = {
        f"set {r.learning_set} {r.shape}": sorted(r.timeline.get("taught", {}))
        for r in runs
        if len(r.timeline.get("taught", {})) > 1
    }
    count = sum(len(v) - 1 for v in extra.values())
    return count, (
        f"{count} pattern(s) beyond one per run over {len(runs)} runs"
        + ("; " + "; ".join(f"{k}: {', '.join(v)}" for k, v in extra.items()) if extra else "")
    )


def _consolidation_cpu(runs: list[TeachRun], paced: PacedRun | None) -> tuple[float, str]:
    """The CPU seconds of the longest teaching consolidation (its process), over every run."""
    times = [c.cpu_s for r in runs for c in r.consolidations]
    if paced is not None and paced.consolidation is not None:
        times.append(paced.consolidation.cpu_s)
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


def _old_patterns_share(runs: list[TeachRun], target: ExamTarget) -> tuple[float | None, str]:
    """The old patterns' lock-ons and switches within the target's steps after teaching, as a
    share of all of them (a run that learned nothing counts one miss)."""
    lock, switch = target.parameter("lock_steps"), target.parameter("switch_steps")
    locks, switches, misses = old_pattern_misses(runs, lock, switch)
    total = len(locks) + len(switches) + sum(not r.new_pattern for r in runs)
    if not total:
        return None, "no old pattern measured"
    return 1.0 - len(misses) / total, (
        f"{total - len(misses)}/{total} within the limits"
        + (
            f"; missed: {'; '.join(misses[:12])}" + (" …" if len(misses) > 12 else "")
            if misses
            else ""
        )
    )


def _deadlines(paced: PacedRun) -> tuple[float, str]:
    """The paced steps that missed their deadline: the end of a step's slot, missed when the
    step's work took longer than dt (the loop's count) or its late start plus its work ran past
    the slot. A start later than ``LATE_S`` within the slot is jitter, reported beside."""
    full = paced.swap_step is not None
    return paced.missed_deadlines + paced.overrun_steps, (
        f"{paced.missed_deadlines} missed, {paced.overrun_steps} ran past their slot; "
        f"{paced.late_steps} started > {LATE_S * 1e3:.0f} ms late (latest "
        f"{paced.max_lateness_ms:.0f} ms) over {paced.steps} paced steps at dt {paced.dt:g}"
        + (" through the consolidation and the swap" if full else " (consolidation cut short)")
    )


def _old_patterns(runs: list[TeachRun], target: ExamTarget) -> tuple[float | None, str]:
    """The old patterns' lock-ons and switches beyond the target's steps after teaching (the
    quick form, without the paper's measures: their lock-on in the timeline after the swap);
    a run that learned nothing counts one. None when no old pattern was measured."""
    lock, switch = target.parameter("lock_steps"), target.parameter("switch_steps")
    locks, switches, misses = old_pattern_misses(runs, lock, switch)
    return len(misses) if locks else None, (
        f"old lock-on {sum(v is not None and v <= lock for v in locks)}/{len(locks)} within "
        f"{lock:g}, old switches "
        f"{sum(v is not None and v <= switch for v in switches)}/{len(switches)} "
        f"within {switch:g}"
        + (
            f"; missed: {'; '.join(misses[:12])}" + (" …" if len(misses) > 12 else "")
            if misses
            else ""
        )
    )


def _unstructured(runs: list[TeachRun]) -> tuple[float, str]:
    """The episodes kept that hold unstructured movement."""
    unstructured = sum(r.episodes_unstructured for r in runs)
    return unstructured, (
        f"{unstructured} episode(s) with unstructured movement, over {len(runs)} runs "
        f"({sum(len(r.episodes) for r in runs)} episodes kept in all)"
    )


# --- the report ------------------------------------------------------------------------------


def report(
    config, runs, before, paced, targets, runtime, progress, exam: Exam, on_exam: Exam | None
) -> list[str]:
    """``report.md``, section by section (``on_exam``: the exam the run is)."""
    return [
        *_introduction(config, runs, runtime, progress, exam.target("follow_within_90s")),
        *([on_exam.describe(), ""] if on_exam is not None else []),
        *_targets_section(targets),
        *_runs_section(runs),
        *_old_patterns_section(runs, before),
        *(_paced_section(paced) if paced is not None else []),
        *_timelines_section(runs),
    ]


def _introduction(
    config: TeachConfig, runs, runtime: float, progress, follow: ExamTarget
) -> list[str]:
    performed = " → ".join(f"{m} ×{n}" for m, n in (runs[0].segments if runs else []))
    partial = progress[0] != progress[1]
    return [
        "# Study: teaching by showing — the robot learns a new shape on-line",
        "",
        f"Per learning set and new shape, a scripted user performs: {performed} (steps; the "
        "first of the learned patterns is another per shape). The loop runs "
        "as fast as possible with the teacher: it waits between two steps for each "
        "consolidation, so a run repeats. The new shape is learned from its two first "
        "performances. *Follow*: steps from the new shape's first step until the episode of "
        "its second performance is kept, plus the steps a paced loop runs while the consolidation "
        "takes its CPU time on one core, plus the lock-on steps on the shape's next "
        f"performance, × dt {config.dt:g} s (target ≤ {follow.parameter('seconds'):.0f} s, and "
        f"the lock-on itself within {follow.parameter('lock_steps'):g} steps, the paper's). The "
        "consolidation's wall time on this shared machine is the load's and is shown beside.",
        "",
        f"{'Quick form (shipped fast-preset model)' if config.quick else 'Full form'}; models "
        f"{'shipped' if config.shipped else config.models or 'learned here'}; consolidation "
        f"iterations {config.consolidation_iterations or 'the consolidation default'}; user "
        f"draws (scenario seeds) {config.scenario_seed}+shape index; runtime {runtime:.0f} s"
        + (f"; **partial: {progress[0]} of {progress[1]} jobs done**." if partial else "."),
        "",
    ]


def _targets_section(targets: dict[str, Target]) -> list[str]:
    rows = [(k, "yes" if t.met else "**no**", t.detail) for k, t in targets.items()]
    return ["## Targets", "", *table(("target", "met", "measured"), rows), ""]


def _run_row(r: TeachRun) -> tuple:
    c = r.consolidations[0] if r.consolidations else None
    first = next((e for e in r.episodes if not e.unstructured), None)
    follow = " + ".join(str(v) for v in r.follow_steps.values()) + f" steps = {fmt(r.follow_s)} s"
    return (
        r.learning_set,
        r.shape,
        fmt(r.detection_delay),
        f"{first.first_step}–{first.last_step} at {first.kept_at}" if first else "none",
        len(r.episodes),
        f"{c.cpu_s:.1f} / {c.wall_s:.0f}" if c else "–",
        r.new_pattern or "–",
        fmt(r.lock_next),
        fmt(100 * r.recognised_next, 0),
        follow if r.follow_s is not None else "never",
        r.episodes_unstructured,
    )


def _runs_section(runs: list[TeachRun]) -> list[str]:
    header = (
        "set | shape | detection delay (steps) | episode (steps, kept at) | episodes | "
        "consolidation CPU / wall (s) | learned as | lock-on next time | recognised next time % | "
        "follow (kept + consolidation + lock) | episodes from unstructured"
    ).split(" | ")
    return ["## Per learning set and shape", "", *table(header, map(_run_row, runs))]


def _old_patterns_section(runs: list[TeachRun], before: dict[str, PaperMeasures]) -> list[str]:
    rows = []
    for name, measures in before.items():
        locks = ", ".join(f"{p}: {fmt(v)}" for p, v in measures.lock.items())
        rows.append((name, "before", locks, fmt(worst(measures.switching.values())), "–", "–"))
        for r in runs:
            if r.learning_set != name or r.after is None:
                continue
            old = tuple(p for p in r.after.lock if p != r.new_pattern)
            new_pairs = {k: v for k, v in r.after.switching.items() if r.new_pattern in k}
            rows.append(
                (
                    name,
                    f"+{r.shape}",
                    ", ".join(f"{p}: {fmt(r.after.lock[p])}" for p in old),
                    fmt(worst(r.after.switching_among(old).values())),
                    fmt(r.after.lock.get(r.new_pattern)),
                    fmt(worst(new_pairs.values())),
                )
            )
    header = (
        "set | model | old lock-on from rest | old switching (worst) | new lock-on from rest | "
        "switching with the new (worst)"
    ).split(" | ")
    return [
        "",
        "## Old patterns after teaching (the paper's measures)",
        "",
        f"Lock-on from rest (paper 3.1, target ≤ {metrics.LOCK_LIMIT}) and switching for every "
        f"ordered pair (3.2, ≤ {metrics.SWITCH_LIMIT}), before teaching and after; worst over "
        "the old patterns.",
        "",
        *table(header, rows),
    ]


def _paced_section(paced: PacedRun) -> list[str]:
    c = paced.consolidation
    rows = [
        ("paced steps", paced.steps),
        ("missed deadlines (a step's work over dt)", paced.missed_deadlines),
        (f"steps started > {LATE_S * 1e3:.0f} ms late", paced.late_steps),
        ("steps whose late start plus work ran past their slot", paced.overrun_steps),
        ("latest start (ms after due)", fmt(paced.max_lateness_ms)),
        ("step work p99 / max (ms)", f"{paced.p99_step_ms:.1f} / {paced.max_step_ms:.1f}"),
        ("steps during the consolidation", fmt(paced.consolidation_steps)),
        ("consolidation CPU / wall (s)", f"{c.cpu_s:.1f} / {c.wall_s:.1f}" if c else "cut short"),
        ("first step with the new model (ms)", fmt(paced.swap_step_ms)),
        ("lock-on after the swap (steps)", fmt(paced.lock_after_swap)),
    ]
    return [
        "",
        "## Deadlines during the background consolidation (paced)",
        "",
        f"Learning set {paced.learning_set}: the user keeps performing {paced.shape} while "
        "the episodes kept in its run are consolidated again in the background process; "
        f"the loop paced at dt {paced.dt:g} s, the new model swapped in between two steps.",
        "",
        *table(("measure", "value"), rows),
    ]


def _timelines_section(runs: list[TeachRun]) -> list[str]:
    from rnnpb.analysis.figures.teach import timeline_file

    figures = [
        embed(f"set {r.learning_set} taught {r.shape}", timeline_file(r.learning_set, r.shape))
        for r in runs
    ]
    return ["", "## Timelines", "", *figures, ""]


def results(config, runs, before, paced, targets, runtime, starts, progress) -> dict[str, Any]:
    """``results.json``: every measure, with the config, the models and the versions (a run's
    motor error beside its timeline)."""

    return {
        "study": NAME,
        "config": asdict(config),
        "models": starts,
        "versions": versions(),
        "runtime_s": runtime,
        "jobs_done": progress[0],
        "jobs": progress[1],
        "targets": {k: t.to_json() for k, t in targets.items()},
        "runs": [r.to_json() for r in runs],
        "before": {k: asdict(v) for k, v in before.items()},
        "paced": asdict(paced) if paced is not None else None,
    }
