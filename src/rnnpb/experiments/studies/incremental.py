"""``rnnpb study incremental``: learning without forgetting, by rehearsal and consolidation
(paper 4.1).

For each learning set 1–4 the left-out pattern is added to the set's model by each method of
:func:`rnnpb.model.consolidation.consolidate` (rehearsal, fine-tuning, replay of the original
data, learning everything from scratch); a chain adds patterns one at a time by rehearsal; new
shapes of the demonstrator are added to the larger set's model
(:mod:`rnnpb.experiments.scenarios.incremental_scenario`). Before and after, for old and new
patterns (:mod:`~rnnpb.experiments.scenarios.incremental_measures`): closed-loop generation
against the model's own before and against the data, lock-on and recognition, switching, the
training error and the time each method takes.

Models: ``--models DIR`` (``set1.npz`` … ``set4.npz`` and the larger set's ``full.npz`` or
``full_seed0.npz``, as ``rnnpb demo`` writes them). Without it the study learns its starting
models into ``OUT/models/``: the full form with the paper's algorithm, the quick form small
fast-preset models.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any

from rnnpb.analysis import metrics
from rnnpb.experiments.exams import Exam, load_exam
from rnnpb.experiments.reporting import embed, fmt, table, versions, write_outputs
from rnnpb.experiments.scenarios.incremental_measures import ModelMeasures
from rnnpb.experiments.scenarios.incremental_runs import study_jobs
from rnnpb.experiments.scenarios.incremental_scenario import IncrementalConfig
from rnnpb.experiments.studies import StudyOptions, StudyOutcome
from rnnpb.experiments.studies._pool import study_pool
from rnnpb.experiments.summary import Target

NAME = "incremental"
SUMMARY = "add a pattern to a learned model by rehearsal, fine-tuning, replay or from scratch"

PAPER_PATTERNS = ("1", "2", "3", "4")
# --- the runner ------------------------------------------------------------------------------


def run(out: Path, options: StudyOptions) -> StudyOutcome:
    """``rnnpb study incremental``: the models of ``--models DIR``, else learned here."""
    return run_study(Path(out), study_config(options), exam=options.exam)


def study_config(options: StudyOptions) -> IncrementalConfig:
    """What the study runs for ``options``: the quick form, the exam's new data, user and
    learning sets, or the full form with both drawn from ``options.seed``."""
    exam = options.exam
    if options.quick:
        config = IncrementalConfig.quick_run(options.seed)
    elif exam is not None:
        config = IncrementalConfig(
            new_data_seed=exam.seed_list("new_data")[0],
            scenario_seed=exam.seed_list("user")[0],
        )
        config = replace(config, learning_sets=exam.learning_sets or config.learning_sets)
    else:
        config = IncrementalConfig(
            # The starting models learned the draw-0 data, which replay and scratch take again;
            # --seed draws the new pattern's demonstrations and the user.
            new_data_seed=options.seed,
            scenario_seed=100 + options.seed,
        )
    return replace(config, models=options.models, workers=options.workers)


def run_study(
    out: Path, config: IncrementalConfig, log=print, exam: Exam | None = None
) -> StudyOutcome:
    """Run the study and write ``out/report.md``, ``out/results.json`` and the figures; after
    every job, so that a run stopped early keeps what it measured, marked partial. ``exam``:
    the run is that exam (recorded in ``results.json``); the targets are judged by the exam
    file's definitions in any case."""
    definitions = exam or load_exam(NAME)
    generation_limit = definitions.target("rehearsal_old_generation").limit
    from rnnpb.analysis.figures import plot_forgetting

    began = time.perf_counter()
    (out / "models").mkdir(parents=True, exist_ok=True)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    before: dict[str, ModelMeasures] = {}
    after: dict[str, dict[str, ModelMeasures]] = {}
    chained: list[ModelMeasures] = []
    larger: dict[str, ModelMeasures] = {}  # "before", then each new shape added

    def write(done: int, total: int) -> StudyOutcome:
        forgetting: dict[str, dict[str, Sequence[float]]] = {
            m: {
                n: after[n][m].old_generation()
                for n in config.learning_sets
                if m in after.get(n, {})
            }
            for m in config.methods
        }
        plot_forgetting(forgetting, out / "figures" / "forgetting.png", generation_limit)
        targets = judge(after, chained, definitions)
        runtime = time.perf_counter() - began
        measured = (before, after, chained, larger)
        outputs = results(config, *measured, targets, runtime, (done, total))
        if exam is not None:
            outputs["exam"] = exam.to_json()
        lines = report(config, *measured, targets, runtime, (done, total), exam)
        write_outputs(out, lines, outputs)
        return StudyOutcome(runtime, targets)

    outcome = StudyOutcome(0.0)
    with study_pool(config.workers, init_here=config.workers > 1) as pool:
        for done, (total, kind, result) in enumerate(study_jobs(pool, config, out), start=1):
            if kind == "chain":
                chained.extend(result)
                log("  chain done")
            elif kind.startswith("larger:"):
                shape = kind.removeprefix("larger:")
                larger[shape] = result[2]
                log(f"  larger set {'before' if shape == 'before' else '+ ' + shape} done")
            else:
                name, method, measured = result
                if method is None:
                    before[name] = measured
                else:
                    after.setdefault(name, {})[method] = measured
                log(f"  set {name} {method or 'before'} done")
            outcome = write(done, total)
    return outcome


# --- the judge -------------------------------------------------------------------------------


def judge(
    after: dict[str, dict[str, ModelMeasures]],
    chained: list[ModelMeasures],
    exam: Exam | None = None,
) -> dict[str, Target]:
    """Every target measured, by ``exam``'s definitions (default: the study's exam file)."""
    exam = exam or load_exam(NAME)
    measured: dict[str, tuple[float | None, str]] = {}
    rehearsal = {name: m["rehearsal"] for name, m in after.items() if "rehearsal" in m}
    if rehearsal:
        measured |= _rehearsal(rehearsal, exam)
    if chained:
        target = exam.target("chain_all_followed")
        lock, switch = target.parameter("lock_steps"), target.parameter("switch_steps")
        locks = ", ".join(
            f"{p}: lock {fmt(m.steps_to_lock)}" for p, m in chained[-1].pattern.items()
        )
        measured["chain_all_followed"] = (
            float(chained[-1].followed(lock, switch)),
            f"after {len(chained) - 1} consolidation(s): {locks}",
        )
    return {
        name: Target(exam.target(name).met(value), detail, value)
        for name, (value, detail) in measured.items()
    }


def judge_results(results: dict[str, Any], exam: Exam) -> dict[str, Target]:
    """The targets judged by ``exam``'s definitions from a finished ``results.json``."""
    after = {
        name: {method: ModelMeasures.from_json(m) for method, m in methods.items()}
        for name, methods in results["after"].items()
    }
    return judge(after, [ModelMeasures.from_json(m) for m in results["chain"]], exam)


def _rehearsal(
    rehearsal: dict[str, ModelMeasures], exam: Exam
) -> dict[str, tuple[float | None, str]]:
    """The rehearsal targets' values: the share of learning sets followed, the worst old
    pattern's generation moved, the slowest consolidation's CPU seconds."""
    target = exam.target("rehearsal_all_followed")
    lock, switch = target.parameter("lock_steps"), target.parameter("switch_steps")
    followed = [name for name, m in rehearsal.items() if m.followed(lock, switch)]
    old = [d for m in rehearsal.values() for d in m.old_generation()]
    cpu = [m.cpu_seconds for m in rehearsal.values() if m.cpu_seconds is not None]
    wall = [m.seconds for m in rehearsal.values()]
    return {
        "rehearsal_all_followed": (
            len(followed) / len(rehearsal),
            f"{len(followed)}/{len(rehearsal)} learning sets: every pattern locked on within "
            f"{lock:g} and recognised, every switch within {switch:g}",
        ),
        "rehearsal_old_generation": (
            max(old, default=None),
            f"worst old pattern's generation moved {fmt(max(old, default=math.nan), 3)} RMS "
            f"(limit {exam.target('rehearsal_old_generation').limit:g})",
        ),
        "rehearsal_within_60s": (
            max(cpu, default=None),
            f"slowest {max(cpu, default=math.nan):.1f} s of CPU time in a single-threaded "
            f"process ({max(wall):.1f} s wall-clock of learning, inflated by other load)",
        ),
    }


# --- the report ------------------------------------------------------------------------------


def report(
    config, before, after, chained, larger, targets, runtime, progress, on_exam: Exam | None
) -> list[str]:
    """``report.md``, section by section (``on_exam``: the exam the run is)."""
    return [
        *_introduction(config, runtime, progress),
        *([on_exam.describe(), ""] if on_exam is not None else []),
        *_targets_section(targets),
        *_methods_section(config, before, after),
        *_chain_section(config, chained),
        *(_larger_set_section(config, larger) if larger else []),
    ]


def _introduction(config: IncrementalConfig, runtime: float, progress) -> list[str]:
    partial = progress[0] != progress[1]
    return [
        "# Incremental learning: rehearsal and consolidation",
        "",
        "Each learning set's left-out pattern is added to the set's model by each method "
        "(rehearsal: the new pattern with the model's own closed-loop regeneration of "
        "the old ones; finetune: the new pattern alone; replay: with the original data; "
        "scratch: everything learned anew). Generation: RMS distance (normalized joints) "
        "of each pattern's closed-loop cycle from the starting model's and from the "
        "nearest demonstration's. Lock-on and switching in steps (targets "
        f"{metrics.LOCK_LIMIT} and {metrics.SWITCH_LIMIT}). Recognised as: the on-line "
        f"recognition's answer after the pattern's first {config.sync_before} steps (what the "
        "robot says it "
        'sees; docs/model.md, "Recognition and novelty"); nearest PB: the learned pattern '
        "whose PB was nearest then (the paper's reading, for comparison).",
        "",
        f"Starting models: {config.models or 'learned here'}; "
        f"{'quick form' if config.quick else 'full form'}; runtime {runtime:.0f} s"
        + (f"; **partial: {progress[0]} of {progress[1]} jobs done**." if partial else "."),
        "",
    ]


def _targets_section(targets: dict[str, Target]) -> list[str]:
    rows = [(k, "yes" if t.met else "**no**", t.detail) for k, t in targets.items()]
    return ["## Targets", "", *table(("target", "met", "detail"), rows), ""]


def _worst_switch(m: ModelMeasures) -> int | None:
    switches = [v for v in m.switching.values() if v is not None]
    return None if len(switches) < len(m.switching) else max(switches, default=0)


def _worst_old(m: ModelMeasures) -> str:
    old = m.old_generation()
    return fmt(max(old), 3) if old else "–"


def _method_row(name: str, label: str, m: ModelMeasures) -> tuple:
    learned = label != "before"
    return (
        name,
        label,
        ", ".join(m.patterns),
        _worst_old(m),
        ", ".join(fmt(p.steps_to_lock) for p in m.pattern.values()),
        ", ".join(p.recognized or "–" for p in m.pattern.values()),
        ", ".join(p.nearest_pb for p in m.pattern.values()),
        fmt(_worst_switch(m)),
        f"{m.train_mse_max:.1e}",
        f"{m.seconds:.1f}" if learned else "–",
        fmt(m.cpu_seconds, 1) if learned else "–",
        m.iterations if learned else "–",
        "yes" if m.followed() else "no",
    )


def _methods_section(config: IncrementalConfig, before, after) -> list[str]:
    measured = [
        (name, label, m)
        for name in config.learning_sets
        for label, m in [
            *([("before", before[name])] if name in before else []),
            *after.get(name, {}).items(),
        ]
    ]
    header = (
        "set | method | patterns | old generation vs before (worst) | lock-on per pattern | "
        "recognised as | nearest PB | worst switch | training MSE (max) | seconds (wall) | "
        "CPU seconds | iterations | all followed"
    ).split(" | ")
    vs_data = [
        (
            name,
            label,
            *(
                fmt(m.pattern[p].generation_vs_data, 3) if p in m.pattern else "–"
                for p in PAPER_PATTERNS
            ),
        )
        for name, label, m in measured
    ]
    return [
        "## Per learning set and method",
        "",
        *table(header, [_method_row(*row) for row in measured]),
        "",
        "Generation against the data (RMS, per pattern):",
        "",
        *table(("set", "method", *PAPER_PATTERNS), vs_data),
        "",
        embed("forgetting per method", "forgetting.png"),
        "",
    ]


def _chain_section(config: IncrementalConfig, chained: list[ModelMeasures]) -> list[str]:
    header = (
        "step | patterns | lock-on | old generation vs before (worst) | worst switch | "
        "seconds (wall) | CPU seconds | all followed"
    ).split(" | ")
    rows = [
        (
            m.label,
            ", ".join(m.patterns),
            ", ".join(fmt(p.steps_to_lock) for p in m.pattern.values()),
            _worst_old(m),
            fmt(_worst_switch(m)),
            f"{m.seconds:.1f}",
            fmt(m.cpu_seconds, 1) if m.cpu_seconds is not None else "–",
            "yes" if m.followed() else "no",
        )
        for m in chained
    ]
    return [
        "## The chain",
        "",
        f"Learned {', '.join(config.chain_start)}, then added "
        f"{', '.join(config.chain_added)} one at a time by rehearsal.",
        "",
        *table(header, rows),
    ]


def _larger_set_section(config: IncrementalConfig, larger: dict[str, ModelMeasures]) -> list[str]:
    header = (
        "added | lock-on per pattern | recognised as | old generation vs before (worst) | "
        "worst switch | CPU seconds | all followed"
    ).split(" | ")
    rows = [
        (
            shape,
            ", ".join(f"{p}: {fmt(v.steps_to_lock)}" for p, v in m.pattern.items()),
            ", ".join(v.recognized or "–" for v in m.pattern.values()),
            _worst_old(m),
            fmt(_worst_switch(m)),
            fmt(m.cpu_seconds, 1) if m.cpu_seconds is not None else "–",
            "yes" if m.followed() else "no",
        )
        for shape, m in larger.items()
    ]
    return [
        "",
        "## The larger set and new shapes",
        "",
        "The larger set's model (the paper's four patterns), and each new shape of the "
        f"demonstrator ({', '.join(config.larger_set_shapes)}) added to it by rehearsal.",
        "",
        *table(header, rows),
    ]


def results(config, before, after, chained, larger, targets, runtime, progress) -> dict[str, Any]:
    """``results.json``: every measure, with the config and the versions."""
    return {
        "study": NAME,
        "config": asdict(config),
        "versions": versions(),
        "runtime_s": runtime,
        "jobs_done": progress[0],
        "jobs": progress[1],
        "targets": {k: t.to_json() for k, t in targets.items()},
        "before": {k: asdict(v) for k, v in before.items()},
        "after": {k: {m: asdict(v) for m, v in d.items()} for k, d in after.items()},
        "chain": [asdict(m) for m in chained],
        "larger_set": {k: asdict(v) for k, v in larger.items()},
    }
