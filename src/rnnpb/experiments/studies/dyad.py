"""Mutual interaction (the paper's section 4.2): two robots imitating each other, and a scripted
subject exploring a robot's repertoire (docs/dyad.md).

Three parts, each on the paper-learned models of learning sets 1-4 (default ``OnlineConfig``):

1. robot–robot from random starts, both robots with the same learned set and with different
   ones: the steps until the first coherent step (target: ≤ 60 steps in ≥ 90 % of runs with
   the same set);
2. a phase diagram over the two robots' adaptation rates, without and with persistence (the
   initiative a robot takes after a stable while): share of time coherent, pattern shifts per
   200 steps, leader index;
3. the subject protocol: a robot (a plain mirror system) and a scripted subject with the
   demonstrator's four movements; the robot's patterns found per simulated minute (target:
   all three within 10 minutes in ≥ 80 % of runs).

Settings (patience, persistence, lead) were chosen on seeds 100-105; the study's seeds start
at ``--seed`` (0).
"""

from __future__ import annotations

import os
import time
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb.analysis import dyad as measures
from rnnpb.analysis import figures
from rnnpb.errors import ConfigError
from rnnpb.experiments.reporting import embed, fmt, table, versions, write_outputs
from rnnpb.experiments.studies import StudyOptions, StudyOutcome
from rnnpb.experiments.summary import Target
from rnnpb.interaction.dyad import (
    AgentConfig,
    DyadRun,
    SubjectConfig,
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
DT = 0.4
LOCK_STEPS = 60  # the target: coherent within 60 steps
LOCK_SHARE = 0.9
HOLD_SHARE = 0.9  # joint attention holds: coherent >= 90 % of the time
SHIFT_RATE = 1.0  # spontaneous shifts: >= 1 per 200 steps
FOUND_MINUTES = 10.0
FOUND_SHARE = 0.8
PATIENCE = 6  # steps of not predicting the partner before a robot initiates
PERSISTENCE = 60  # steps of stable interaction before a robot initiates (the "shifting" runs)
RATES = (0.1, 1.0)
CHUNK = 60  # steps of a subject session between checks whether all is found


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


def _robots(
    model_a: TrainedModel,
    model_b: TrainedModel,
    a: AgentConfig,
    b: AgentConfig,
    seed: int,
    steps: int,
    record: Path | None = None,
) -> tuple[dict, Any, Any]:
    pair = robot_pair(model_a, model_b, a, b, seed=seed)
    if record is not None:
        with DyadRecorder(record, model_a.network.pb_size, DT) as recorder:
            run = pair.run(steps, on_step=recorder.write)
    else:
        run = pair.run(steps)
    shared = tuple(p for p in model_a.patterns if p in model_b.patterns)
    # Each robot's class: the learned pattern its PB is nearest to, while it moves.
    recognised = [
        np.array([model.nearest_pattern(p)[0] for p in run[f"{side}_pb"]], dtype=object)
        for model, side in ((model_a, "a"), (model_b, "b"))
    ]
    found = measures.measure_dyad(
        run["a_shown"],
        run["b_shown"],
        shared,
        run["a_pb"],
        run["b_pb"],
        recognised_a=recognised[0],
        recognised_b=recognised[1],
    )
    # The same runs judged by their movements against the demonstrator's templates.
    looks = measures.measure_dyad(run["a_shown"], run["b_shown"], shared, run["a_pb"], run["b_pb"])
    return run.arrays, found, looks


def _subject_session(
    dyad: Any, model: TrainedModel, n_steps: int, record: Path | None
) -> tuple[dict, Any]:
    """Up to ``n_steps`` steps, a cycle at a time: a session ends once every learned
    pattern is found (nothing after that changes what the protocol measures)."""
    steps: list = []
    recorder = DyadRecorder(record, model.network.pb_size, DT) if record is not None else None

    def keep(record: Any) -> None:
        steps.append(record)
        if recorder is not None:
            recorder.write(record)

    try:
        while len(steps) < n_steps:
            dyad.run(min(CHUNK, n_steps - len(steps)), on_step=keep)
            arrays = DyadRun.from_steps(steps).arrays
            found = measures.measure_dyad(
                arrays["a_shown"], arrays["b_shown"], model.patterns, arrays["a_pb"]
            )
            if found.found[-1] >= len(model.patterns):
                break
    finally:
        if recorder is not None:
            recorder.close()
    return arrays, found


def run(out: Path, options: StudyOptions) -> StudyOutcome:
    start = time.perf_counter()
    out = Path(out)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    (out / "sessions").mkdir(parents=True, exist_ok=True)
    quick = options.quick
    models = {
        name: TrainedModel.load(_model_path(name)) for name in ("set1", "set2", "set3", "set4")
    }
    seeds = list(range(options.seed, options.seed + (2 if quick else 4)))
    follower = AgentConfig(patience=PATIENCE)
    results: dict[str, Any] = {
        "config": {
            "dt": DT,
            "patience": PATIENCE,
            "persistence": PERSISTENCE,
            "rates": list(RATES),
            "agent": asdict(follower),
            "subject": asdict(SubjectConfig()),
            "online": OnlineConfig().to_dict(),
            "models": {k: str(_model_path(k)) for k in models},
            "quick": quick,
        },
        "seeds": seeds,
        "versions": versions(),
    }
    report = [
        "# Mutual interaction (section 4.2)",
        "",
        "Two agents coupled through their senses (docs/dyad.md). Models: the paper-learned "
        "learning sets 1-4; on-line regression: the default `OnlineConfig`.",
        "",
    ]

    # 1. random starts ----------------------------------------------------------------------
    pairs = [("set1", "set1"), ("set2", "set2"), ("set3", "set3"), ("set4", "set4")]
    if quick:
        pairs = pairs[:1]
    mixed = [("set1", "set2"), ("set3", "set4")][: 1 if quick else 2]
    mixed_seeds = seeds[:2]
    starts: list[dict[str, Any]] = []
    example = None
    for kind, group, group_seeds in (("same", pairs, seeds), ("different", mixed, mixed_seeds)):
        for name_a, name_b in group:
            for seed in group_seeds:
                record = (
                    out / "sessions" / f"robots_{name_a}_{name_b}_seed{seed}.csv"
                    if seed == seeds[0]
                    else None
                )
                arrays, found, looks = _robots(
                    models[name_a], models[name_b], follower, follower, seed, 80, record
                )
                starts.append(
                    {
                        "kind": kind,
                        "a": name_a,
                        "b": name_b,
                        "seed": seed,
                        **found.summary(DT),
                        "first_coherent_by_templates": looks.first_coherent,
                    }
                )
                if example is None and kind == "same":
                    example = (arrays, found, f"{name_a} and {name_b}, seed {seed}")
    same = [s for s in starts if s["kind"] == "same"]
    locked = [
        s for s in same if s["first_coherent"] is not None and s["first_coherent"] <= LOCK_STEPS
    ]
    lock_share = len(locked) / len(same)
    locked_looks = [
        s
        for s in same
        if s["first_coherent_by_templates"] is not None
        and s["first_coherent_by_templates"] <= LOCK_STEPS
    ]
    results["random_starts"] = starts
    figures.plot_dyad(
        example[0],
        example[1].coherent,
        out / "figures" / "robots.png",
        title=f"two robots from random starts ({example[2]})",
        shifts=[(s.step, s.leader) for s in example[1].shifts],
    )
    report += [
        "## Robot–robot from random starts",
        "",
        f"Both robots adapt (adaptation 1) and initiate a pattern of their own after "
        f"{PATIENCE} steps (and up to twice that) of not predicting the other. A "
        "robot's class is the learned pattern nearest its PB while it moves (docs/dyad.md"
        "); judged instead by the movement against the demonstrator's templates, "
        f"{len(locked_looks)}/{len(same)} same-set runs are coherent within "
        f"{LOCK_STEPS} steps (a model's closed loop may play a pattern unlike the "
        "demonstrator's).",
        "",
        *table(
            [
                "sets",
                "kind",
                "runs",
                f"coherent within {LOCK_STEPS} steps",
                "first coherent step (median)",
                "coherent share (median)",
            ],
            [
                [
                    f"{a} + {b}",
                    kind,
                    len(rows),
                    f"{sum(r['first_coherent'] is not None and r['first_coherent'] <= LOCK_STEPS for r in rows)}",  # noqa: E501
                    fmt(
                        np.median(
                            [
                                r["first_coherent"] if r["first_coherent"] is not None else np.inf
                                for r in rows
                            ]
                        ),
                        0,
                    ),
                    fmt(np.median([r["coherent_share"] for r in rows]), 2),
                ]
                for (kind, a, b) in dict.fromkeys((s["kind"], s["a"], s["b"]) for s in starts)
                for rows in [[s for s in starts if (s["kind"], s["a"], s["b"]) == (kind, a, b)]]
            ],
        ),
        "",
        embed("two robots", "robots.png"),
        "",
    ]

    # 2. the phase diagram ------------------------------------------------------------------
    grid_seeds = seeds[: 1 if quick else 2]
    rates = RATES
    steps = 200
    panels: dict[str, dict[str, np.ndarray]] = {}
    cells: list[dict[str, Any]] = []
    for label, persistence in (
        ("no persistence", None),
        (f"persistence {PERSISTENCE}", PERSISTENCE),
    ):
        share = np.full((len(rates), len(rates)), np.nan)
        rate = np.full_like(share, np.nan)
        lead = np.full_like(share, np.nan)
        for i, ra in enumerate(rates):
            for j, rb in enumerate(rates):
                rows = []
                for seed in grid_seeds:
                    a = AgentConfig(adaptation=ra, patience=PATIENCE, persistence=persistence)
                    b = AgentConfig(adaptation=rb, patience=PATIENCE, persistence=persistence)
                    _, found, _ = _robots(models["set1"], models["set1"], a, b, seed, steps)
                    rows.append(
                        {
                            "setting": label,
                            "adaptation_a": ra,
                            "adaptation_b": rb,
                            "seed": seed,
                            **found.summary(DT),
                        }
                    )
                cells += rows
                share[i, j] = np.mean([r["coherent_share"] for r in rows])
                rate[i, j] = np.mean([r["pattern_shifts"] * 200 / r["steps"] for r in rows])
                led_a = sum(r["led_by_a"] for r in rows)
                led_b = sum(r["led_by_b"] for r in rows)
                lead[i, j] = (led_a - led_b) / (led_a + led_b) if led_a + led_b else np.nan
        panels[label] = {
            "coherent share": share,
            "shifts per 200 steps": rate,
            "leader index": lead,
        }
    results["phase_diagram"] = cells
    figures.plot_phase_diagram(rates, panels, out / "figures" / "phase_diagram.png")
    holds = [c for c in cells if c["coherent_share"] >= HOLD_SHARE]
    shifting = [
        c
        for c in cells
        if c["pattern_shifts"] * 200 / c["steps"] >= SHIFT_RATE
        and c["led_by_a"] > 0
        and c["led_by_b"] > 0
    ]
    report += [
        "## Phase diagram over the two adaptation rates",
        "",
        f"Learning set 1 for both, {steps} steps from random starts, seeds "
        f"{grid_seeds}; rows: A's adaptation, columns: B's. Joint attention holds where "
        f"coherent ≥ {HOLD_SHARE:.0%} of the time; spontaneous shifts: ≥ {SHIFT_RATE:g} "
        "pattern shift per 200 steps, with both agents leading some.",
        "",
        *table(
            [
                "setting",
                "A",
                "B",
                "coherent share",
                "shifts / 200 steps",
                "leader index",
                "runs holding",
                "runs shifting, lead both sides",
            ],
            [
                [
                    label,
                    f"{ra:g}",
                    f"{rb:g}",
                    fmt(panels[label]["coherent share"][i, j], 2),
                    fmt(panels[label]["shifts per 200 steps"][i, j], 2),
                    fmt(panels[label]["leader index"][i, j], 2),
                    sum(
                        c in holds
                        for c in cells
                        if (c["setting"], c["adaptation_a"], c["adaptation_b"]) == (label, ra, rb)
                    ),
                    sum(
                        c in shifting
                        for c in cells
                        if (c["setting"], c["adaptation_a"], c["adaptation_b"]) == (label, ra, rb)
                    ),
                ]
                for label in panels
                for i, ra in enumerate(rates)
                for j, rb in enumerate(rates)
            ],
        ),
        "",
        embed("phase diagram", "phase_diagram.png"),
        "",
    ]

    # 3. the subject protocol ---------------------------------------------------------------
    subject_sets = ["set1"] if quick else ["set1", "set2", "set3", "set4"]
    subject_seeds = seeds[:1] if quick else seeds[:2]
    minutes = 2.0 if quick else FOUND_MINUTES
    n_steps = int(round(minutes * 60 / DT))
    robot = AgentConfig()
    sessions: list[dict[str, Any]] = []
    curves: dict[str, np.ndarray] = {}
    for name in subject_sets:
        model = models[name]
        for seed in subject_seeds:
            dyad = robot_and_subject(model, robot, SubjectConfig(), seed=seed)
            record = (
                out / "sessions" / f"subject_{name}_seed{seed}.csv"
                if seed == subject_seeds[0]
                else None
            )
            arrays, found = _subject_session(dyad, model, n_steps, record)
            all_found = np.flatnonzero(found.found >= len(model.patterns))
            sessions.append(
                {
                    "set": name,
                    "seed": seed,
                    **found.summary(DT),
                    "minutes_to_all": (float(all_found[0] * DT / 60) if all_found.size else None),
                    "steps_run": len(found.found),
                    "per_minute": [
                        int(found.found[min(int(m * 60 / DT), len(found.found)) - 1])
                        for m in range(1, int(minutes) + 1)
                    ],
                }
            )
            curves[f"{name} seed {seed}"] = found.found
            if name == subject_sets[0] and seed == subject_seeds[0]:
                figures.plot_dyad(
                    arrays,
                    found.coherent,
                    out / "figures" / "subject.png",
                    title=f"robot ({name}) and scripted subject, seed {seed}",
                    names=("robot", "subject"),
                    shifts=[
                        (s.step, {"a": "robot", "b": "subject"}.get(s.leader, ""))
                        for s in found.shifts
                    ],
                )
    figures.plot_patterns_found(curves, DT, 3, out / "figures" / "patterns_found.png")
    results["subject"] = sessions
    all_in_time = [
        s
        for s in sessions
        if s["minutes_to_all"] is not None and s["minutes_to_all"] <= FOUND_MINUTES
    ]
    report += [
        "## The subject protocol",
        "",
        "A robot (a plain mirror system, adaptation 1, no initiative but when left "
        "alone) and a scripted subject who knows the demonstrator's four movements, "
        "not the robot's three; the subject follows a robot movement close to one of "
        "its own and initiates another when they cannot match (docs/dyad.md). A pattern "
        "is found once the first joint-attention episode on it has lasted "
        f"{measures.MIN_EPISODE} coherent steps. Up to {minutes:g} simulated minutes "
        "(a session ends once every pattern is found).",
        "",
        *table(
            [
                "set",
                "seed",
                "found",
                "minutes to all",
                "found by minute",
                "pattern shifts",
                "led by robot / subject",
            ],
            [
                [
                    s["set"],
                    s["seed"],
                    s["patterns_found"],
                    fmt(s["minutes_to_all"], 1),
                    " ".join(str(v) for v in s["per_minute"]),
                    s["pattern_shifts"],
                    f"{s['led_by_a']} / {s['led_by_b']}",
                ]
                for s in sessions
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
            f"{len(locked)}/{len(same)} same-set runs coherent within {LOCK_STEPS} steps "
            f"(target ≥ {LOCK_SHARE:.0%}; by the demonstrator's templates "
            f"{len(locked_looks)}/{len(same)})",
        ),
        "phase_diagram_both_regimes": Target(
            bool(holds) and bool(shifting),
            f"{len(holds)} runs with joint attention holding (coherent ≥ {HOLD_SHARE:.0%}), "
            f"{len(shifting)} runs shifting ≥ {SHIFT_RATE:g}/200 steps with the lead on both "
            "sides",
        ),
        "subject_finds_all": Target(
            len(all_in_time) / len(sessions) >= FOUND_SHARE,
            f"{len(all_in_time)}/{len(sessions)} sessions found all three patterns within "
            f"{FOUND_MINUTES:g} simulated minutes (target ≥ {FOUND_SHARE:.0%})",
        ),
    }
    runtime = time.perf_counter() - start
    results["targets"] = {k: t.to_json() for k, t in targets.items()}
    results["runtime_s"] = runtime
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
