"""Mutual interaction (the paper's section 4.2): two robots imitating each other, and a scripted
subject exploring a robot's repertoire (docs/dyad.md).

Three parts, each on the paper-learned models of learning sets 1-4 (default ``OnlineConfig``):

1. robot–robot from random starts, both robots with the same learned set and with different
   ones: the steps until the first coherent step (target: ≤ 60 steps in ≥ 90 % of runs with
   the same set);
2. a phase diagram over the two robots' adaptation rates, without and with persistence (the
   initiative a robot takes after a stable while), and a line over persistence: share of time
   coherent, pattern shifts per 200 steps, leader index;
3. the subject protocol: a robot (a plain mirror system) and a scripted subject with the
   demonstrator's four movements; the robot's patterns found per simulated minute (target:
   all three within 10 minutes in ≥ 80 % of runs).

Coherence is judged from the agents' movements (:mod:`rnnpb.analysis.dyad`): both on the same
learned pattern — as taught, or as the robot's own network plays it in closed loop — and
phase-locked. The runs are jobs in ``options.workers`` worker processes, one core each.
Settings (patience, persistence, lead) were chosen on seeds 100-105; the study's seeds start
at ``--seed`` (0).
"""

from __future__ import annotations

import os
import time
from concurrent.futures import Future, as_completed
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb.analysis import dyad as measures
from rnnpb.analysis import figures
from rnnpb.errors import ConfigError
from rnnpb.experiments.reporting import embed, fmt, table, versions, write_outputs
from rnnpb.experiments.studies import StudyOptions, StudyOutcome
from rnnpb.experiments.studies._pool import study_pool
from rnnpb.experiments.summary import Target
from rnnpb.interaction.dyad import (
    AgentConfig,
    DyadRun,
    SubjectConfig,
    pattern_references,
    robot_and_subject,
    robot_pair,
)
from rnnpb.interaction.recorder import DyadRecorder
from rnnpb.model.io import TrainedModel
from rnnpb.model.online_config import OnlineConfig

NAME = "dyad"
SUMMARY = "mutual interaction: two robots, or a robot and a scripted subject (section 4.2)"

# The paper-learned models of a full `rnnpb demo --out results/full` run (set1-4.npz);
# RNNPB_DYAD_MODELS names another folder.
MODELS_DIR = Path("results/full/models")
SETS = ("set1", "set2", "set3", "set4")
DT = 0.4
LOCK_STEPS = 60  # the target: coherent within 60 steps
LOCK_SHARE = 0.9
HOLD_SHARE = 0.9  # joint attention holds: coherent >= 90 % of the time
SHIFT_RATE = 1.0  # spontaneous shifts: >= 1 per 200 steps
FOUND_MINUTES = 10.0
FOUND_SHARE = 0.8
PATIENCE = 6  # steps of not predicting the partner before a robot initiates
PERSISTENCE = 60  # steps of stable interaction before a robot initiates (the "shifting" runs)
CHUNK = 60  # steps of a subject session between checks whether all is found


@dataclass(frozen=True)
class DyadStudySize:
    """How much the study runs: seeds per random-start condition and its steps; the phase
    diagram's adaptation rates, seeds, steps and persistences (over the grid) and the
    persistences of the line at adaptation 1 for both; the subject protocol's sets, seeds and
    simulated minutes."""

    start_seeds: int
    start_steps: int
    same_sets: tuple[str, ...]
    mixed_sets: tuple[tuple[str, str], ...]
    rates: tuple[float, ...]
    grid_seeds: int
    grid_steps: int
    grid_persistence: tuple[int | None, ...]
    line_persistence: tuple[int, ...]
    subject_sets: tuple[str, ...]
    subject_seeds: int
    subject_minutes: float

    @classmethod
    def for_options(cls, options: StudyOptions) -> DyadStudySize:
        if options.quick:
            return cls(2, 80, ("set1",), (("set1", "set2"),), (0.1, 1.0), 1, 200,
                       (None, PERSISTENCE), (30,), ("set1",), 1, 2.0)  # fmt: skip
        # Sized to run in about half an hour of a shared, loaded 2-core machine (docs/dyad.md).
        return cls(
            start_seeds=5,
            start_steps=80,
            same_sets=SETS,
            mixed_sets=(("set1", "set2"), ("set3", "set4")),
            rates=(0.03, 0.1, 0.3, 1.0),
            grid_seeds=3,
            grid_steps=300,
            grid_persistence=(None, PERSISTENCE),
            line_persistence=(30,),
            subject_sets=SETS,
            subject_seeds=12,
            subject_minutes=FOUND_MINUTES,
        )


def _model_path(name: str) -> Path:
    root = Path(os.environ.get("RNNPB_DYAD_MODELS", MODELS_DIR))
    path = root / f"{name}.npz"
    if not path.is_file():
        raise ConfigError(
            f"the dyad study needs the paper-learned model {path} "
            "of a full `rnnpb demo` run (set RNNPB_DYAD_MODELS to the folder that "
            "holds set1-4.npz)"
        )
    return path


_LOADED: dict[str, tuple[TrainedModel, dict[str, np.ndarray]]] = {}


def _load(path: str) -> tuple[TrainedModel, dict[str, np.ndarray]]:
    """A model and its patterns' closed-loop references, once per process."""
    if path not in _LOADED:
        model = TrainedModel.load(path)
        _LOADED[path] = (model, pattern_references(model))
    return _LOADED[path]


def _figure_arrays(arrays: dict[str, np.ndarray], found: measures.DyadMeasures) -> dict[str, Any]:
    return {
        "arrays": {k: arrays[k] for k in ("a_shown", "b_shown", "a_pb", "b_pb")},
        "coherent": found.coherent,
        "shifts": [(s.step, s.leader) for s in found.shifts],
    }


def robots_job(
    path_a: str,
    path_b: str,
    a: AgentConfig,
    b: AgentConfig,
    seed: int,
    steps: int,
    record: str | None = None,
    keep: bool = False,
) -> dict[str, Any]:
    """One robot–robot run from a random start, measured: its summary (coherence judged by
    each robot's learned patterns as taught and as its network plays them) and
    ``first_coherent_by_templates`` (as taught only); with ``keep``, what its figure needs."""
    cpu = time.process_time()
    (model_a, refs_a), (model_b, refs_b) = _load(path_a), _load(path_b)
    pair = robot_pair(model_a, model_b, a, b, seed=seed)
    if record is not None:
        with DyadRecorder(Path(record), model_a.network.pb_size, DT) as recorder:
            run = pair.run(steps, on_step=recorder.write)
    else:
        run = pair.run(steps)
    shared = tuple(p for p in model_a.patterns if p in model_b.patterns)
    found = measures.measure_dyad(
        run["a_shown"],
        run["b_shown"],
        shared,
        run["a_pb"],
        run["b_pb"],
        references_a=refs_a,
        references_b=refs_b,
    )
    looks = measures.measure_dyad(run["a_shown"], run["b_shown"], shared, run["a_pb"], run["b_pb"])
    out: dict[str, Any] = {
        "summary": {
            **found.summary(DT),
            "first_coherent_by_templates": looks.first_coherent,
            "coherent_share_by_templates": looks.coherent_share,
            "cpu_s": time.process_time() - cpu,
        }
    }
    if keep:
        out["figure"] = _figure_arrays(run.arrays, found)
    return out


def subject_job(
    path: str, seed: int, n_steps: int, record: str | None = None, keep: bool = False
) -> dict[str, Any]:
    """One subject session, up to ``n_steps`` steps, a cycle at a time: it ends once every
    learned pattern is found (nothing after that changes what the protocol measures)."""
    cpu = time.process_time()
    model, refs = _load(path)
    dyad = robot_and_subject(model, AgentConfig(), SubjectConfig(), seed=seed)
    steps: list = []
    recorder = DyadRecorder(Path(record), model.network.pb_size, DT) if record is not None else None

    def keep_step(step: Any) -> None:
        steps.append(step)
        if recorder is not None:
            recorder.write(step)

    try:
        while len(steps) < n_steps:
            dyad.run(min(CHUNK, n_steps - len(steps)), on_step=keep_step)
            arrays = DyadRun.from_steps(steps).arrays
            found = measures.measure_dyad(
                arrays["a_shown"], arrays["b_shown"], model.patterns, arrays["a_pb"],
                references_a=refs,
            )  # fmt: skip
            if found.found[-1] >= len(model.patterns):
                break
    finally:
        if recorder is not None:
            recorder.close()
    looks = measures.measure_dyad(
        arrays["a_shown"], arrays["b_shown"], model.patterns, arrays["a_pb"]
    )
    all_found = np.flatnonzero(found.found >= len(model.patterns))
    all_looks = np.flatnonzero(looks.found >= len(model.patterns))
    minutes = int(round(n_steps * DT / 60))
    out: dict[str, Any] = {
        "summary": {
            **found.summary(DT),
            "minutes_to_all": float(all_found[0] * DT / 60) if all_found.size else None,
            "minutes_to_all_by_templates": (
                float(all_looks[0] * DT / 60) if all_looks.size else None
            ),
            "steps_run": len(found.found),
            "cpu_s": time.process_time() - cpu,
            "per_minute": [
                int(found.found[min(int(m * 60 / DT), len(found.found)) - 1])
                for m in range(1, minutes + 1)
            ],
        },
        "found": found.found,
    }
    if keep:
        out["figure"] = _figure_arrays(arrays, found)
    return out


def _median_first(rows: list[dict[str, Any]], key: str = "first_coherent") -> float:
    return float(np.median([r[key] if r[key] is not None else np.inf for r in rows]))


def _within(rows: list[dict[str, Any]], key: str = "first_coherent") -> int:
    return sum(r[key] is not None and r[key] <= LOCK_STEPS for r in rows)


def run(out: Path, options: StudyOptions) -> StudyOutcome:
    start = time.perf_counter()
    out = Path(out)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    (out / "sessions").mkdir(parents=True, exist_ok=True)
    size = DyadStudySize.for_options(options)
    paths = {name: str(_model_path(name)) for name in SETS}
    for name in SETS:
        TrainedModel.load(paths[name])  # a model that does not load fails here, once
    first = options.seed
    start_seeds = list(range(first, first + size.start_seeds))
    grid_seeds = list(range(first, first + size.grid_seeds))
    subject_seeds = list(range(first, first + size.subject_seeds))
    follower = AgentConfig(patience=PATIENCE)
    results: dict[str, Any] = {
        "config": {
            "dt": DT,
            "patience": PATIENCE,
            "persistence": PERSISTENCE,
            "size": asdict(size),
            "agent": asdict(follower),
            "subject": asdict(SubjectConfig()),
            "online": OnlineConfig().to_dict(),
            "coherence": {
                "class_window": measures.CLASS_WINDOW,
                "class_tolerance": measures.CLASS_TOLERANCE,
                "max_lag": measures.MAX_LAG,
                "lock_correlation": measures.LOCK_CORRELATION,
                "lock_steady": measures.LOCK_STEADY,
                "moving_level": measures.MOVING_LEVEL,
            },
            "models": paths,
            "quick": options.quick,
            "workers": options.workers,
        },
        "seeds": {"starts": start_seeds, "grid": grid_seeds, "subject": subject_seeds},
        "versions": versions(),
    }

    # Every run is a job; the longest are submitted first so that the workers end together.
    jobs: dict[Future, tuple[str, dict[str, Any]]] = {}
    done: list[tuple[dict[str, Any], dict[str, Any]]] = []
    subject_steps = int(round(size.subject_minutes * 60 / DT))
    # Kept to one core here too when workers are started: they inherit it.
    with study_pool(options.workers, init_here=options.workers > 1) as pool:

        def submit(part: str, key: dict[str, Any], function: Any, *args: Any) -> None:
            jobs[pool.submit(function, *args)] = (part, key)

        for k, seed in enumerate(subject_seeds):
            # Each seed its own session, the sets in turn.
            name = size.subject_sets[k % len(size.subject_sets)]
            record = (
                str(out / "sessions" / f"subject_{name}_seed{seed}.csv")
                if k < len(size.subject_sets)
                else None
            )
            submit("subject", {"set": name, "seed": seed}, subject_job, paths[name], seed,
                   subject_steps, record, k == 0)  # fmt: skip
        grid = [
            (persistence, ra, rb)
            for persistence in size.grid_persistence
            for ra in size.rates
            for rb in size.rates
        ] + [(persistence, 1.0, 1.0) for persistence in size.line_persistence]
        for persistence, ra, rb in grid:
            for seed in grid_seeds:
                a = AgentConfig(adaptation=ra, patience=PATIENCE, persistence=persistence)
                b = AgentConfig(adaptation=rb, patience=PATIENCE, persistence=persistence)
                key = {"persistence": persistence, "adaptation_a": ra, "adaptation_b": rb,
                       "seed": seed}  # fmt: skip
                submit("grid", key, robots_job, paths["set1"], paths["set1"], a, b, seed,
                       size.grid_steps)  # fmt: skip
        pairs = [("same", (n, n)) for n in size.same_sets] + [
            ("different", p) for p in size.mixed_sets
        ]
        for kind, (name_a, name_b) in pairs:
            for seed in start_seeds:
                record = (
                    str(out / "sessions" / f"robots_{name_a}_{name_b}_seed{seed}.csv")
                    if seed == first
                    else None
                )
                keep = (kind, name_a, seed) == ("same", size.same_sets[0], first)
                key = {"kind": kind, "a": name_a, "b": name_b, "seed": seed}
                submit("starts", key, robots_job, paths[name_a], paths[name_b], follower,
                       follower, seed, size.start_steps, record, keep)  # fmt: skip
        for future in as_completed(jobs):
            part, key = jobs[future]
            done.append(({"part": part, **key}, future.result()))

    def rows(part: str) -> list[dict[str, Any]]:
        keys = [k for k, _ in done if k["part"] == part]
        order = sorted(range(len(keys)), key=lambda i: str(keys[i]))
        picked = [(k, r) for k, r in done if k["part"] == part]
        return [{**picked[i][0], **picked[i][1]["summary"]} for i in order]

    def figure_of(part: str) -> dict[str, Any]:
        return next(r["figure"] for k, r in done if k["part"] == part and "figure" in r)

    report = [
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

    # 1. random starts ----------------------------------------------------------------------
    starts = rows("starts")
    results["random_starts"] = starts
    same = [s for s in starts if s["kind"] == "same"]
    locked = _within(same)
    locked_looks = _within(same, "first_coherent_by_templates")
    lock_share = locked / len(same)
    example = figure_of("starts")
    figures.plot_dyad(
        example["arrays"],
        example["coherent"],
        out / "figures" / "robots.png",
        title=f"two robots from random starts ({size.same_sets[0]} both, seed {first})",
        shifts=example["shifts"],
    )
    report += [
        "## Robot–robot from random starts",
        "",
        f"Both robots adapt (adaptation 1) and initiate a pattern of their own after "
        f"{PATIENCE} steps (and up to twice that) of not predicting the other; "
        f"{size.start_steps} steps, seeds {start_seeds[0]}–{start_seeds[-1]} per pair. "
        "Judged by the pattern as taught only (the demonstrator's templates), "
        f"{locked_looks}/{len(same)} same-set runs are coherent within {LOCK_STEPS} steps.",
        "",
        *table(
            [
                "sets",
                "kind",
                "runs",
                f"coherent within {LOCK_STEPS} steps",
                "first coherent step (median)",
                "coherent share (median)",
                f"as taught only: within {LOCK_STEPS}",
            ],
            [
                [
                    f"{a} + {b}",
                    kind,
                    len(group),
                    _within(group),
                    fmt(_median_first(group), 0),
                    fmt(np.median([r["coherent_share"] for r in group]), 2),
                    _within(group, "first_coherent_by_templates"),
                ]
                for (kind, a, b) in dict.fromkeys((s["kind"], s["a"], s["b"]) for s in starts)
                for group in [[s for s in starts if (s["kind"], s["a"], s["b"]) == (kind, a, b)]]
            ],
        ),
        "",
        embed("two robots", "robots.png"),
        "",
    ]

    # 2. the phase diagram ------------------------------------------------------------------
    cells = rows("grid")
    results["phase_diagram"] = cells
    rates = size.rates

    def cell(persistence: int | None, ra: float, rb: float) -> dict[str, Any]:
        group = [
            c
            for c in cells
            if (c["persistence"], c["adaptation_a"], c["adaptation_b"]) == (persistence, ra, rb)
        ]
        led_a = sum(c["led_by_a"] for c in group)
        led_b = sum(c["led_by_b"] for c in group)
        share = float(np.mean([c["coherent_share"] for c in group]))
        shift_rate = float(np.mean([c["pattern_shifts"] * 200 / c["steps"] for c in group]))
        return {
            "persistence": persistence,
            "adaptation_a": ra,
            "adaptation_b": rb,
            "runs": len(group),
            "coherent_share": share,
            "shifts_per_200": shift_rate,
            "led_by_a": led_a,
            "led_by_b": led_b,
            "leader_index": (led_a - led_b) / (led_a + led_b) if led_a + led_b else float("nan"),
            "holds": share >= HOLD_SHARE,
            "shifts": shift_rate >= SHIFT_RATE and led_a > 0 and led_b > 0,
        }

    summary_cells = [cell(p, ra, rb) for p in size.grid_persistence for ra in rates for rb in rates]
    line_cells = [
        cell(p, 1.0, 1.0)
        for p in sorted({*size.line_persistence, *(q for q in size.grid_persistence if q)})
    ] + [cell(None, 1.0, 1.0)]
    results["phase_cells"] = summary_cells
    results["persistence_line"] = line_cells
    panels: dict[str, dict[str, np.ndarray]] = {}
    for persistence in size.grid_persistence:
        label = "no persistence" if persistence is None else f"persistence {persistence}"
        grid_of = {
            measure: np.array(
                [[cell(persistence, ra, rb)[key] for rb in rates] for ra in rates], dtype=float
            )
            for measure, key in (
                ("coherent share", "coherent_share"),
                ("shifts per 200 steps", "shifts_per_200"),
                ("leader index", "leader_index"),
            )
        }
        panels[label] = grid_of
    figures.plot_phase_diagram(rates, panels, out / "figures" / "phase_diagram.png")
    settings = list(
        {
            (c["persistence"], c["adaptation_a"], c["adaptation_b"]): c
            for c in summary_cells + line_cells
        }.values()
    )
    holding = [c for c in settings if c["holds"]]
    shifting = [c for c in settings if c["shifts"]]

    def setting(c: dict[str, Any]) -> str:
        p = "none" if c["persistence"] is None else str(c["persistence"])
        return f"persistence {p}, A {c['adaptation_a']:g}, B {c['adaptation_b']:g}"

    def cell_rows(group: list[dict[str, Any]]) -> list[list[Any]]:
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

    header = ["persistence", "A", "B", "coherent share", "shifts / 200 steps",
              "led by A / B", "leader index", "regime"]  # fmt: skip
    report += [
        "## Phase diagram over the two adaptation rates",
        "",
        f"Learning set 1 for both, {size.grid_steps} steps from random starts, seeds "
        f"{grid_seeds}; rows: A's adaptation, columns: B's; cells are means over the seeds. "
        f"Joint attention holds where coherent ≥ {HOLD_SHARE:.0%} of the time; spontaneous "
        f"shifts: ≥ {SHIFT_RATE:g} pattern shift per 200 steps, with each agent leading some.",
        "",
        *table(header, cell_rows(summary_cells)),
        "",
        embed("phase diagram", "phase_diagram.png"),
        "",
        "### Persistence at adaptation 1 for both",
        "",
        *table(header, cell_rows(line_cells)),
        "",
        f"Cells where joint attention holds: {len(holding)} "
        f"({'; '.join(setting(c) for c in holding) or 'none'}). Cells with spontaneous shifts "
        f"led from both sides: {len(shifting)} "
        f"({'; '.join(setting(c) for c in shifting) or 'none'}).",
        "",
    ]

    # 3. the subject protocol ---------------------------------------------------------------
    sessions = rows("subject")
    results["subject"] = sessions
    curves = {f"{k['set']} seed {k['seed']}": r["found"] for k, r in done if k["part"] == "subject"}
    figures.plot_patterns_found(curves, DT, 3, out / "figures" / "patterns_found.png")
    example = figure_of("subject")
    figures.plot_dyad(
        example["arrays"],
        example["coherent"],
        out / "figures" / "subject.png",
        title=f"robot ({size.subject_sets[0]}) and scripted subject, seed {first}",
        names=("robot", "subject"),
        shifts=[(s, {"a": "robot", "b": "subject"}.get(w, "")) for s, w in example["shifts"]],
    )
    in_time = [
        s
        for s in sessions
        if s["minutes_to_all"] is not None and s["minutes_to_all"] <= FOUND_MINUTES
    ]
    in_time_looks = [
        s
        for s in sessions
        if s["minutes_to_all_by_templates"] is not None
        and s["minutes_to_all_by_templates"] <= FOUND_MINUTES
    ]
    report += [
        "## The subject protocol",
        "",
        "A robot (a plain mirror system, adaptation 1, no initiative but when left "
        "alone) and a scripted subject who knows the demonstrator's four movements, "
        "not the robot's three; the subject follows a robot movement close to one of "
        "its own and initiates another when they cannot match (docs/dyad.md). A pattern "
        "is found once the first joint-attention episode on it has lasted "
        f"{measures.MIN_EPISODE} coherent steps. Up to {size.subject_minutes:g} simulated "
        f"minutes ({subject_steps} steps; a session ends once every pattern is found), seeds "
        f"{subject_seeds[0]}–{subject_seeds[-1]}, each its own session, the sets in turn. "
        "Judged by the patterns as taught "
        f"only, {len(in_time_looks)}/{len(sessions)} sessions find all three in time.",
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
            [
                [
                    name,
                    len(group),
                    sum(s in in_time for s in group),
                    fmt(_median_first(group, "minutes_to_all"), 1),
                    fmt(np.median([s["patterns_found"] for s in group]), 0),
                    sum(s["pattern_shifts"] for s in group),
                    f"{sum(s['led_by_a'] for s in group)} / {sum(s['led_by_b'] for s in group)}",
                ]
                for name in size.subject_sets
                for group in [[s for s in sessions if s["set"] == name]]
            ],
        ),
        "",
        embed("subject", "subject.png"),
        "",
        embed("patterns found", "patterns_found.png"),
        "",
    ]

    targets = {
        "robots_lock_from_random_starts": Target(
            lock_share >= LOCK_SHARE,
            f"{locked}/{len(same)} same-set runs coherent within {LOCK_STEPS} steps "
            f"(target ≥ {LOCK_SHARE:.0%}; by the patterns as taught only "
            f"{locked_looks}/{len(same)})",
        ),
        "phase_diagram_both_regimes": Target(
            bool(holding) and bool(shifting),
            f"{len(holding)} settings with joint attention holding (coherent ≥ "
            f"{HOLD_SHARE:.0%}), {len(shifting)} shifting ≥ {SHIFT_RATE:g}/200 steps with the "
            "lead on both sides",
        ),
        "subject_finds_all": Target(
            len(in_time) / len(sessions) >= FOUND_SHARE,
            f"{len(in_time)}/{len(sessions)} sessions found all three patterns within "
            f"{FOUND_MINUTES:g} simulated minutes (target ≥ {FOUND_SHARE:.0%})",
        ),
    }
    runtime = time.perf_counter() - start
    results["targets"] = {k: t.to_json() for k, t in targets.items()}
    results["runtime_s"] = runtime
    results["job_cpu_s"] = float(sum(r["summary"]["cpu_s"] for _, r in done))
    report += [
        "## Targets",
        "",
        *table(
            ["target", "met", "detail"],
            [[k, "yes" if t.met else "NOT met", t.detail] for k, t in targets.items()],
        ),
        "",
        f"Runtime {runtime:.0f} s; versions: "
        + ", ".join(f"{k} {v}" for k, v in results["versions"].items()),
        "",
    ]
    write_outputs(out, report, results)
    return StudyOutcome(runtime_s=runtime, targets=targets)
