"""Mutual interaction (the paper's section 4.2): two robots imitating each other, and a scripted
subject exploring a robot's repertoire (docs/dyad.md).

Three parts, on the models of learning sets 1-4 (default ``OnlineConfig``):

1. robot–robot from random starts, both robots with the same learned set and with different
   ones: the steps until the first coherent step;
2. a phase diagram over the two robots' adaptation rates, without and with persistence (the
   initiative a robot takes after a stable while), and a line over persistence: share of time
   coherent, pattern shifts per 200 steps, leader index;
3. the subject protocol: a robot (a plain mirror system) and a scripted subject with the
   demonstrator's four movements; the robot's patterns found per simulated minute.

The scenarios and measures are :mod:`rnnpb.experiments.scenarios.dyad`; the targets' definitions
are the study's exam (``exams/dyad.toml``). Models: ``--models DIR`` (``set1.npz`` …), else
learned here (the paper's algorithm; the quick form the fast preset).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb.analysis import dyad as measures
from rnnpb.analysis import figures
from rnnpb.experiments.exams import Exam, load_exam
from rnnpb.experiments.reporting import embed, fmt, table, versions, write_outputs
from rnnpb.experiments.scenarios import dyad as scenario
from rnnpb.experiments.scenarios.dyad import DT, PATIENCE, DyadSeeds, DyadStudySize
from rnnpb.experiments.studies import StudyOptions, StudyOutcome
from rnnpb.experiments.summary import Target

NAME = "dyad"
SUMMARY = "mutual interaction: two robots, or a robot and a scripted subject (section 4.2)"

REGIMES = ("coherent share", "shifts per 200 steps", "leader index")


def run(out: Path, options: StudyOptions) -> StudyOutcome:
    start = time.perf_counter()
    out = Path(out)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    (out / "sessions").mkdir(parents=True, exist_ok=True)
    exam = options.exam or load_exam(NAME)
    size = DyadStudySize.for_options(options)
    seeds = DyadSeeds.from_first(size, options.seed)
    if options.exam is not None:
        seeds = DyadSeeds.from_exam(exam)
        size = seeds.sized(size)
    paths = scenario.model_paths(
        options.models, size.needed_sets(), out, options.quick, seeds.training
    )
    results: dict[str, Any] = {
        "config": scenario.study_config(size, paths, options),
        "seeds": {
            "starts": list(seeds.starts),
            "grid": list(seeds.grid),
            "subject": list(seeds.subject),
        },
        "versions": versions(),
    }
    if options.exam is not None:
        results["exam"] = exam.to_json()
    done = scenario.run_jobs(paths, size, seeds, out, options.workers)
    results["random_starts"] = scenario.part_rows(done, "starts")
    cells = scenario.part_rows(done, "grid")
    results["phase_diagram"] = cells
    regimes = exam.target("phase_diagram_both_regimes")
    hold, shift = regimes.parameter("hold_share"), regimes.parameter("shift_rate")
    summary_cells = [
        scenario.phase_cell(cells, p, ra, rb, hold, shift)
        for p in size.grid_persistence
        for ra in size.rates
        for rb in size.rates
    ]
    line = sorted({*size.line_persistence, *(q for q in size.grid_persistence if q)})
    line_cells = [scenario.phase_cell(cells, p, 1.0, 1.0, hold, shift) for p in line] + [
        scenario.phase_cell(cells, None, 1.0, 1.0, hold, shift)
    ]
    results["phase_cells"] = summary_cells
    results["persistence_line"] = line_cells
    results["subject"] = scenario.part_rows(done, "subject")
    _figures(out, done, size, seeds, summary_cells)
    targets = judge_results(results, exam)
    report = [
        *_introduction(options),
        *([exam.describe(), ""] if options.exam is not None else []),
        *_starts_section(results["random_starts"], size, seeds, exam),
        *_phase_section(summary_cells, line_cells, size, seeds, hold, shift),
        *_subject_section(results["subject"], size, seeds, exam),
    ]
    runtime = time.perf_counter() - start
    results["targets"] = {k: t.to_json() for k, t in targets.items()}
    results["runtime_s"] = runtime
    results["job_cpu_s"] = float(sum(r["summary"]["cpu_s"] for _, r in done))
    report += _targets_section(targets, runtime, results["versions"])
    write_outputs(out, report, results)
    return StudyOutcome(runtime_s=runtime, targets=targets)


# --- the judge ---------------------------------------------------------------------------------


def judge_results(results: dict[str, Any], exam: Exam) -> dict[str, Target]:
    """The study's targets judged by ``exam``'s definitions from its results (measured by
    :func:`rnnpb.experiments.scenarios.dyad.measured`)."""
    values = scenario.measured(results, exam)
    met = exam.judge({name: m["value"] for name, m in values.items()})
    starts, regimes = values["robots_lock_from_random_starts"], values["phase_diagram_both_regimes"]
    subject = values["subject_finds_all"]
    lock = exam.target("robots_lock_from_random_starts")
    target = exam.target("phase_diagram_both_regimes")
    found = exam.target("subject_finds_all")
    return {
        "robots_lock_from_random_starts": Target(
            met["robots_lock_from_random_starts"],
            f"{starts['locked']}/{starts['runs']} same-set runs coherent within "
            f"{lock.parameter('steps')} steps (target ≥ {lock.limit:.0%}; by the patterns as "
            f"taught only {starts['by_templates']}/{starts['runs']})",
            starts["value"],
        ),
        "phase_diagram_both_regimes": Target(
            met["phase_diagram_both_regimes"],
            f"{regimes['holding']} settings with joint attention holding (coherent ≥ "
            f"{target.parameter('hold_share'):.0%}), {regimes['shifting']} shifting ≥ "
            f"{target.parameter('shift_rate'):g}/200 steps with the lead on both sides",
            regimes["value"],
        ),
        "subject_finds_all": Target(
            met["subject_finds_all"],
            f"{subject['in_time']}/{subject['sessions']} sessions found all three patterns "
            f"within {found.parameter('minutes'):g} simulated minutes (target ≥ "
            f"{found.limit:.0%})",
            subject["value"],
        ),
    }


# --- figures and report ------------------------------------------------------------------------


def _figures(out, done, size, seeds, summary_cells) -> None:
    example = scenario.part_figure(done, "starts")
    figures.plot_dyad(
        example["arrays"],
        example["coherent"],
        out / "figures" / "robots.png",
        title=f"two robots from random starts ({size.same_sets[0]} both, seed {seeds.starts[0]})",
        shifts=example["shifts"],
    )
    cells = {(c["persistence"], c["adaptation_a"], c["adaptation_b"]): c for c in summary_cells}
    panels: dict[str, dict[str, np.ndarray]] = {}
    for persistence in size.grid_persistence:
        label = "no persistence" if persistence is None else f"persistence {persistence}"
        panels[label] = {
            measure: np.array(
                [[cells[(persistence, ra, rb)][key] for rb in size.rates] for ra in size.rates],
                dtype=float,
            )
            for measure, key in zip(
                REGIMES, ("coherent_share", "shifts_per_200", "leader_index"), strict=True
            )
        }
    figures.plot_phase_diagram(size.rates, panels, out / "figures" / "phase_diagram.png")
    curves = {f"{k['set']} seed {k['seed']}": r["found"] for k, r in done if k["part"] == "subject"}
    figures.plot_patterns_found(curves, DT, 3, out / "figures" / "patterns_found.png")
    example = scenario.part_figure(done, "subject")
    figures.plot_dyad(
        example["arrays"],
        example["coherent"],
        out / "figures" / "subject.png",
        title=f"robot ({size.subject_sets[0]}) and scripted subject, seed {seeds.subject[0]}",
        names=("robot", "subject"),
        shifts=[(s, {"a": "robot", "b": "subject"}.get(w, "")) for s, w in example["shifts"]],
    )


def _introduction(options: StudyOptions) -> list[str]:
    return [
        "# Mutual interaction (section 4.2)",
        "",
        "Two agents coupled through their senses (docs/dyad.md). Models: the paper-learned "
        "learning sets 1-4; on-line regression: the default `OnlineConfig`. **Coherent** "
        "(joint attention): both agents' movements on the same learned pattern — judged from "
        "the movement over the last cycle against the pattern as taught and, for a robot, as "
        "its own network plays it in closed loop — and phase-locked (cross-correlation "
        f"≥ {measures.LOCK_CORRELATION:g} at a lag of at most {measures.MAX_LAG} steps, the "
        f"lag steady over {measures.LOCK_STEADY} steps). Runs in {options.workers} worker "
        "process(es).",
        "",
    ]


def _starts_section(starts, size: DyadStudySize, seeds: DyadSeeds, exam: Exam) -> list[str]:
    steps = exam.target("robots_lock_from_random_starts").parameter("steps")
    same = [s for s in starts if s["kind"] == "same"]
    looks = scenario.within(same, steps, "first_coherent_by_templates")
    groups = {}
    for s in starts:
        groups.setdefault((s["kind"], s["a"], s["b"]), []).append(s)
    return [
        "## Robot–robot from random starts",
        "",
        f"Both robots adapt (adaptation 1) and initiate a pattern of their own after "
        f"{PATIENCE} steps (and up to twice that) of not predicting the other; "
        f"{size.start_steps} steps, seeds {seeds.starts[0]}–{seeds.starts[-1]} per pair. "
        "Judged by the pattern as taught only (the demonstrator's templates), "
        f"{looks}/{len(same)} same-set runs are coherent within {steps} steps.",
        "",
        *table(
            [
                "sets",
                "kind",
                "runs",
                f"coherent within {steps} steps",
                "first coherent step (median)",
                "coherent share (median)",
                f"as taught only: within {steps}",
            ],  # fmt: skip
            [
                [
                    f"{a} + {b}",
                    kind,
                    len(group),
                    scenario.within(group, steps),
                    fmt(scenario.median_first(group), 0),
                    fmt(np.median([r["coherent_share"] for r in group]), 2),
                    scenario.within(group, steps, "first_coherent_by_templates"),
                ]
                for (kind, a, b), group in groups.items()
            ],
        ),
        "",
        embed("two robots", "robots.png"),
        "",
    ]


def _setting(c: dict[str, Any]) -> str:
    p = "none" if c["persistence"] is None else str(c["persistence"])
    return f"persistence {p}, A {c['adaptation_a']:g}, B {c['adaptation_b']:g}"


def _cell_rows(group: list[dict[str, Any]]) -> list[list[Any]]:
    return [
        [
            "none" if c["persistence"] is None else c["persistence"],
            f"{c['adaptation_a']:g}",
            f"{c['adaptation_b']:g}",
            fmt(c["coherent_share"], 2),
            fmt(c["shifts_per_200"], 2),
            f"{c['led_by_a']} / {c['led_by_b']}",
            fmt(c["leader_index"], 2),
            "holds" if c["holds"] else ("shifts" if c["shifts"] else "—"),
        ]
        for c in group
    ]


def _phase_section(summary_cells, line_cells, size, seeds, hold, shift) -> list[str]:
    settings = list(
        {
            (c["persistence"], c["adaptation_a"], c["adaptation_b"]): c
            for c in summary_cells + line_cells
        }.values()
    )
    holding = [c for c in settings if c["holds"]]
    shifting = [c for c in settings if c["shifts"]]
    header = ["persistence", "A", "B", "coherent share", "shifts / 200 steps",
              "led by A / B", "leader index", "regime"]  # fmt: skip
    return [
        "## Phase diagram over the two adaptation rates",
        "",
        f"Learning set 1 for both, {size.grid_steps} steps from random starts, seeds "
        f"{list(seeds.grid)}; rows: A's adaptation, columns: B's; cells are means over the "
        f"seeds. Joint attention holds where coherent ≥ {hold:.0%} of the time; spontaneous "
        f"shifts: ≥ {shift:g} pattern shift per 200 steps, with each agent leading some.",
        "",
        *table(header, _cell_rows(summary_cells)),
        "",
        embed("phase diagram", "phase_diagram.png"),
        "",
        "### Persistence at adaptation 1 for both",
        "",
        *table(header, _cell_rows(line_cells)),
        "",
        f"Cells where joint attention holds: {len(holding)} "
        f"({'; '.join(_setting(c) for c in holding) or 'none'}). Cells with spontaneous shifts "
        f"led from both sides: {len(shifting)} "
        f"({'; '.join(_setting(c) for c in shifting) or 'none'}).",
        "",
    ]


def _subject_section(sessions, size: DyadStudySize, seeds: DyadSeeds, exam: Exam) -> list[str]:
    minutes = exam.target("subject_finds_all").parameter("minutes")
    subject_steps = int(round(size.subject_minutes * 60 / DT))
    looks = scenario.within(sessions, minutes, "minutes_to_all_by_templates")
    rows = []
    for name in size.subject_sets:
        group = [s for s in sessions if s["set"] == name]
        rows.append([
            name,
            len(group),
            scenario.within(group, minutes, "minutes_to_all"),
            fmt(scenario.median_first(group, "minutes_to_all"), 1),
            fmt(np.median([s["patterns_found"] for s in group]), 0),
            sum(s["pattern_shifts"] for s in group),
            f"{sum(s['led_by_a'] for s in group)} / {sum(s['led_by_b'] for s in group)}",
        ])  # fmt: skip
    return [
        "## The subject protocol",
        "",
        "A robot (a plain mirror system, adaptation 1, no initiative but when left "
        "alone) and a scripted subject who knows the demonstrator's four movements, "
        "not the robot's three; the subject follows a robot movement close to one of "
        "its own and initiates another when they cannot match (docs/dyad.md). A pattern "
        "is found once the first joint-attention episode on it has lasted "
        f"{measures.MIN_EPISODE} coherent steps. Up to {size.subject_minutes:g} simulated "
        f"minutes ({subject_steps} steps; a session ends once every pattern is found), seeds "
        f"{seeds.subject[0]}–{seeds.subject[-1]}, each its own session, the sets in turn. "
        "Judged by the patterns as taught "
        f"only, {looks}/{len(sessions)} sessions find all three in time.",
        "",
        *table(
            [
                "set",
                "sessions",
                "all found in time",
                "minutes to all (median)",
                "found (median)",
                "pattern shifts (total)",
                "led by robot / subject",
            ],  # fmt: skip
            rows,
        ),
        "",
        embed("subject", "subject.png"),
        "",
        embed("patterns found", "patterns_found.png"),
        "",
    ]


def _targets_section(targets: dict[str, Target], runtime: float, versions_: dict) -> list[str]:
    return [
        "## Targets",
        "",
        *table(
            ["target", "met", "detail"],
            [[k, "yes" if t.met else "NOT met", t.detail] for k, t in targets.items()],
        ),
        "",
        f"Runtime {runtime:.0f} s; versions: "
        + ", ".join(f"{k} {v}" for k, v in versions_.items()),
        "",
    ]
