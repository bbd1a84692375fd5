"""``rnnpb study novelty``: does the robot know what it sees? (recognition with confidence, and
a novelty detector that tells a new movement from noise; paper section 4.1.)

For each learning set (1–4, and the larger set), the mirror system meets generated streams of
the user (:mod:`rnnpb.experiments.scenarios.novelty`): each learned pattern held; a learned
pattern, then a novel structured movement; each new shape at half and at twice the usual
speed; unstructured movement; the hands held still; the hands stopping after a movement.
Every step's novelty state is compared with the truth. The targets' definitions are the
study's exam (``exams/novelty.toml``).

Models: ``--models DIR`` (the models ``rnnpb demo`` writes), else ``OUT/models/`` — those
present there, the others learned and saved there (the paper's algorithm and the fast preset;
``--quick``: the fast preset, sets 1 and full only).
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb.experiments.exams import Exam, load_exam
from rnnpb.experiments.reporting import embed, fmt, table, versions, write_outputs
from rnnpb.experiments.scenarios.novelty import (
    LEAD_STEPS,
    PERIOD,
    STATES,
    StreamRun,
    measure,
    model_job,
    study_models,
)
from rnnpb.experiments.studies import StudyOptions, StudyOutcome
from rnnpb.experiments.studies._pool import study_pool
from rnnpb.experiments.summary import Target

NAME = "novelty"
SUMMARY = "recognition with confidence and novelty detection over generated streams"


def run(out: Path, options: StudyOptions) -> StudyOutcome:
    from rnnpb import _xla
    from rnnpb.analysis.figures import plot_confusion, plot_delays, plot_roc
    from rnnpb.demonstrator import NEW_SHAPES

    _xla.configure()
    started = time.perf_counter()
    out = Path(out)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    exam = options.exam or load_exam(NAME)
    steps = 72 if options.quick else 84
    if options.exam is not None:
        seeds = list(exam.seed_list("user"))
        shapes = exam.shapes
        models = study_models(out, options.models, False, exam.seed_list("training")[0],
                              exam.learning_sets)  # fmt: skip
    else:
        seeds = [options.seed + 1000 + i for i in range(1 if options.quick else 2)]
        shapes = tuple(NEW_SHAPES[:2] if options.quick else NEW_SHAPES)
        models = study_models(out, options.models, options.quick)
    runs: list[StreamRun] = []
    alone: list[StreamRun] = []
    settings: dict[str, dict[str, Any]] = {}
    with study_pool(min(options.workers, len(models))) as pool:
        jobs = [
            pool.submit(model_job, name, set_name, str(path), seeds, steps, shapes)
            for name, (set_name, path) in models.items()
        ]
        for job in jobs:
            name, chosen, model_runs, model_alone = job.result()
            settings[name] = chosen
            runs += model_runs
            alone += model_alone
    settle, within, grace = _definitions(exam)

    def measured(group: list[StreamRun]) -> dict[str, Any]:
        return measure(group, settle, within, grace)

    per_set = {name: measured([r for r in runs if r.model == name]) for name in models}
    presets = {
        preset: [r for r in runs if settings[r.model]["online_preset"] == preset]
        for preset in dict.fromkeys(s["online_preset"] for s in settings.values())
    }
    per_preset = {preset: measured(rs) for preset, rs in presets.items()}
    overall = measured(runs)
    without_taught = {name: measured([r for r in alone if r.model == name]) for name in models}
    without_taught["all"] = measured(alone)
    targets = judge(overall, exam)
    for preset, m in per_preset.items():
        if len(presets) > 1:
            targets |= {f"{preset}: {k}": t for k, t in judge(m, exam).items()}
    figures = out / "figures"
    plot_confusion({n: m["confusion"] for n, m in per_set.items()}, figures / "confusion.png")
    plot_delays(
        {n: [d for d in m["novel_delay_steps"]] for n, m in per_set.items()},
        figures / "delays.png",
        period=PERIOD,
    )
    plot_roc({n: m["roc"] for n, m in per_set.items()}, figures / "roc.png")
    report = [
        *_introduction(options, seeds, settings, settle),
        *([exam.describe(), ""] if options.exam is not None else []),
        *_targets_section(targets),
        *_per_set_section(per_set, exam),
        *_taught_section(per_set, overall, without_taught, settings, exam),
        *_confidence_section(per_preset, overall),
        *_confusion_section(overall),
    ]
    results = {
        "study": NAME,
        "quick": options.quick,
        "seeds": seeds,
        "config": {
            "models": settings,
            "steps": steps,
            "settle_steps": settle,
            "lead_steps": LEAD_STEPS,
        },
        "models": {n: str(path) for n, (_, path) in models.items()},
        "per_set": per_set,
        "per_preset": per_preset,
        "overall": overall,
        "without_taught_hands": {
            name: {key: m[key] for key in exam.targets} for name, m in without_taught.items()
        },
        "targets": {k: t.to_json() for k, t in targets.items()},
        "versions": versions(),
    }
    if options.exam is not None:
        results["exam"] = exam.to_json()
    write_outputs(out, report, results)
    return StudyOutcome(runtime_s=time.perf_counter() - started, targets=targets)


# --- the judge ---------------------------------------------------------------------------------


def _definitions(exam: Exam) -> tuple[int, int, int]:
    """The steps not judged after a movement starts, the steps within which a novel
    movement is detected in time, and the steps not judged after the hands stop."""
    settle = int(exam.parameter("settle_steps"))
    within = int(exam.target("novel_within_3_cycles").parameter("steps"))
    return settle, within, int(exam.target("stopped_called_still").parameter("steps"))


def judge(measures: dict[str, Any], exam: Exam | None = None) -> dict[str, Target]:
    """The targets by ``exam``'s definitions (default: the study's exam), from the measures
    (a target whose measure is absent, as in results written before the study measured it, is
    left out, not failed)."""
    exam = exam or load_exam(NAME)
    measured = replace(exam, targets={k: t for k, t in exam.targets.items() if k in measures})
    return measured.verdicts(
        measures, lambda t, v: f"{100 * v:.1f} % ({t.compare} {100 * t.limit:.0f} %)"
    )


def judge_results(results: dict[str, Any], exam: Exam) -> dict[str, Target]:
    """The study's targets judged by ``exam``'s definitions from its results (over every
    model; the per-preset targets as the run adds them)."""
    targets = judge(results["overall"], exam)
    if len(results["per_preset"]) > 1:
        for preset, m in results["per_preset"].items():
            targets |= {f"{preset}: {k}": t for k, t in judge(m, exam).items()}
    return targets


# --- the report --------------------------------------------------------------------------------


def _introduction(options, seeds, settings, settle: int) -> list[str]:
    return [
        "# Study: novelty — does the robot know what it sees?",
        "",
        f"{'Quick form' if options.quick else 'Full form'}; draws of the user (scenario "
        f"seeds) {seeds}"
        + (
            f", the exam's (version {options.exam.version}), never used to choose a setting. "
            if options.exam is not None
            else ": development draws; the targets are judged on the exam (`--exam`). "
        )
        + f"Steps judged: from {settle} steps after a movement starts. Each model runs "
        "with the on-line regression and recognition settings chosen for its learning "
        "(`OnlineConfig.for_model`): "
        + ", ".join(f"{n}: {s['online_preset']}" for n, s in settings.items())
        + ". Targets over all models, then per regression preset.",
        "",
    ]


def _targets_section(targets: dict[str, Target]) -> list[str]:
    return [
        "## Targets",
        "",
        *table(
            ["target", "met", "measured"],
            [[k, "yes" if t.met else "NO", t.detail] for k, t in targets.items()],
        ),
    ]


def _per_set_section(per_set: dict[str, dict[str, Any]], exam: Exam) -> list[str]:
    rows = []
    for name, m in per_set.items():
        delays = [d for d in m["novel_delay_steps"] if d is not None]
        rows.append([
            name,
            fmt(100 * m["learned_recognised"]),
            fmt(100 * m["learned_nearest_pb"]),
            fmt(100 * m["learned_called_novel"]),
            fmt(100 * m["novel_within_3_cycles"]),
            fmt(float(np.median(delays))) if delays else "never",
            fmt(100 * m["novel_after_detection"]),
            fmt(100 * m["unstructured_called_novel"]),
            fmt(100 * m["still_called_still"]),
            f"{m['roc_auc']:.3f}",
        ])  # fmt: skip
    header = ["set", "learned recognised %", "nearest PB right %", "learned novel %",
              "novel within 3 cycles %", "median delay (steps)", "novel after detection %",
              "unstructured novel %", "still %", "ROC AUC"]  # fmt: skip
    speeds = [[name, *[fmt(100 * m[key]) for key in SPEED_KEYS]] for name, m in per_set.items()]
    grace = _definitions(exam)[2]
    return [
        "", "## Per learning set", "", *table(header, rows), "",
        "New shapes at half and at twice the usual speed (share of settled steps called "
        "novel; at half speed the stream and the steps not judged are twice as long), and the "
        f"hands stopping (share of each stop's steps after its first {grace} "
        "called still):",
        "", *table(["set", "0.5× novel %", "2× novel %", "stopped: still %"], speeds),
    ]  # fmt: skip


SPEED_KEYS = ("novel_slow_called_novel", "novel_fast_called_novel", "stopped_called_still")


def _taught_section(per_set, overall, without_taught, settings, exam: Exam) -> list[str]:
    kept = all(s["taught_hands"] for s in settings.values())
    lacking = ", ".join(n for n, s in settings.items() if not s["taught_hands"])
    rows = [
        [f"{name}{suffix}", *[fmt(100 * m[key]) for key in exam.targets]]
        for name in [*per_set, "all"]
        for suffix, m in (
            ("", overall if name == "all" else per_set[name]),
            (" without", without_taught[name]),
        )
    ]
    return [
        "",
        "## What the hands as taught add",
        "",
        "The same evidence replayed through the detector without the third term (the hands "
        'as taught; docs/model.md, "Recognition and novelty"): the network\'s evidence, the '
        "PB and the structure test alone, as before models kept their taught hands. A model "
        "without them (a file of format 1 or 2) runs this way; "
        + ("every model here kept them." if kept else f"here: {lacking}."),
        "",
        *table(["models", *exam.targets], rows),
    ]


def _confidence_section(per_preset, overall) -> list[str]:
    rows = [
        [name, fmt(m["confidence_right"]), fmt(m["confidence_wrong"]), str(m["wrong_steps"])]
        for name, m in [*per_preset.items(), ("all", overall)]
    ]
    return [
        "",
        "## Confidence",
        "",
        "Mean confidence of the recognised pattern on learned patterns' judged steps, where "
        "it was right and where it was wrong (a meaningful confidence is lower when wrong):",
        "",
        *table(["models", "when right", "when wrong", "wrong steps"], rows),
    ]


def _confusion_section(overall) -> list[str]:
    return [
        "",
        "## Confusion of the four states (all sets)",
        "",
        *table(
            ["truth \\ said", *[s or "undecided" for s in STATES]],
            [[kind, *row.values()] for kind, row in overall["confusion"].items()],
        ),
        "",
        embed("confusion matrices", "confusion.png"),
        embed("detection delays", "delays.png"),
        embed("ROC", "roc.png"),
        "",
    ]
