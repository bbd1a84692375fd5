"""``rnnpb study teach``: teaching by showing, end to end (paper 4.1; docs/teaching.md).

Per step time (the paper's 0.4 s and a person's 0.1 s), learning set (1–4 and the larger set)
and new movement (the demonstrator's new shapes and free shapes it does not make), a scripted
user shows the robot the movement as a person shows something — three cycles, other movements,
three cycles again — and then a third time
(:mod:`rnnpb.experiments.scenarios.teaching_scenario`); measured
(:mod:`~rnnpb.experiments.scenarios.teaching_measures`, the targets by
:mod:`~rnnpb.experiments.scenarios.teaching_targets`): whether the movement was learned from
the two showings before the third and its third showing recognised, patterns learned from
random movement and twice, the old patterns' lock-on after the swap, the consolidation's CPU
time, and the deadlines of a paced run at each step time.

Models: ``--models DIR`` (``set1.npz`` … ``set4.npz`` and ``full.npz`` or ``full_seed0.npz``,
as ``rnnpb demo`` writes them; copied into ``OUT/runs/``, never written). Without it the full
form learns them with the paper's algorithm into ``OUT/models/``; the quick form teaches the
shipped fast-preset model of learning set 1 one shape.
"""

from __future__ import annotations

import time
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any

from rnnpb.experiments.exams import Exam, load_exam
from rnnpb.experiments.reporting import embed, fmt, table, versions, write_outputs
from rnnpb.experiments.scenarios.teaching_measures import LATE_S, PacedRun, TeachRun
from rnnpb.experiments.scenarios.teaching_runs import job_count, paced_job, study_jobs
from rnnpb.experiments.scenarios.teaching_scenario import TeachConfig, starting_models
from rnnpb.experiments.scenarios.teaching_targets import (
    target_measures,
    third_showing_share,
    where,
)
from rnnpb.experiments.studies import StudyOptions, StudyOutcome
from rnnpb.experiments.studies._pool import study_pool
from rnnpb.experiments.summary import Target

NAME = "teach"
SUMMARY = (
    "teach new movements as people show them: keep, learn from two showings, recognise the third"
)


# --- the runner ------------------------------------------------------------------------------


def run(out: Path, options: StudyOptions) -> StudyOutcome:
    """``rnnpb study teach``: the models of ``--models DIR``, else the shipped model (quick)
    or models learned here with the paper's algorithm (full)."""
    return run_study(Path(out), study_config(options), exam=options.exam)


def study_config(options: StudyOptions) -> TeachConfig:
    """What the study runs for ``options``: the quick form, the exam's draws, or the full
    form with the user drawn from ``options.seed`` (development draws 600 on)."""
    exam = options.exam
    if options.quick:
        config = TeachConfig.quick_run(options.seed)
        if options.models is not None:
            config = replace(config, models=options.models, shipped=False)
        return config
    if exam is None:
        return TeachConfig(
            models=options.models, scenario_seed=600 + 10 * options.seed, workers=options.workers
        )
    return TeachConfig(
        models=options.models,
        workers=options.workers,
        scenario_seed=exam.seed_list("user")[0],
        training_seed=exam.seed_list("training")[0],
        free_shapes=exam.seed_list("free_shapes"),
        shapes=exam.shapes,
        learning_sets=exam.learning_sets,
        step_times=tuple(float(dt) for dt in exam.name_list("step_times")),
        showing_cycles=int(exam.parameter("showing_cycles")),
        third_cycles=int(exam.parameter("third_cycles")),
        other_cycles=int(exam.parameter("other_cycles")),
        unstructured_steps=int(exam.parameter("unstructured_steps")),
    )


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
    runs: list[TeachRun] = []
    paced: list[PacedRun] = []
    total = len(config.step_times) * job_count(config)
    done = 0
    outcome = StudyOutcome(0.0)

    def write() -> StudyOutcome:
        targets = judge(runs, paced, definitions)
        runtime = time.perf_counter() - began
        measured = results(config, runs, paced, targets, runtime, (done, total))
        if exam is not None:
            measured["exam"] = exam.to_json()
        write_outputs(
            out, report(config, runs, paced, targets, runtime, (done, total), exam), measured
        )
        return StudyOutcome(runtime, targets)

    for j, dt in enumerate(config.step_times):
        # the regression's effort per second kept at each step, as `rnnpb interact` keeps it
        at = replace(config, dt=dt, online=config.online.at_step(dt))
        folder = out / f"dt{dt:g}"
        (folder / "runs").mkdir(parents=True, exist_ok=True)
        given = at.shipped or at.models is not None
        starts = starting_models(at, folder / "models") if given else {}
        with study_pool(at.workers, init_here=True) as pool:
            starts = starts or starting_models(at, folder / "models", pool)
            for result in study_jobs(pool, at, starts, folder / "runs"):
                done += 1
                if not isinstance(result, TeachRun):
                    continue
                runs.append(result)
                plot_taught_run(
                    result.timeline,
                    out / "figures",
                    result.learning_set,
                    f"{result.shape}_dt{dt:g}",
                    dt,
                )
                log(
                    f"  [{done}/{total}] dt {dt:g} set {result.learning_set} {result.shape}: "
                    f"learned {result.new_pattern or 'nothing'}, third showing "
                    f"{100 * result.recognised_next:.0f} % recognised"
                )
                outcome = write()
        mine = {(r.learning_set, r.shape): r for r in runs if r.dt == dt}
        if at.paced is not None and at.paced in mine and mine[at.paced].new_pattern:
            # Alone, after the others: the loop and the consolidation each have a core.
            seed = at.scenario_seed + 90 + j
            paced.append(paced_job(*at.paced, starts[at.paced[0]], at, folder / "runs", seed))
            log(f"  paced run at dt {dt:g}: {paced[-1].missed_deadlines} missed deadline(s)")
        done += int(at.paced is not None)
        outcome = write()
    return outcome


# --- the judge -------------------------------------------------------------------------------


def judge(
    runs: list[TeachRun], paced: list[PacedRun], exam: Exam | None = None
) -> dict[str, Target]:
    """Every target measured (:mod:`~rnnpb.experiments.scenarios.teaching_targets`), by
    ``exam``'s definitions (default: the study's exam file)."""
    exam = exam or load_exam(NAME)
    measures = target_measures(runs, paced)
    measured = {name: measures[name](exam.target(name)) for name in exam.targets}
    return {
        name: Target(exam.target(name).met(value), detail, value)
        for name, (value, detail) in ((k, m) for k, m in measured.items() if m is not None)
    }


def judge_results(results: dict[str, Any], exam: Exam) -> dict[str, Target]:
    """The targets judged by ``exam``'s definitions from a finished ``results.json``."""
    runs = [TeachRun.from_json(r) for r in results["runs"]]
    paced = [PacedRun.from_json(p) for p in results["paced"]]
    return judge(runs, paced, exam)


# --- the report ------------------------------------------------------------------------------


def report(config, runs, paced, targets, runtime, progress, on_exam: Exam | None) -> list[str]:
    """``report.md``, section by section (``on_exam``: the exam the run is)."""
    performed = " → ".join(f"{m} ×{n}" for m, n in (runs[0].segments if runs else []))
    partial = progress[0] != progress[1]
    rows = [
        (
            f"{r.dt:g}",
            r.learning_set,
            r.shape,
            fmt(r.detection_delay),
            len(r.episodes),
            r.new_pattern or "–",
            fmt(r.swaps[0]) if r.swaps else "–",
            r.timeline["third_showing"],
            fmt(100 * third_showing_share(r, 12), 0),
            r.episodes_unstructured,
        )
        for r in runs
    ]
    header = (
        "dt | set | movement | novel after (steps) | episodes kept | learned as | swapped at "
        "| third showing at | third showing recognised % | episodes with random movement"
    ).split(" | ")
    lines = [
        "# Study: teaching by showing — learned from two showings, recognised the third",
        "",
        f"Per step time ({', '.join(f'{dt:g} s' for dt in config.step_times)}), learning set and "
        f"new movement, a scripted user performs, e.g.: {performed} (steps). The loop runs as "
        "fast as possible with the teacher (it waits between two steps for each consolidation, "
        "so a run repeats); the paced runs measure the deadlines.",
        "",
        f"{'Quick form (shipped fast-preset model)' if config.quick else 'Full form'}; models "
        f"{'shipped' if config.shipped else config.models or 'learned here'}; user draws from "
        f"{config.scenario_seed}; free shapes {', '.join(map(str, config.free_shapes)) or 'none'}; "
        f"runtime {runtime:.0f} s"
        + (f"; **partial: {progress[0]} of {progress[1]} jobs done**." if partial else "."),
        "",
        *([on_exam.describe(), ""] if on_exam is not None else []),
        "## Targets",
        "",
        *table(
            ("target", "met", "measured"),
            [(k, "yes" if t.met else "**no**", t.detail) for k, t in targets.items()],
        ),
        "",
        "## Per step time, learning set and movement",
        "",
        *table(header, rows),
    ]
    for p in paced:
        c = p.consolidation
        lines += [
            "",
            f"## Deadlines during a background consolidation, paced at dt {p.dt:g} s",
            "",
            *table(
                ("measure", "value"),
                [
                    ("paced steps", p.steps),
                    ("missed deadlines", p.missed_deadlines),
                    ("steps past their slot", p.overrun_steps),
                    (f"steps started > {LATE_S * 1e3:.0f} ms late", p.late_steps),
                    ("step work p99 / max (ms)", f"{p.p99_step_ms:.1f} / {p.max_step_ms:.1f}"),
                    (
                        "consolidation CPU / wall (s)",
                        f"{c.cpu_s:.1f} / {c.wall_s:.1f}" if c else "cut short",
                    ),
                    ("lock-on after the swap (steps)", fmt(p.lock_after_swap)),
                ],
            ),
        ]
    from rnnpb.analysis.figures.teach import timeline_file

    lines += ["", "## Timelines", ""]
    lines += [embed(where(r), timeline_file(r.learning_set, f"{r.shape}_dt{r.dt:g}")) for r in runs]
    return lines


def results(config, runs, paced, targets, runtime, progress) -> dict[str, Any]:
    """``results.json``: every measure, with the config and the versions (a run's motor error
    beside its timeline)."""
    return {
        "study": NAME,
        "config": asdict(config),
        "versions": versions(),
        "runtime_s": runtime,
        "jobs_done": progress[0],
        "jobs": progress[1],
        "targets": {k: t.to_json() for k, t in targets.items()},
        "runs": [r.to_json() for r in runs],
        "paced": [asdict(p) for p in paced],
    }
