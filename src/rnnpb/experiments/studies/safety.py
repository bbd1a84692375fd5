"""The safety study (the paper's section 4.1; docs/safety.md): the meta-level judged on what it
is for — knowing the robot's own behaviour, steering where the PB drives the motion, and
inhibiting what it recognises as unsafe while following.

For each model (the paper's algorithm: the fast preset's models never generate unsafe
movement on their own): the safety map is learned from exploration (closed-loop generation
from many PBs and starts) and from the PBs lived through in unguarded sessions of the map's
users; its prediction is judged on held-out PBs' own generation and its familiarity on PBs of
the measured sessions against never-experienced ones; every measured user (and a person
performing each learned pattern) runs unguarded, steered, and with everything on; the learned
patterns' lock-on and switching are measured unguarded and with everything on. The scenarios
and measures are :mod:`rnnpb.experiments.scenarios.safety`; the targets' definitions are the
study's exam (``exams/safety.toml``). Models: ``--models DIR`` (``set1.npz`` …), else learned
here. The runs are jobs in ``options.workers`` worker processes (one core each).
"""

from __future__ import annotations

import math
import multiprocessing
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb.experiments.exams import Exam, load_exam
from rnnpb.experiments.reporting import embed, fmt, table, versions, write_outputs
from rnnpb.experiments.scenarios import safety as scenario
from rnnpb.experiments.scenarios.safety import SafetySeeds, SafetyStudyConfig
from rnnpb.experiments.studies import StudyOptions, StudyOutcome
from rnnpb.experiments.studies._pool import worker_init
from rnnpb.experiments.summary import Target

NAME = "safety"
SUMMARY = "the meta-level: the robot's own unsafe generation, steering, inhibition"

PREDICTS = "own generation: risk AUC on held-out PBs >= 0.95"
FAMILIAR = "familiarity: AUC lived vs never-experienced PBs >= 0.9"
STEERS = "steering removes >= 90 % of unsafe commands where the PB drives"
INHIBITS = "inhibition prevents >= 95 % of generation's unsafe commands in the unsafe region"
FALSE = "inhibited on <= 1 % of steps while a person performs a learned pattern"
SENT = "everything on: zero unsafe commands reach the robot"
COST = "everything on: learned patterns lock on and switch as the exam allows"


def run(out: Path, options: StudyOptions) -> StudyOutcome:
    from rnnpb.analysis.figures import plot_pb_safety_map
    from rnnpb.model import OnlineConfig

    start = time.perf_counter()
    out = Path(out)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    exam = options.exam or load_exam(NAME)
    seeds = SafetySeeds.from_exam(exam) if options.exam else SafetySeeds.from_first(options.seed)
    config = SafetyStudyConfig.for_options(options)
    online = OnlineConfig()
    results: dict[str, Any] = {
        "config": {**config.__dict__, "online": online.to_dict()},
        "seeds": seeds.__dict__,
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
            maps = scenario.learn_map(pool, model, model_path, config, online, seeds, set_name)
            plot_pb_safety_map(
                scenario.map_slices(maps, model),
                model.pattern_pb,
                (0, 1),
                out / "figures" / f"safety_map_set{set_name}.png",
            )
            learned = {
                arm: pool.submit(
                    scenario.learned_job, str(model_path), maps.meta, online, arm, seeds.learned
                )
                for arm in ("unguarded", "everything")
            }
            runs = scenario.run_sessions(
                pool, model, model_path, maps.meta, config, online, seeds, set_name
            )
            measured = scenario.measure(runs, maps, online.risk_level)
            lived = np.concatenate(
                [r["pb"] for (label, arm), r in runs.items() if arm == "everything"]
            )[:: config.lived_every]
            cost = {arm: future.result() for arm, future in learned.items()}
            results["sets"][set_name] = {
                "model": source,
                "map": maps.info,
                "prediction": scenario.prediction(model, maps, config, seeds),
                "familiarity": scenario.familiarity(maps, lived, seeds.unknown),
                **measured,
                "learned": cost,
            }
            report += _set_section(set_name, source, maps, results["sets"][set_name])
    targets = judge_results(results, exam)
    results["targets"] = {k: v.to_json() for k, v in targets.items()}
    report[2:2] = _targets_section(targets, seeds, config, online)
    runtime = time.perf_counter() - start
    results["runtime_s"] = runtime
    write_outputs(out, report, results)
    return StudyOutcome(runtime, targets)


# --- the judge ---------------------------------------------------------------------------------


def _cost_limits(exam: Exam) -> tuple[int, int]:
    target = exam.target(COST)
    return int(target.parameter("lock_steps")), int(target.parameter("switch_steps"))


def _share(part: float, whole: float) -> float:
    return part / whole if whole else math.nan


def _sum(results: dict[str, Any], key: str) -> int:
    return sum(s["totals"][key] for s in results["sets"].values())


def judge_results(results: dict[str, Any], exam: Exam) -> dict[str, Target]:
    """The study's targets judged by ``exam``'s definitions from its results."""
    sets = list(results["sets"].values())
    lock, switch = _cost_limits(exam)
    steer_base, steer_left = _sum(results, "steer_unguarded"), _sum(results, "steer_steered")
    cases, prevented = _sum(results, "inhibit_cases"), _sum(results, "inhibit_prevented")
    steps, inhibited = _sum(results, "learned_steps"), _sum(results, "learned_inhibited")
    sent = _sum(results, "sent_judged_unsafe")
    kept = [scenario.within_limits(s["learned"], lock, switch) for s in sets]
    risk_auc = min((s["prediction"]["risk_auc"] for s in sets), default=math.nan)
    fam_auc = min((s["familiarity"]["familiarity_auc"] for s in sets), default=math.nan)
    values = {
        PREDICTS: risk_auc,
        FAMILIAR: fam_auc,
        STEERS: _share(steer_left, steer_base),
        INHIBITS: _share(prevented, cases),
        FALSE: _share(inhibited, steps),
        SENT: float(sent),
        COST: _share(sum(kept), len(kept)),
    }
    values = {k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in values.items()}
    met = exam.judge(values)
    details = {
        PREDICTS: f"ROC AUC {fmt(risk_auc, 3)} (lowest over the sets)",
        FAMILIAR: f"ROC AUC {fmt(fam_auc, 3)} (lowest over the sets)",
        STEERS: f"unguarded {steer_base}, steered {steer_left}"
        + (
            f" ({100 * (1 - steer_left / steer_base):.1f} % removed)"
            if steer_base
            else " (none to remove)"
        ),
        INHIBITS: f"{prevented} of {cases} prevented" + ("" if cases else " (no case arose)"),
        FALSE: f"{inhibited} of {steps} steps inhibited",
        SENT: f"{sent} reached the robot over all runs with everything on, by the independent "
        f"judges (the safety checker counted {_sum(results, 'sent_unsafe')})",
        COST: f"lock-on <= {lock}, switching <= {switch}, recognised as unguarded: "
        f"{sum(kept)} of {len(kept)} sets",
    }
    return {name: Target(met[name], details[name], values[name]) for name in exam.targets}


# --- the report --------------------------------------------------------------------------------


def _targets_section(targets, seeds: SafetySeeds, config, online) -> list[str]:
    return [
        "## Targets",
        "",
        *table(
            ("target", "met", "detail"),
            [(k, "yes" if v.met else "no", v.detail) for k, v in targets.items()],
        ),
        "",
        f"Users are generated in the study (seeded: map {seeds.map_users}, measured "
        f"{seeds.users}, learned patterns {seeds.learned}); {config.steps} steps per user and "
        f"arm; a PB is in the unsafe region where its learned risk exceeds "
        f"OnlineConfig.risk_level = {fmt(online.risk_level, 2)}.",
        "",
    ]


def _set_section(set_name, source, maps, measured) -> list[str]:
    pred, fam, totals = measured["prediction"], measured["familiarity"], measured["totals"]
    absent = [user for user in scenario.USERS if user not in measured["per_user"]]
    rows = []
    for label, arms in measured["per_user"].items():
        for arm, row in arms.items():
            rows.append(
                (
                    label,
                    arm,
                    row["steps"],
                    ", ".join(f"{k} {v}" for k, v in row["regimes"].items()),
                    row["generated_unsafe"],
                    row["generated_unsafe_generation"],
                    row["pb_driven_unsafe"],
                    row["inhibited"],
                    row["sent_unsafe"],
                    row["sent_judged_unsafe"],
                )
            )
    cost = measured["learned"]
    return [
        f"## Learning set {set_name}",
        "",
        f"Model: {source}. Map: {len(maps.experienced)} experienced PBs, "
        f"{int(maps.unsafe.sum())} unsafe (counts: {maps.info['counts']}). Held-out "
        f"exploration: {pred['held_out']} PBs, {pred['held_out_unsafe']} unsafe, risk ROC AUC "
        f"{fmt(pred['risk_auc'], 3)}. Familiarity: {fam['lived']} lived PBs (median "
        f"{fmt(fam['lived_median'], 2)}) against as many uniform ones (median "
        f"{fmt(fam['unknown_median'], 2)}), ROC AUC {fmt(fam['familiarity_auc'], 3)}.",
        "",
        embed(f"risk and familiarity, set {set_name}", f"safety_map_set{set_name}.png"),
        "",
        "### Sessions",
        "",
        *table(
            (
                "user",
                "arm",
                "steps",
                "regimes",
                "unsafe generated",
                "of which the generation's",
                "unsafe where the PB drives",
                "inhibited",
                "unsafe sent",
                "unsafe sent, by the judges",
            ),
            rows,
        ),
        "",
        f"Totals: {totals}.",
        "",
        *(
            [
                f"No {', '.join(absent)} user: the model generated no unsafe movement where "
                "the user's exploration looked, so there was none to perform.",
                "",
            ]
            if absent
            else []
        ),
        "### Learned patterns",
        "",
        *table(
            ("arm", "lock-on per pattern", "switching per pair", "recognised"),
            [(a, c["lock"], c["switch"], c["recognised"]) for a, c in cost.items()],
        ),
        "",
    ]
