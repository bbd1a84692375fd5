"""The safety study (the paper's section 4.1; docs/safety.md): a map of PB space, and
adversarial users with and without the meta-level and the command filter.

For each model: the safety map is learned from exploration (closed-loop generation from many
PBs) and from the PBs visited while adversarial users of the map's seeds interact with the
unguarded robot; then adversarial users of other seeds interact with the robot with the guard
off, with the barrier and with the projection, the command filter in the act section of the
loop each time; and the learned patterns are performed with each guard. The scenarios and
measures are :mod:`rnnpb.experiments.scenarios.safety`; the targets' definitions are the
study's exam (``exams/safety.toml``). Models: ``--models DIR`` (``set1.npz`` …), else learned
here (the paper's algorithm; the quick form the fast preset). The runs are jobs in
``options.workers`` worker processes (one core each).
"""

from __future__ import annotations

import math
import multiprocessing
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

from rnnpb.experiments.exams import Exam, load_exam
from rnnpb.experiments.reporting import embed, fmt, table, versions, write_outputs
from rnnpb.experiments.scenarios import safety as scenario
from rnnpb.experiments.scenarios.safety import GUARDS, SafetySeeds, SafetyStudyConfig
from rnnpb.experiments.studies import StudyOptions, StudyOutcome
from rnnpb.experiments.studies._pool import worker_init
from rnnpb.experiments.summary import Target

NAME = "safety"
SUMMARY = "where in PB space behaviour is unsafe: the meta-level and the command filter"

FILTER = "filter: zero collisions and speed violations reach the robot"
GUARDED = ("barrier", "projection")


def _removes(guard: str) -> str:
    return f"meta-level alone ({guard}) removes >= 90 % of unsafe commands"


def _no_cost(guard: str) -> str:
    return f"no cost on learned patterns ({guard})"


def run(out: Path, options: StudyOptions) -> StudyOutcome:
    from rnnpb.analysis.figures import plot_pb_safety_map
    from rnnpb.model import OnlineConfig, generate
    from rnnpb.safety import SafetyChecker

    start = time.perf_counter()
    out = Path(out)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    exam = options.exam or load_exam(NAME)
    seeds = SafetySeeds.from_exam(exam) if options.exam else SafetySeeds.from_first(options.seed)
    config = SafetyStudyConfig.for_options(options)
    online = OnlineConfig()
    checker = SafetyChecker()
    results: dict[str, Any] = {
        "config": {**config.__dict__, "online": online.to_dict()},
        "seed": options.seed,
        "versions": versions(),
        "sets": {},
    }
    if options.exam is not None:
        results["exam"] = exam.to_json()
    report = ["# Safety by experience (paper section 4.1)", ""]
    if options.exam is not None:
        report += [exam.describe(), ""]
    worker_init()
    pool = ProcessPoolExecutor(
        max_workers=options.workers,
        mp_context=multiprocessing.get_context("spawn"),
        initializer=worker_init,
    )
    with pool:
        models = scenario.study_models(options.models, config, seeds.model, out / "models")
        for set_name, (model, source) in models.items():
            model_path = out / "models" / f"set{set_name}.npz"
            model_path.parent.mkdir(exist_ok=True)
            model.save(model_path)  # a copy the workers load (the original is not touched)
            maps = scenario.learn_map(pool, model, model_path, set_name, config, online, seeds)
            plot_pb_safety_map(
                scenario.map_slices(maps, model),
                model.pattern_pb,
                (0, 1),
                out / "figures" / f"safety_map_set{set_name}.png",
            )
            adversarial, cost = scenario.run_guards(
                pool, model_path, maps.meta, set_name, config, online, seeds, out / "runs.jsonl"
            )
            for guard in GUARDED:
                cost[guard]["within_limits"] = scenario.within_limits(
                    cost, guard, *_cost_limits(exam, guard)
                )
            results["sets"][set_name] = {
                "model": source,
                "map": maps.info,
                "adversarial": adversarial,
                "learned": cost,
                "learned_safe_check": {
                    name: not checker.check(generate(model, pb, 120).motor).unsafe.any()
                    for name, pb in model.pattern_pb.items()
                },
            }
            report += _set_section(set_name, source, maps, adversarial, cost)
    results["totals"] = _totals(results)
    targets = judge_results(results, exam)
    results["targets"] = {k: v.to_json() for k, v in targets.items()}
    users = (
        f"{seeds.users[0]}–{seeds.users[-1]}"
        if options.exam is not None
        else f"{options.seed} + 1000 + k"
    )
    report[2:2] = _targets_section(targets, users, config, online)
    runtime = time.perf_counter() - start
    results["runtime_s"] = runtime
    write_outputs(out, report, results)
    return StudyOutcome(runtime, targets)


def _totals(results: dict[str, Any]) -> dict[str, int]:
    """Unsafe commands sent (collision and speed) and generated per guard, over every set."""
    totals = {"sent": 0, "generated_off": 0, "generated_barrier": 0, "generated_projection": 0}
    for measured in results["sets"].values():
        for row in measured["adversarial"].values():
            totals["sent"] += row["collision_sent"] + row["speed_sent"]
            totals[f"generated_{row['guard']}"] += row["unsafe_generated"]
    return totals


# --- the judge ---------------------------------------------------------------------------------


def _cost_limits(exam: Exam, guard: str) -> tuple[int, int]:
    target = exam.target(_no_cost(guard))
    return int(target.parameter("lock_steps")), int(target.parameter("switch_steps"))


def judge_results(results: dict[str, Any], exam: Exam) -> dict[str, Target]:
    """The study's targets judged by ``exam``'s definitions from its results."""
    totals = results["totals"]
    base = totals["generated_off"]
    values: dict[str, float] = {FILTER: totals["sent"]}
    for guard in GUARDED:
        values[_removes(guard)] = totals[f"generated_{guard}"] / base if base else math.nan
    for guard in GUARDED:
        limits = _cost_limits(exam, guard)
        kept = [
            scenario.within_limits(s["learned"], guard, *limits) for s in results["sets"].values()
        ]
        values[_no_cost(guard)] = sum(kept) / len(kept) if kept else math.nan
    met = exam.judge(values)
    targets = {FILTER: Target(met[FILTER], f"{totals['sent']} reached the robot over all runs")}
    for guard in GUARDED:
        left = totals[f"generated_{guard}"]
        targets[_removes(guard)] = Target(
            met[_removes(guard)],
            f"unguarded {base}, {guard} {left}"
            + (f" ({100 * (1 - left / base):.1f} % removed)" if base else " (none to remove)"),
        )
    for guard in GUARDED:
        lock, switch = _cost_limits(exam, guard)
        targets[_no_cost(guard)] = Target(
            met[_no_cost(guard)],
            f"lock-on <= {lock}, switching <= {switch}, recognition as with the guard off",
        )
    return targets


# --- the report --------------------------------------------------------------------------------


def _targets_section(targets, users: str, config, online) -> list[str]:
    return [
        "## Targets",
        "",
        *table(
            ("target", "met", "detail"),
            [(k, "yes" if v.met else "no", v.detail) for k, v in targets.items()],
        ),
        "",
        f"Users are generated in the study (seeded: {users}); "
        f"{config.steps} steps per user and guard; a PB step is unsafe where its learned "
        f"risk exceeds OnlineConfig.risk_level = {fmt(online.risk_level, 2)}.",
        "",
    ]


def _set_section(set_name, source, maps, adversarial, cost) -> list[str]:
    return [
        f"## Learning set {set_name}",
        "",
        f"Model: {source}. Map: "
        f"{len(maps.experienced)} experienced PBs, {int(maps.unsafe.sum())} unsafe "
        f"(explored: {maps.info['counts']}).",
        "",
        embed(f"risk and familiarity, set {set_name}", f"safety_map_set{set_name}.png"),
        "",
        "### Adversarial users",
        "",
        *_adversarial_table(adversarial),
        "",
        "### Cost on learned patterns",
        "",
        *table(
            ("guard", "lock-on per pattern", "switching per pair", "recognised", "filter acted"),
            [
                (
                    g,
                    cost[g]["lock"],
                    cost[g]["switch"],
                    cost[g]["recognised"],
                    cost[g]["filter_prevented_on_learned"],
                )
                for g in GUARDS
            ],
        ),
        "",
    ]


def _adversarial_table(adversarial: dict[str, dict[str, Any]]) -> list[str]:
    return table(
        (
            "user",
            "guard",
            "steps",
            "unsafe generated (collision/speed)",
            "limit",
            "prevented by filter",
            "collision sent",
            "speed sent",
            "unsettled sent",
            "unsafe-PB steps",
            "parts colliding (generated)",
        ),
        [
            (
                r["user"],
                r["guard"],
                r["steps"],
                f"{r['collision_generated']}/{r['speed_generated']}",
                r["limit_generated"],
                r["prevented"],
                r["collision_sent"],
                r["speed_sent"],
                r["unsettled_sent"],
                r["unsafe_pb_steps"],
                ", ".join(f"{k} {v}" for k, v in r["collision_parts"].items()) or "—",
            )
            for r in adversarial.values()
        ],
    )
