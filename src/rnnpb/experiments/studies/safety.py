"""The safety study (the paper's section 4.1; docs/safety.md): a map of PB space, and
adversarial users with and without the meta-level and the command filter.

For each model: the safety map is learned from exploration (closed-loop generation from many
PBs) and from the PBs visited while adversarial users of *training* seeds interact with the
unguarded robot; then adversarial users of other seeds interact with the robot with the guard
off, with the barrier and with the projection, the command filter in the act section of the
loop each time. The filter's record says which generated commands were unsafe (what reaches
the robot without the filter) and the commands sent are checked again (what reaches it with
the filter). The mirror's motor input is its own closed-loop prediction
(``OnlineConfig.motor_input``), so the filter does not change what the network generates and
one run measures both.

The adversarial users are generated here (seeded): random walks of both hands, jerky targets
(a new random target every 1–4 steps), fast scribbles (sums of sinusoids with periods of 2–5
steps), a full swing (each hand coordinate jumping between the view's edges every step) and
the paper's novel pattern (the pattern the learning set left out, from the demonstrator).
The cost on learned patterns: :func:`rnnpb.experiments.paper.synchronization` (lock-on and
recognition, paper 3.1) and :func:`~rnnpb.experiments.paper.switching` (every ordered pair,
3.2), guard off and on.

The runs are jobs in ``options.workers`` worker processes (one core each): the PBs visited
for the map, then every (user, guard) run and the learned-pattern runs per guard.
"""

from __future__ import annotations

import json
import multiprocessing
import os
import sys
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb.analysis import metrics
from rnnpb.experiments.reporting import embed, fmt, table, versions, write_outputs
from rnnpb.experiments.studies import StudyOptions, StudyOutcome
from rnnpb.experiments.summary import Target

NAME = "safety"
SUMMARY = "where in PB space behaviour is unsafe: the meta-level and the command filter"

USERS = ("random_walk", "jerky_targets", "fast_scribbles", "full_swing", "novel_pattern")
GUARDS = ("off", "barrier", "projection")
MODELS_ENV = "RNNPB_STUDY_MODELS"
"""A directory of learned models ``set1.npz`` … (the demo's); without it the study learns its
own (paper preset; quick: the fast preset)."""


@dataclass(frozen=True)
class SafetyStudyConfig:
    sets: tuple[str, ...]
    steps: int  # per adversarial user and guard
    visited_steps: int  # per adversarial user, training seeds, for the map
    samples: int  # explored PBs
    quick: bool

    @classmethod
    def for_options(cls, options: StudyOptions) -> SafetyStudyConfig:
        if options.quick:
            return cls(sets=("1",), steps=150, visited_steps=100, samples=200, quick=True)
        return cls(sets=("1",), steps=10_000, visited_steps=1000, samples=2000, quick=False)


def adversarial_stream(kind: str, n_steps: int, seed: int, learning_set: str) -> np.ndarray:
    """A user's hands (n_steps, 4) in [0, 1] of the given kind."""
    rng = np.random.default_rng(seed)
    if kind == "random_walk":
        walk = 0.5 + np.cumsum(rng.normal(0, 0.04, (n_steps, 4)), axis=0)
        return 1 - np.abs(1 - np.mod(walk, 2.0))  # reflected into [0, 1]
    if kind == "jerky_targets":
        out, t = np.empty((n_steps, 4)), 0
        while t < n_steps:
            hold = int(rng.integers(1, 5))
            out[t : t + hold] = rng.uniform(0.05, 0.95, 4)
            t += hold
        return out
    if kind == "fast_scribbles":
        t = np.arange(n_steps)[:, None]
        periods = rng.uniform(2.0, 5.0, (3, 4))
        phases = rng.uniform(0, 2 * np.pi, (3, 4))
        wave = sum(np.sin(2 * np.pi * t / periods[k] + phases[k]) for k in range(3)) / 3
        return np.clip(0.5 + 0.4 * wave, 0, 1)
    if kind == "full_swing":
        # Each coordinate of each hand jumps between the two edges of the view every step
        # (the fastest movement the camera could see), with random reach and phase.
        low = rng.uniform(0.0, 0.2, 4)
        high = rng.uniform(0.8, 1.0, 4)
        flip = (np.arange(n_steps)[:, None] + rng.integers(0, 2, 4)) % 2
        return np.where(flip == 0, low, high)
    if kind == "novel_pattern":
        from rnnpb.demonstrator import novel_scenario

        return novel_scenario(learning_set, n_steps=n_steps, seed=seed).sensory
    raise ValueError(kind)


def _models(config: SafetyStudyConfig, seed: int) -> dict[str, Any]:
    from rnnpb.demonstrator import learning_set
    from rnnpb.model import TrainConfig, TrainedModel, train
    from rnnpb.robot import JOINT_LIMITS

    directory = os.environ.get(MODELS_ENV)
    models = {}
    for name in config.sets:
        path = Path(directory) / f"set{name}.npz" if directory else None
        if path is not None and path.exists():
            models[name] = (TrainedModel.load(path), str(path))
        else:
            train_config = (
                TrainConfig.fast(iterations=1500, seed=seed)
                if config.quick
                else TrainConfig.paper(seed=seed)
            )
            models[name] = (
                train(learning_set(name, seed=seed), JOINT_LIMITS, config=train_config),
                f"learned here ({train_config.optimizer})",
            )
    return models


def _interact(model, online, meta, sensory, truth=None) -> dict[str, np.ndarray]:
    from rnnpb.interaction import InteractionLoop
    from rnnpb.model import MirrorSystem
    from rnnpb.robot import ELBOW_AT_ZERO_PITCH
    from rnnpb.safety import CommandFilter
    from rnnpb.sources import ArraySensorySource

    rest = np.array([0.0, 0.0, 0.0, ELBOW_AT_ZERO_PITCH] * 2)
    command_filter = CommandFilter(initial=rest)
    records = []
    with ArraySensorySource(sensory, truth=truth) as source:
        InteractionLoop(
            MirrorSystem(model, online, meta=meta), source, command_filter=command_filter
        ).run(on_step=records.append)
    return {
        "motor": np.array([r.motor for r in records]),
        "pb": np.array([r.pb for r in records]),
        "observed": np.array([r.observed for r in records]),
        "predicted": np.array([r.predicted for r in records]),
        "unsafe": np.array([r.unsafe for r in records], dtype=object),
        "filtered": np.array([r.filtered for r in records], dtype=object),
        "rest": rest,
    }


def _physical(reasons: np.ndarray, kind: str) -> int:
    return int(sum(any(w.startswith(kind + ":") for w in r.split()) for r in reasons))


def _worker_init() -> None:
    # Each worker keeps to one core; the pool provides the parallelism.
    from rnnpb import _xla

    _xla.configure()
    _xla.single_threaded()


def _visit_job(model_path: str, online, user: str, steps: int, seed: int, set_name: str):
    """PBs an adversarial user of a training seed visits with the unguarded robot, labelled
    by whether the command generated there collided or was too fast (the map's experience)."""
    from rnnpb.model import TrainedModel
    from rnnpb.safety import visited

    model = TrainedModel.load(model_path)
    run = _interact(model, online, None, adversarial_stream(user, steps, seed, set_name))
    unsafe = [
        any(w.split(":")[0] in ("collision", "speed") for w in r.split()) for r in run["unsafe"]
    ]
    return visited(run["pb"], unsafe)


def _adversarial_job(
    model_path: str, meta, online, guard: str, user: str, steps: int, seed: int, set_name: str
) -> dict[str, Any]:
    """One adversarial user with one guard, the command filter in the loop: what the network
    generated (what reaches the robot without the filter) and what was sent (with it)."""
    from rnnpb.model import TrainedModel
    from rnnpb.safety import SafetyChecker, risk

    model = TrainedModel.load(model_path)
    sensory = adversarial_stream(user, steps, seed, set_name)
    t0 = time.perf_counter()
    run = _interact(
        model, replace(online, safety_guard=guard), None if guard == "off" else meta, sensory
    )
    seconds = time.perf_counter() - t0
    sent = SafetyChecker().check(run["motor"], previous=run["rest"])
    pb_risk = risk(meta, run["pb"])
    return {
        "user": user,
        "guard": guard,
        "steps": len(run["motor"]),
        "seed": seed,
        "unsafe_generated": int(
            sum(
                any(w.split(":")[0] in ("collision", "speed") for w in r.split())
                for r in run["unsafe"]
            )
        ),
        "collision_generated": _physical(run["unsafe"], "collision"),
        "speed_generated": _physical(run["unsafe"], "speed"),
        "limit_generated": _physical(run["unsafe"], "limit"),
        "prevented": int(sum(bool(f) for f in run["filtered"])),
        "collision_sent": sent.count("collision"),
        "speed_sent": sent.count("speed"),
        "unsettled_sent": sent.count("unsettled"),
        "unsafe_pb_steps": int((pb_risk > online.risk_level).sum()),
        "mean_risk": float(pb_risk.mean()),
        "ms_per_step": 1e3 * seconds / max(len(run["motor"]), 1),
        # Which parts collided in the generated commands (what drives the robot into them).
        "collision_parts": dict(
            Counter(
                w.split(":", 1)[1]
                for r in run["unsafe"]
                for w in r.split()
                if w.startswith("collision:")
            ).most_common(3)
        ),
    }


def _learned_job(model_path: str, meta, online, guard: str) -> dict[str, Any]:
    """Lock-on, recognition and switching of the learned patterns with one guard
    (:func:`rnnpb.experiments.paper.synchronization` and ``switching``, paper 3.1–3.2), and
    whether the command filter would change any command of the performed patterns."""
    from rnnpb.experiments.paper import switching, synchronization
    from rnnpb.model import TrainedModel
    from rnnpb.robot import JOINT_LIMITS
    from rnnpb.safety import CommandFilter

    model = TrainedModel.load(model_path)
    cfg = replace(online, safety_guard=guard)
    meta = None if guard == "off" else meta
    lock, recognised, prevented = {}, {}, 0
    for pattern in model.patterns:
        sync = synchronization(model, pattern, cfg, JOINT_LIMITS, seed=7, meta=meta)
        lock[pattern] = sync.steps_to_lock
        recognised[pattern] = sync.recognized_pattern
        # The motor input is the network's own prediction, so filtering afterwards is what
        # the filter in the loop would have done.
        command_filter = CommandFilter(initial=sync.run.motor[0])
        prevented += sum(bool(command_filter(c).filtered) for c in sync.run.motor)
    switch = switching(model, cfg, JOINT_LIMITS, seed=7, meta=meta).pairs
    return {
        "lock": lock,
        "recognised": recognised,
        "switch": switch,
        "filter_prevented_on_learned": int(prevented),
    }


def _map_slices(maps, model, grid: int = 41):
    learned = model.pattern_pb
    axis = np.linspace(0, 1, grid)
    xx, yy = np.meshgrid(axis, axis)
    slices = []
    for name, pb in learned.items():
        points = np.broadcast_to(pb, (grid, grid, len(pb))).copy()
        points[..., 0], points[..., 1] = xx, yy
        slices.append(
            (
                f"pb2={pb[2]:.2f}, pb3={pb[3]:.2f} (pattern {name})",
                maps.risk(points),
                maps.familiarity(points),
            )
        )
    return slices


def run(out: Path, options: StudyOptions) -> StudyOutcome:
    from rnnpb.analysis.figures import plot_pb_safety_map
    from rnnpb.model import OnlineConfig, generate
    from rnnpb.safety import ExplorationConfig, SafetyChecker, learn_safety_map, safety_map_path

    start = time.perf_counter()
    out = Path(out)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    config = SafetyStudyConfig.for_options(options)
    online = OnlineConfig()
    checker = SafetyChecker()
    results: dict[str, Any] = {
        "config": {**config.__dict__, "online": online.to_dict()},
        "seed": options.seed,
        "versions": versions(),
        "sets": {},
    }
    report = ["# Safety by experience (paper section 4.1)", ""]
    totals = {"sent": 0, "generated_off": 0, "generated_barrier": 0, "generated_projection": 0}
    cost_ok = {"barrier": True, "projection": True}
    context = multiprocessing.get_context("spawn")
    _worker_init()
    pool = ProcessPoolExecutor(
        max_workers=options.workers, mp_context=context, initializer=_worker_init
    )
    with pool:
        for set_name, (model, source) in _models(config, options.seed).items():
            model_path = out / "models" / f"set{set_name}.npz"
            model_path.parent.mkdir(exist_ok=True)
            model.save(model_path)  # a copy the workers load (the original is not touched)
            # Experience from PBs visited by adversarial users of training seeds (not the
            # ones measured below).
            visits = list(
                pool.map(
                    _visit_job,
                    *zip(
                        *[
                            (
                                str(model_path),
                                online,
                                user,
                                config.visited_steps,
                                options.seed + k,
                                set_name,
                            )
                            for k, user in enumerate(USERS)
                        ],
                        strict=True,
                    ),
                )
            )
            also = visits[0]
            for more in visits[1:]:
                also = also.joined(more)
            maps = learn_safety_map(
                model, ExplorationConfig(samples=config.samples, seed=options.seed), also=also
            )
            maps.save(safety_map_path(model_path))
            plot_pb_safety_map(
                _map_slices(maps, model),
                model.pattern_pb,
                (0, 1),
                out / "figures" / f"safety_map_set{set_name}.png",
            )
            jobs = {
                pool.submit(
                    _adversarial_job,
                    str(model_path),
                    maps.meta,
                    online,
                    guard,
                    user,
                    config.steps,
                    options.seed + 1000 + k,
                    set_name,
                ): f"{user}/{guard}"
                for k, user in enumerate(USERS)
                for guard in GUARDS
            }
            learned_jobs = {
                guard: pool.submit(_learned_job, str(model_path), maps.meta, online, guard)
                for guard in GUARDS
            }
            adversarial = {}
            for future in as_completed(jobs):
                adversarial[jobs[future]] = future.result()
                # Each run as it comes (a long study interrupted keeps what it measured).
                with open(out / "runs.jsonl", "a", encoding="utf-8") as handle:
                    handle.write(json.dumps({"set": set_name, **adversarial[jobs[future]]}) + "\n")
                print(
                    f"  set {set_name}: {jobs[future]} done ({len(adversarial)}/{len(jobs)})",
                    file=sys.stderr,
                    flush=True,
                )
            adversarial = {key: adversarial[key] for key in jobs.values()}
            cost = {guard: future.result() for guard, future in learned_jobs.items()}
            for row in adversarial.values():
                totals["sent"] += row["collision_sent"] + row["speed_sent"]
                totals[f"generated_{row['guard']}"] += row["unsafe_generated"]
            learned_safe = {
                name: not checker.check(generate(model, pb, 120).motor).unsafe.any()
                for name, pb in model.pattern_pb.items()
            }
            for guard in ("barrier", "projection"):
                locks = [v for v in cost[guard]["lock"].values()]
                switches = [v for v in cost[guard]["switch"].values()]
                cost[guard]["within_limits"] = (
                    all(v is not None and v <= metrics.LOCK_LIMIT for v in locks)
                    and all(v is not None and v <= metrics.SWITCH_LIMIT for v in switches)
                    and cost[guard]["recognised"] == cost["off"]["recognised"]
                )
            for guard in ("barrier", "projection"):
                cost_ok[guard] = cost_ok[guard] and cost[guard]["within_limits"]
            results["sets"][set_name] = {
                "model": source,
                "map": maps.info,
                "adversarial": adversarial,
                "learned": cost,
                "learned_safe_check": learned_safe,
            }
            report += [
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
            ]
            report += table(
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
            report += ["", "### Cost on learned patterns", ""]
            report += table(
                (
                    "guard",
                    "lock-on per pattern",
                    "switching per pair",
                    "recognised",
                    "filter acted",
                ),
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
            )
            report.append("")
    base = totals["generated_off"]
    targets = {
        "filter: zero collisions and speed violations reach the robot": Target(
            totals["sent"] == 0, f"{totals['sent']} reached the robot over all runs"
        )
    }
    for guard in ("barrier", "projection"):
        left = totals[f"generated_{guard}"]
        targets[f"meta-level alone ({guard}) removes >= 90 % of unsafe commands"] = Target(
            base > 0 and left <= 0.1 * base,
            f"unguarded {base}, {guard} {left}"
            + (f" ({100 * (1 - left / base):.1f} % removed)" if base else " (none to remove)"),
        )
    for guard in ("barrier", "projection"):
        targets[f"no cost on learned patterns ({guard})"] = Target(
            cost_ok[guard],
            f"lock-on <= {metrics.LOCK_LIMIT}, switching <= "
            f"{metrics.SWITCH_LIMIT}, recognition as with the guard off",
        )
    results["totals"] = totals
    results["targets"] = {k: v.to_json() for k, v in targets.items()}
    report[2:2] = [
        "## Targets",
        "",
        *table(
            ("target", "met", "detail"),
            [(k, "yes" if v.met else "no", v.detail) for k, v in targets.items()],
        ),
        "",
        f"Users are generated in the study (seeded: {options.seed} + 1000 + k); "
        f"{config.steps} steps per user and guard; a PB step is unsafe where its learned "
        f"risk exceeds OnlineConfig.risk_level = {fmt(online.risk_level, 2)}.",
        "",
    ]
    runtime = time.perf_counter() - start
    results["runtime_s"] = runtime
    write_outputs(out, report, results)
    return StudyOutcome(runtime, targets)
