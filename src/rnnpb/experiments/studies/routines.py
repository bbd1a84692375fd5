"""``rnnpb study routines``: does a higher level that learned routines make the robot switch
with the person rather than after them? (Paper section 4: multiple levels of RNNPB.)

Two routines of learning set 1's patterns (:mod:`rnnpb.experiments.scenarios.routines`) are
learned over the shipped lower model from some draws of the user; other draws then perform
them, deviate from them, perform an order neither routine has, and perform them with more
timing variability. Every stream runs through the two levels twice, with the higher level's
prior going down and without it (the higher level only watching), so the switch lag is
compared on the same streams. The targets' definitions are the study's exam
(``exams/routines.toml``).
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path
from typing import Any

from rnnpb.experiments.exams import Exam, load_exam
from rnnpb.experiments.reporting import embed, fmt, table, versions, write_outputs
from rnnpb.experiments.studies import StudyOptions, StudyOutcome
from rnnpb.experiments.summary import Target

NAME = "routines"
SUMMARY = "a higher RNNPB learns routines: switch lag with and without it, recognition"


def run(out: Path, options: StudyOptions) -> StudyOutcome:
    from rnnpb import _xla
    from rnnpb.analysis.figures import plot_two_levels
    from rnnpb.experiments.scenarios.routines import ROUTINES, learn, measure, runs_for_seed
    from rnnpb.model import TrainedModel
    from rnnpb.models import SHIPPED_MODEL

    _xla.configure()
    started = time.perf_counter()
    out = Path(out)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    exam = options.exam or load_exam(NAME)
    if options.exam is not None:
        seeds = list(exam.seed_list("user"))
        training = list(exam.seed_list("training"))
    elif options.quick:
        seeds, training = [options.seed + 101], [options.seed + 201]
    else:
        seeds = [options.seed + 101 + i for i in range(10)]
        training = [options.seed + 201 + i for i in range(3)]
    jitters = () if options.quick else (0.2, 0.3)
    lower = TrainedModel.load(SHIPPED_MODEL)
    # The quick form: each routine learned from one performance, routine A performed.
    routines = learn(lower, training, repeats=1 if options.quick else 2)
    routines.save(out / "routines.npz")
    names = ("A",) if options.quick else tuple(ROUTINES)
    runs = [r for seed in seeds for r in runs_for_seed(lower, routines, seed, jitters, names)]
    within, deviation_steps, judged_from = _definitions(exam)
    measures = measure(runs, within, deviation_steps, judged_from)
    targets = judge(measures, exam)
    shown = next(r for r in runs if r.kind == "learned" and r.prior)
    plot_two_levels(
        shown.lower_pb,
        shown.higher_pb,
        shown.switches,
        shown.said,
        out / "figures" / "two_levels.png",
        f"routine {shown.routine}, user draw {shown.seed}",
    )
    report = [
        *_introduction(options, seeds, training, ROUTINES),
        *([exam.describe(), ""] if options.exam is not None else []),
        *_targets_section(targets),
        *_lag_section(measures, within, jitters),
        "",
        "## The two levels over a routine",
        "",
        "The lower PB (above) and the higher PB (below) with the routine the higher level "
        "says; the user's switches dashed.",
        "",
        embed("the two levels' PBs", "two_levels.png"),
        "",
    ]
    results = {
        "study": NAME,
        "quick": options.quick,
        "seeds": seeds,
        "config": {
            "training": training,
            "performed": list(names),
            "routines": {k: [list(p) for p in v] for k, v in ROUTINES.items()},
            "lower_model": str(SHIPPED_MODEL.name),
            "lower_fingerprint": lower.fingerprint,
            "timing_jitters": list(jitters),
            "segments": vars(routines.segments),
            "recognition_error": routines.recognition_error,
        },
        "overall": measures,
        "targets": {k: t.to_json() for k, t in targets.items()},
        "versions": versions(),
    }
    if options.exam is not None:
        results["exam"] = exam.to_json()
    write_outputs(out, report, results)
    return StudyOutcome(runtime_s=time.perf_counter() - started, targets=targets)


def _definitions(exam: Exam) -> tuple[int, int, int]:
    within = int(exam.target("switches_within_with").parameter("steps"))
    deviation = int(exam.target("deviation_followed_with").parameter("steps"))
    return within, deviation, int(exam.parameter("judged_from"))


def judge(measures: dict[str, Any], exam: Exam | None = None) -> dict[str, Target]:
    """The targets by ``exam``'s definitions (default: the study's exam)."""
    exam = exam or load_exam(NAME)
    measured = replace(exam, targets={k: t for k, t in exam.targets.items() if k in measures})

    def detail(target, value) -> str:
        if target.limit >= 1 and "lag" in target.counts or "median" in target.counts:
            return f"{value:g} steps ({target.compare} {target.limit:g})"
        return f"{100 * value:.1f} % ({target.compare} {100 * target.limit:.0f} %)"

    return measured.verdicts(measures, detail)


def judge_results(results: dict[str, Any], exam: Exam) -> dict[str, Target]:
    """The study's targets judged by ``exam``'s definitions from its results."""
    return judge(results["overall"], exam)


def _introduction(options, seeds, training, routines) -> list[str]:
    parts = "; ".join(
        f"{name}: " + ", ".join(f"{p} for {c} cycles" for p, c in r) for name, r in routines.items()
    )
    return [
        "# Study: routines — switching with the person, not after them",
        "",
        f"{'Quick form' if options.quick else 'Full form'}; routines ({parts}) learned over "
        f"the shipped model from user draws {training}, performed by draws {seeds}"
        + (
            f" (the exam's, version {options.exam.version}, never used to choose a setting)."
            if options.exam is not None
            else " (development draws; the targets are judged on the exam, `--exam`)."
        )
        + " Each stream runs with the higher level's prior and without it (the same "
        "stream, the higher level only watching).",
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


def _pct(value: Any) -> str:
    return "-" if value is None else fmt(100 * value)


def _lag_section(m: dict[str, Any], within: int, jitters) -> list[str]:
    rows = [
        [
            "learned routines",
            fmt(m["median_lag_with"]),
            fmt(m["median_lag_without"]),
            _pct(m["switches_within_with"]),
            _pct(m["switches_within_without"]),
        ],
        *[
            [
                f"timing variability {j:g}",
                fmt(m[f"timing {j:g} median_lag_with"]),
                fmt(m[f"timing {j:g} median_lag_without"]),
                _pct(m[f"timing {j:g} within_with"]),
                _pct(m[f"timing {j:g} within_without"]),
            ]
            for j in jitters
        ],
    ]
    return [
        "",
        "## Switch lag with and without the higher level",
        "",
        f"Steps from the user's switch until the lower PB's nearest pattern is the new one "
        f"for 3 steps in a row; share of switches followed within {within} steps. The "
        "learned routines are performed with the demonstrator's usual timing (each part "
        "about 10 % longer or shorter); the timing rows with more.",
        "",
        *table(
            ["streams", "median lag with", "without", f"within {within} with %", "without %"],
            rows,
        ),
        "",
        *table(
            ["measure", "with the prior", "without"],
            [
                [
                    "deviations followed within 15 steps %",
                    _pct(m["deviation_followed_with"]),
                    _pct(m["deviation_followed_without"]),
                ],
                [
                    "routine recognised in its first part %",
                    _pct(m["recognised_in_first_segment"]),
                    "-",
                ],
                [
                    "unlearned order taken for a routine, % of steps",
                    _pct(m["unlearned_taken_for_learned"]),
                    "-",
                ],
            ],
        ),
    ]
