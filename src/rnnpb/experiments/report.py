"""Run every experiment of the paper's section 3 and write ``report.md`` and ``results.json``.

The jobs (one per trained model) run in ``workers`` processes; every job is seeded, so a run
repeats. Outputs under the chosen directory::

    data/            the learning sets as sequence CSVs (set1/ … set4/, full/)
    models/          every trained model (setK.npz, full_seedN.npz)
    figures/         the figures the report embeds
    report.md        measure | paper | ours, with the figures
    results.json     every measure, the config, versions and which file is which
"""

from __future__ import annotations

import json
import math
import multiprocessing
import os
import platform
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb import __version__
from rnnpb._atomic import atomic_write
from rnnpb.experiments.paper import (
    LOCK_LIMIT,
    RELOCK_LIMIT,
    SETTLE_LIMIT,
    SWITCH_LIMIT,
    ExperimentConfig,
    larger_set_job,
    learning_set_job,
    sequence_file_name,
)
from rnnpb.model import OnlineConfig, TrainConfig

LEARNING_SETS = ("1", "2", "3", "4")


def _worker_init() -> None:
    # Each worker keeps to one core; the pool provides the parallelism.
    from rnnpb import _xla

    _xla.single_threaded()


def run_jobs(out: Path, config: ExperimentConfig,
             log: Callable[[str], None]) -> tuple[dict, list, dict]:
    models, data = out / "models", out / "data"
    models.mkdir(parents=True, exist_ok=True)
    jobs: dict[Any, tuple[str, Any]] = {}
    default: dict[str, dict] = {}
    paper: dict[str, dict] = {}
    larger: list[dict] = []
    _worker_init()
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=config.workers, mp_context=context,
                             initializer=_worker_init) as pool:
        compare = config.paper_online if config.compare_paper else None
        for name in LEARNING_SETS:
            data_dir = data / f"set{name}"
            data_dir.mkdir(parents=True, exist_ok=True)
            future = pool.submit(learning_set_job, name, config.train, config.online, config,
                                 str(models / f"set{name}.npz"), str(data_dir), "default", True,
                                 compare)
            jobs[future] = ("default", name)
        for seed in range(config.larger_set_seeds):
            future = pool.submit(larger_set_job, seed, config.larger_train, config.online, config,
                                 str(models / f"full_seed{seed}.npz"))
            jobs[future] = ("larger", seed)
        for done, future in enumerate(as_completed(jobs), start=1):
            kind, key = jobs[future]
            result = future.result()
            if kind == "default":
                default[key] = result
                if "compare" in result:  # the same model, the paper's on-line regression
                    compared = result.pop("compare")
                    paper[key] = {**result, **compared, "label": "paper"}
            else:
                larger.append(result)
            log(f"  [{done}/{len(jobs)}] {kind} {'seed ' if kind == 'larger' else 'set '}"
                f"{key} done")
    larger.sort(key=lambda r: r["seed"])
    return default, larger, paper


def _values(results: dict[str, dict], key: str) -> dict[str, dict[str, Any]]:
    return {name: {s["pattern"]: s[key] for s in r["synchronization"]}
            for name, r in results.items()}


def _flat(nested: dict[str, dict[str, Any]]) -> list[Any]:
    return [v for inner in nested.values() for v in inner.values()]


def _max_or_none(values: list[Any]) -> Any:
    """The largest value; None (never) counts as the worst."""
    if any(v is None for v in values):
        return None
    return max(values) if values else None


def summarize(results: dict[str, dict]) -> dict[str, Any]:
    """The measures of one configuration (default or paper) as JSON-ready values."""
    ordered = {k: results[k] for k in sorted(results)}
    summary = {
        "train_mse": {k: r["train_mse_max"] for k, r in ordered.items()},
        "train_rms": {k: r["train_rms_max"] for k, r in ordered.items()},
        "train_mse_per_output": {k: r["train_mse_per_output"] for k, r in ordered.items()},
        "train_seconds": {k: r["train_seconds"] for k, r in ordered.items()},
        "sync_steps_to_lock": _values(ordered, "steps_to_lock"),
        "pb_settle_steps": _values(ordered, "pb_settle_steps"),
        "phase_lag_steps": _values(ordered, "phase_lag_steps"),
        "recognized_pattern": _values(ordered, "recognized_pattern"),
        "pause_relative_motion": _values(ordered, "pause_relative_motion"),
        "pause_steps_to_relock": _values(ordered, "pause_steps_to_relock"),
        "switch_steps": {k: r["switching"]["pairs"] for k, r in ordered.items()},
    }
    recognized = _flat(_values(ordered, "recognized_pattern"))
    patterns = [p for r in ordered.values() for p in r["patterns"]]
    summary["recognized_correctly"] = int(sum(a == b for a, b in zip(recognized, patterns,
                                                                     strict=True)))
    summary["recognition_runs"] = len(patterns)
    return summary


def _fmt(value: Any, digits: int = 1) -> str:
    if value is None:
        return "never"
    if isinstance(value, float):
        if math.isnan(value):
            return "–"
        return f"{value:.{digits}f}"
    return str(value)


def _range(values: list[Any]) -> str:
    if not values:
        return "–"
    if any(v is None for v in values):
        finite = [v for v in values if v is not None]
        worst = "never"
    else:
        finite = values
        worst = _fmt(max(values))
    median = _fmt(float(np.median(finite))) if finite else "–"
    return f"median {median}, worst {worst}"


def _target(values: list[Any], limit: float) -> tuple[bool, str]:
    worst = _max_or_none(values)
    met = worst is not None and worst <= limit
    return met, f"{_within(values, limit)}/{len(values)} within {limit:g}"


def targets(summary: dict[str, Any], larger: list[dict], novel_cases: list[int]
            ) -> dict[str, dict[str, Any]]:
    out = {}
    mse = list(summary["train_mse"].values())
    out["train_mse_below_3e-4"] = {"met": all(v < 3e-4 for v in mse),
                                   "detail": f"max {max(mse):.2e}"}
    for key, values, limit in (
            ("lock_within_10", _flat(summary["sync_steps_to_lock"]), LOCK_LIMIT),
            ("pb_settles_within_20", _flat(summary["pb_settle_steps"]), SETTLE_LIMIT),
            ("relock_within_5", _flat(summary["pause_steps_to_relock"]), RELOCK_LIMIT),
            ("switch_within_15", _flat(summary["switch_steps"]), SWITCH_LIMIT)):
        met, detail = _target(values, limit)
        out[key] = {"met": met, "detail": detail}
    if novel_cases:
        seen = sorted(set(novel_cases))
        out["all_three_novel_cases"] = {
            "met": seen == [1, 2, 3],
            "detail": f"cases seen: {seen}" + ("" if seen == [1, 2, 3] else
                                               "; the report explains why, from the "
                                               "attractor analysis")}
    if larger:
        out["larger_set_9_of_10"] = _larger_target(sum(r["follows_all"] for r in larger),
                                                   len(larger))
    return out


_DRAW_MEASURES = (("sync_steps_to_lock", "lock_within_10", LOCK_LIMIT),
                  ("pb_settle_steps", "pb_settles_within_20", SETTLE_LIMIT),
                  ("pause_steps_to_relock", "relock_within_5", RELOCK_LIMIT),
                  ("switch_steps", "switch_within_15", SWITCH_LIMIT))


def _larger_target(success: int, runs: int) -> dict[str, Any]:
    return {"met": success >= math.ceil(0.9 * runs), "detail": f"{success}/{runs}"}


def _within(values: list[Any], limit: float) -> int:
    return sum(v is not None and v <= limit for v in values)


def draws_summary(results: dict[str, dict], larger: list[dict], config: ExperimentConfig
                  ) -> dict[str, Any]:
    """The lock-on, pause, switching and larger-set measures for every draw of the user's
    imperfection (the report's ``scenario_seed`` and the ``extra_scenario_seeds``), each
    draw's target counts, and the targets over all draws pooled."""
    ordered = {k: results[k] for k in sorted(results)}
    by_seed: dict[str, dict[str, Any]] = {}
    for seed in (config.scenario_seed, *config.extra_scenario_seeds):
        primary = seed == config.scenario_seed
        runs = ordered if primary else {k: r["draws"][seed] for k, r in ordered.items()}
        follows = list(larger) if primary else [r["draws"][seed] for r in larger]
        draw: dict[str, Any] = {key: _values(runs, source) for key, source in (
            ("sync_steps_to_lock", "steps_to_lock"), ("pb_settle_steps", "pb_settle_steps"),
            ("pause_steps_to_relock", "pause_steps_to_relock"))}
        draw["switch_steps"] = {k: r["switching"]["pairs"] for k, r in runs.items()}
        draw["larger_set_success"] = int(sum(f["follows_all"] for f in follows))
        draw["larger_set_steps_to_follow"] = [f["steps_to_follow"] for f in follows]
        draw["targets"] = {name: dict(zip(("met", "detail"),
                                          _target(_flat(draw[key]), limit), strict=True))
                           for key, name, limit in _DRAW_MEASURES}
        if larger:
            draw["targets"]["larger_set_9_of_10"] = _larger_target(draw["larger_set_success"],
                                                                   len(follows))
        by_seed[str(seed)] = draw
    pooled: dict[str, dict[str, Any]] = {}
    for key, name, limit in _DRAW_MEASURES:
        met, detail = _target([v for d in by_seed.values() for v in _flat(d[key])], limit)
        pooled[name] = {"met": met, "detail": detail}
    if larger:
        pooled["larger_set_9_of_10"] = _larger_target(
            sum(d["larger_set_success"] for d in by_seed.values()), len(larger) * len(by_seed))
    return {"scenario_seeds": [int(s) for s in by_seed], "by_seed": by_seed,
            "targets": pooled}


def _jsonable(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (np.floating, float)):
        return None if not math.isfinite(float(value)) else float(value)
    if isinstance(value, np.integer):
        return int(value)
    return value


def run_demo(out_dir: str | os.PathLike[str], config: ExperimentConfig,
             log: Callable[[str], None] = print) -> dict[str, Any]:
    """Run everything; write the report, the results and the figures; return the results."""
    from rnnpb.analysis import figures
    from rnnpb.demonstrator import learning_set
    from rnnpb.demonstrator._figure import figure4
    from rnnpb.robot import JOINT_LIMITS
    from rnnpb.sequences import write_sequence

    start = time.perf_counter()
    out = Path(out_dir)
    figure_dir = out / "figures"
    figure_dir.mkdir(parents=True, exist_ok=True)
    full_dir = out / "data" / "full"
    full = learning_set("full", seed=config.data_seed,
                        samples_per_pattern=config.samples_per_pattern)
    for seq in full:
        write_sequence(full_dir / sequence_file_name(seq), seq)
    log(f"training and running the experiments ({'quick' if config.quick else 'full'} run, "
        f"{config.workers} workers) …")
    default, larger, paper = run_jobs(out, config, log)
    log("drawing the figures …")
    figure4(full, figure_dir / "figure4_patterns.png")

    set1 = default["1"]
    sync = set1["synchronization"][0]
    figures.plot_session(sync["run"].session(), figure_dir / "figure5_synchronization.png",
                         title=f"Learning set 1: the user performs pattern {sync['pattern']}, "
                         f"pauses (shaded) and goes on", joint_limits=JOINT_LIMITS,
                         marks=[(sync["steps_to_lock"] or 0, "locked")])
    sequence = set1["sequence"]
    session = sequence["run"].session()
    switches = sequence["run"].switch_steps
    figures.plot_session(session, figure_dir / "figure6_switching.png",
                         title="Learning set 1: the user switches among the learned patterns",
                         joint_limits=JOINT_LIMITS,
                         marks=[(s, "switch") for s in switches])
    figures.plot_switch_zoom(session, [(s - 10, s + 30) for s in switches],
                             figure_dir / "figure7_switching_zoom.png", JOINT_LIMITS, switches)
    figures.plot_switch_matrix({k: default[k]["switching"]["pairs"] for k in sorted(default)},
                               figure_dir / "switching_matrix.png", SWITCH_LIMIT)
    novel_runs = [(run, default[k]["attractors"]) for k in sorted(default)
                  for run in default[k]["novel"]]
    shown: list[tuple[dict, dict]] = []
    for case in (1, 2, 3):  # one example of each case, as the paper shows
        for run, attractors in novel_runs:
            if run["case"] == case:
                shown.append((run, attractors))
                break
    for run, attractors in novel_runs:
        if len(shown) >= 3:
            break
        if all(run is not s for s, _ in shown):
            shown.append((run, attractors))
    figures.plot_novel_responses([r for r, _ in shown], figure_dir / "figure8_novel.png",
                                 JOINT_LIMITS)
    figures.plot_attractors(shown, figure_dir / "figure9_attractors.png",
                            config.attractor_transient)
    histories = {f"set {k}": default[k]["train_history"] for k in sorted(default)}
    figures.plot_training(histories, figure_dir / "training.png")

    summary = summarize(default)
    novel = [{k: run[k] for k in ("learning_set", "novel_pattern", "amplitude", "case",
                                  "description", "period", "nearest_pattern", "distance",
                                  "return_error")} for run, _ in novel_runs]
    results: dict[str, Any] = {
        "rnnpb_version": __version__,
        "versions": _versions(),
        "config": asdict(config),
        **summary,
        "novel_case": novel,
        "novel_cases_seen": sorted({r["case"] for r in novel}),
        "closed_loop_periods": {k: {p: a["period"] for p, a in default[k]["attractors"].items()}
                                for k in sorted(default)},
        "switch_sequence_steps_to_follow": sequence["steps_to_follow"],
        "larger_set_success": int(sum(r["follows_all"] for r in larger)),
        "larger_set_runs": [{k: r[k] for k in ("seed", "model", "train_mse_max",
                                               "steps_to_follow", "follows_all")}
                            for r in larger],
        "targets": targets(summary, larger, [r["case"] for r in novel]),
        "draws": draws_summary(default, larger, config),
        "files": {
            "models": {**{f"set{k}": f"models/set{k}.npz" for k in sorted(default)},
                       **{f"full_seed{r['seed']}": f"models/full_seed{r['seed']}.npz"
                          for r in larger}},
            "learning_sets": {**{f"set{k}": {"patterns": default[k]["patterns"],
                                             "data": f"data/set{k}/"} for k in sorted(default)},
                              "full": {"patterns": ["1", "2", "3", "4"], "data": "data/full/"}},
            "figures": sorted(p.name for p in figure_dir.glob("*.png")),
        },
    }
    if paper:
        results["paper_regression"] = summarize(paper)
        results["paper_regression"]["targets"] = targets(results["paper_regression"], [], [])
    results["runtime_s"] = time.perf_counter() - start
    with atomic_write(out / "results.json", "w", encoding="utf-8") as handle:
        json.dump(_jsonable(results), handle, indent=1)
    write_report(out / "report.md", results, config)
    return results


def _versions() -> dict[str, str]:
    import jax
    import mujoco

    return {"python": platform.python_version(), "jax": jax.__version__,
            "numpy": np.__version__, "mujoco": mujoco.__version__,
            "machine": platform.machine(), "cpus": str(os.cpu_count())}


def _missing_cases_explanation(results: dict[str, Any]) -> list[str]:
    """Why a response case did not occur, from the attractor analysis's own numbers."""
    runs = results["novel_case"]
    seen = {r["case"] for r in runs}
    missing = [c for c in (1, 2, 3) if c not in seen]
    if not missing or not runs:
        return []
    periods = sorted({r["period"] for r in runs if r["period"] is not None})
    worst_return = max(r["return_error"] for r in runs)
    closed = [p for periods_ in results["closed_loop_periods"].values()
              for p in periods_.values()]
    learned = sorted({p for p in closed if p is not None})
    cycles = sum(p is not None for p in closed)
    if cycles == len(closed):
        autonomous = (f"The closed-loop attractors of the learned patterns are limit cycles too "
                      f"(periods {', '.join(map(str, learned))}), and with on-line regression "
                      "the network entrains to the period it is shown.")
    else:
        autonomous = (f"Of the learned patterns' closed-loop attractors, {cycles} of "
                      f"{len(closed)} are limit cycles (periods "
                      f"{', '.join(map(str, learned)) or '–'}) and the others do not repeat "
                      "within 60 steps; yet driven by a repeated input and with on-line "
                      "regression, the network entrains to the period it is shown.")
    lines = ["", f"**Why case {' and '.join(map(str, missing))} did not occur here.**"]
    if 3 in missing:
        lines.append(
            f"Every response settled on a limit cycle: the largest return error over all "
            f"{len(runs)} runs is {worst_return:.3f} (a response counts as unsteady above "
            f"0.1), at period(s) {', '.join(map(str, periods))} — the period of the repeated "
            f"input cycle or a multiple of it. {autonomous} The input here is one exactly "
            "repeated cycle (the paper's user demonstrated the novel patterns by hand), and "
            "the PB, regressed every step, keeps the response on that period.")
    if 2 in missing:
        lines.append("Every periodic response lay within 0.05 of a learned pattern's cycle: "
                     "the novel patterns were drawn into the learned attractors.")
    if 1 in missing:
        lines.append("No periodic response lay within 0.05 of a learned pattern's cycle.")
    return lines


def _describe_learning(train: TrainConfig) -> str:
    if train.optimizer == "momentum":
        how = "the paper's algorithm, gradient descent with momentum"
    else:
        how = "Adam with noise on the teacher-forced inputs (the fast preset)"
    return f"{how}, {train.iterations:,} iterations"


def _describe_configuration(config: ExperimentConfig) -> str:
    """What **default** and **paper's regression** mean in this run, from its config."""
    def onset(online: OnlineConfig) -> str:
        return "optimised with the PB" if online.optimize_onset else "carried over"

    online = config.online
    phase = (f", phase restarts from the learned cycles (scored on the last "
             f"{online.phase_restarts} steps)" if online.phase_restarts else "")
    gate = (f", the surprise gate at {online.surprise_gate} RMS (power {online.gate_power:g})"
            if online.surprise_gate > 0 else ", no surprise gate")
    text = (f"**default** is this run's configuration. Learning: "
            f"{_describe_learning(config.train)} (the larger set: "
            f"{config.larger_train.iterations:,} iterations). On-line: "
            f"L = {online.window}, {online.iterations} iterations, integration length "
            f"{online.pb.integration_length}, onset state {onset(online)}"
            f"{', restarts at the learned PBs' if online.restart_span else ''}"
            f"{phase}{gate}.")
    if config.compare_paper:
        paper = config.paper_online
        text += (f" **paper's regression** runs the same models with the paper's on-line "
                 f"regression (L = {paper.window}, l = {paper.pb.integration_length}, "
                 f"{paper.iterations} iterations, onset state {onset(paper)}).")
    return text


def write_report(path: Path, results: dict[str, Any], config: ExperimentConfig) -> None:
    ours = results
    theirs = results.get("paper_regression")
    lines = [
        "# rnnpb — the experiments of Ito & Tani (2004), reproduced",
        "",
        f"rnnpb {results['rnnpb_version']}, {'quick' if config.quick else 'full'} run, "
        f"{results['runtime_s']:.0f} s on {results['versions']['cpus']} CPU(s) "
        f"(jax {results['versions']['jax']}, mujoco {results['versions']['mujoco']}). "
        "Every number below is in `results.json`; the definitions of the measures are in "
        "`rnnpb.analysis.metrics` and docs/experiments.md.",
        "",
        _describe_configuration(config),
        "",
        f"Every learning set holds {config.samples_per_pattern} demonstrations of each of its "
        f"patterns (the paper: 2), from the synthetic demonstrator with data seed "
        f"{config.data_seed}.",
        "",
        "## Summary",
        "",
        "| measure | paper | ours (default) | ours (paper's regression) |",
        "|---|---|---|---|",
    ]

    def row(name: str, paper_text: str, key: str, flatten: bool = True,
            kind: str = "range") -> None:
        def cell(summary: dict | None) -> str:
            if summary is None:
                return "not run (quick)" if config.quick else "–"
            value = summary[key]
            values = _flat(value) if flatten else list(value.values())
            if kind == "max":
                return f"max {max(values):.2e}"
            return _range(values)
        lines.append(f"| {name} | {paper_text} | {cell(ours)} | {cell(theirs)} |")

    row("final training error (MSE per output, worst of sets 1–4)", "< 3e-4 (RMS, read as MSE)",
        "train_mse", flatten=False, kind="max")
    lines.append(f"| final training error as RMS (worst) | < 3e-4 | "
                 f"{max(ours['train_rms'].values()):.2e} | "
                 + (f"{max(theirs['train_rms'].values()):.2e}" if theirs else "–") + " |")
    row("steps until locked on a learned pattern", "about 10", "sync_steps_to_lock")
    row("steps until the PB settles", "about 20", "pb_settle_steps")
    row("phase lag once locked (steps; + = robot behind)", "mostly synchronous",
        "phase_lag_steps")
    row("robot motion during a 5-step pause (relative to before)", "keeps moving",
        "pause_relative_motion")
    row("steps to re-lock after the pause", "a few", "pause_steps_to_relock")
    row("steps until the robot follows a switch (every ordered pair, sets 1–4)",
        "several", "switch_steps")
    lines.append(f"| learned pattern recognised (nearest learned PB) | all | "
                 f"{ours['recognized_correctly']}/{ours['recognition_runs']} | "
                 + (f"{theirs['recognized_correctly']}/{theirs['recognition_runs']}"
                    if theirs else "–") + " |")
    cases = [r["case"] for r in ours["novel_case"]]
    lines.append(f"| novel-pattern responses (case 1 / 2 / 3) | all three occur | "
                 f"{cases.count(1)} / {cases.count(2)} / {cases.count(3)} | – |")
    lines.append(f"| larger set: runs that follow every pattern | 9 of 10 | "
                 f"{ours['larger_set_success']} of {len(ours['larger_set_runs'])} | – |")
    draws = ours["draws"]
    seeds = draws["scenario_seeds"]

    def verdict(value: dict[str, Any] | None) -> str:
        if value is None:
            return "–"
        return f"{'met' if value['met'] else 'NOT met'} ({value['detail']})"

    lines += ["", "### Targets", "",
              f"For the report's draw of the user's imperfection (scenario seed {seeds[0]}) and "
              f"over all {len(seeds)} draws ({', '.join(map(str, seeds))}; see "
              "\"Other draws of the user's imperfection\" below):", "",
              "| target | default | default, all draws | paper's regression |",
              "|---|---|---|---|"]
    for key, value in ours["targets"].items():
        other = theirs["targets"].get(key) if theirs else None
        lines.append(f"| {key} | {verdict(value)} | {verdict(draws['targets'].get(key))} | "
                     f"{verdict(other)} |")
    lines += [
        "",
        "## The four movement patterns (Figure 4)",
        "",
        "![patterns](figures/figure4_patterns.png)",
        "",
        "## Learning",
        "",
        "| learning set | MSE (worst output) | RMS | seconds |",
        "|---|---|---|---|",
    ]
    for k in sorted(ours["train_mse"]):
        lines.append(f"| {k} | {ours['train_mse'][k]:.2e} | {ours['train_rms'][k]:.2e}"
                     f" | {ours['train_seconds'][k]:.0f} |")
    lines += ["", "![training](figures/training.png)", "",
              "## 3.1 Synchronization and pause (Figure 5)", "",
              "| set | pattern | steps to lock | PB settles | phase lag | recognised | "
              "motion in pause | re-lock |", "|---|---|---|---|---|---|---|---|"]
    for k in sorted(ours["sync_steps_to_lock"]):
        for p in ours["sync_steps_to_lock"][k]:
            lines.append(
                f"| {k} | {p} | {_fmt(ours['sync_steps_to_lock'][k][p])} | "
                f"{_fmt(ours['pb_settle_steps'][k][p])} | "
                f"{_fmt(ours['phase_lag_steps'][k][p], 2)} | "
                f"{ours['recognized_pattern'][k][p]} | "
                f"{_fmt(ours['pause_relative_motion'][k][p], 2)} | "
                f"{_fmt(ours['pause_steps_to_relock'][k][p])} |")
    lines += ["", "![synchronization](figures/figure5_synchronization.png)", "",
              "## 3.2 Switching (Figures 6 and 7)", "",
              "Steps from the user's switch until the robot follows the new pattern, for "
              "every ordered pair of learned patterns in every learning set (the user performs "
              "50 steps of the first pattern, then the second):", "",
              "![switching matrix](figures/switching_matrix.png)", "",
              "![switching](figures/figure6_switching.png)", "",
              "![switching zoom](figures/figure7_switching_zoom.png)", "",
              "## 3.3 Novel patterns and attractors (Figures 8 and 9)", "",
              "One cycle of the pattern a learning set left out is repeated while the PB is "
              "regressed on-line; the robot's response after the transient is classified "
              "(case 1: a limit cycle like a learned one; 2: a new limit cycle; 3: unsteady).",
              "", "| set | novel pattern | size | response |", "|---|---|---|---|"]
    for run in ours["novel_case"]:
        lines.append(f"| {run['learning_set']} | {run['novel_pattern']} | "
                     f"x{run['amplitude']:g} | {run['description']} |")
    lines += _missing_cases_explanation(ours)
    lines += ["", "![novel](figures/figure8_novel.png)", "",
              "![attractors](figures/figure9_attractors.png)", "",
              "Closed-loop periods of the learned patterns (steps; none = not periodic): "
              + "; ".join(f"set {k}: " + ", ".join(f"{p}→{_fmt(v)}" for p, v in periods.items())
                          for k, periods in ours["closed_loop_periods"].items()),
              "", "## 3.4 The larger set", "",
              "| seed | training MSE | steps to follow 1 / 2 / 3 / 4 | follows all |",
              "|---|---|---|---|"]
    for run in ours["larger_set_runs"]:
        steps = " / ".join(_fmt(v) for v in run["steps_to_follow"].values())
        lines.append(f"| {run['seed']} | {run['train_mse_max']:.2e} | {steps} | "
                     f"{'yes' if run['follows_all'] else 'no'} |")
    lines += ["", "## Other draws of the user's imperfection", "",
              "The user's imperfection (period, size and shape from cycle to cycle, drift, "
              "sensor noise) is drawn at random; the figures above use one draw. The same "
              "models, driven by other draws, give (counts within the target; median and worst "
              "steps):", "",
              "| scenario seed | lock on ≤ 10 | PB settles ≤ 20 | re-lock ≤ 5 | switch ≤ 15 | "
              "larger set |", "|---|---|---|---|---|---|"]
    for seed, draw in draws["by_seed"].items():
        cells = []
        for key, _, limit in _DRAW_MEASURES:
            values = _flat(draw[key])
            cells.append(f"{_within(values, limit)}/{len(values)} ({_range(values)})")
        n_larger = len(draw["larger_set_steps_to_follow"])
        cells.append(f"{draw['larger_set_success']}/{n_larger}" if n_larger else "–")
        lines.append(f"| {seed}{' (above)' if int(seed) == seeds[0] else ''} | "
                     + " | ".join(cells) + " |")
    lines += ["", "## Files", "",
              "Models (reuse them with `rnnpb interact --model …`): "
              + ", ".join(f"`{v}`" for v in ours["files"]["models"].values()) + ".",
              "Learning sets as sequence CSVs: `data/set1/` … `data/set4/`, `data/full/`.", ""]
    with atomic_write(path, "w", encoding="utf-8") as handle:
        handle.write("\n".join(lines))
