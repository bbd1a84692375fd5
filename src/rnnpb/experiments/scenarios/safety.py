"""The safety study's scenarios and measures (``rnnpb study safety``, docs/safety.md).

Adversarial users generated here (seeded): random walks of both hands, jerky targets (a new
random target every 1–4 steps), fast scribbles (sums of sinusoids with periods of 2–5 steps), a
full swing (each hand coordinate jumping between the view's edges every step) and the paper's
novel pattern (the pattern the learning set left out, from the demonstrator). Each runs through
the interaction loop with the command filter in its act section; the filter's record says
which generated commands were unsafe (what reaches the robot without the filter) and the
commands sent are checked again (what reaches it with the filter). The mirror's motor input is
its own closed-loop prediction (``OnlineConfig.motor_input``), so the filter does not change
what the network generates and one run measures both. The cost on learned patterns:
:func:`rnnpb.experiments.paper.synchronization` (lock-on and recognition, paper 3.1) and
:func:`~rnnpb.experiments.paper.switching` (every ordered pair, 3.2), guard off and on.
"""

from __future__ import annotations

import json
import sys
import time
from collections import Counter
from concurrent.futures import as_completed
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.experiments.exams import Exam
from rnnpb.experiments.scenarios import study_models as shared
from rnnpb.experiments.studies import StudyOptions

USERS = ("random_walk", "jerky_targets", "fast_scribbles", "full_swing", "novel_pattern")
GUARDS = ("off", "barrier", "projection")


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


@dataclass(frozen=True)
class SafetySeeds:
    """The study's seeds: the model's learning and the map's exploration (``model``), the
    adversarial users whose visited PBs the map learns from (``map_users``, one per user kind
    in :data:`USERS` order), those measured with every guard (``users``, likewise) and the
    user performing the learned patterns (``learned``)."""

    model: int
    map_users: tuple[int, ...]
    users: tuple[int, ...]
    learned: int

    @classmethod
    def from_first(cls, seed: int) -> SafetySeeds:
        """``--seed``'s: the model, exploration and map users from ``seed`` on, the measured
        users from ``seed + 1000`` on, the learned patterns' user 7."""
        return cls(
            seed,
            tuple(seed + k for k in range(len(USERS))),
            tuple(seed + 1000 + k for k in range(len(USERS))),
            7,
        )

    @classmethod
    def from_exam(cls, exam: Exam) -> SafetySeeds:
        users = {k: exam.seed_list(k) for k in ("map_users", "users")}
        if any(len(seeds) != len(USERS) for seeds in users.values()):
            raise ConfigError(f"the safety exam needs one seed per user kind ({len(USERS)})")
        return cls(
            exam.seed_list("model")[0],
            users["map_users"],
            users["users"],
            exam.seed_list("learned_patterns")[0],
        )


def study_models(
    directory: str | None, config: SafetyStudyConfig, seed: int, out: Path
) -> dict[str, Any]:
    """Each learning set's model and where it came from: ``directory``'s ``setK.npz`` (a
    missing one is a clear error), or learned into ``out`` (the paper's algorithm; quick: the
    fast preset)."""
    from rnnpb.model import TrainConfig, TrainedModel

    train_config = (
        TrainConfig.fast(iterations=1500, seed=seed)
        if config.quick
        else TrainConfig.paper(seed=seed)
    )
    paths = shared.study_models(config.sets, directory, out, lambda _: train_config, seed)
    source = None if directory is not None else f"learned here ({train_config.optimizer})"
    return {name: (TrainedModel.load(path), source or path) for name, path in paths.items()}


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


def visit_job(model_path: str, online, user: str, steps: int, seed: int, set_name: str):
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


def adversarial_job(
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


def learned_job(model_path: str, meta, online, guard: str, seed: int) -> dict[str, Any]:
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
        sync = synchronization(model, pattern, cfg, JOINT_LIMITS, seed=seed, meta=meta)
        lock[pattern] = sync.steps_to_lock
        recognised[pattern] = sync.recognized_pattern
        # The motor input is the network's own prediction, so filtering afterwards is what
        # the filter in the loop would have done.
        assert sync.run is not None  # synchronization keeps its run
        command_filter = CommandFilter(initial=sync.run.motor[0])
        prevented += sum(bool(command_filter(c).filtered) for c in sync.run.motor)
    switch = switching(model, cfg, JOINT_LIMITS, seed=seed, meta=meta).pairs
    return {
        "lock": lock,
        "recognised": recognised,
        "switch": switch,
        "filter_prevented_on_learned": int(prevented),
    }


def map_slices(maps, model, grid: int = 41):
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


def learn_map(pool, model, model_path: Path, set_name: str, config, online, seeds: SafetySeeds):
    """The safety map of ``model`` (saved beside ``model_path``): learned from exploration and
    from the PBs adversarial users of the map's seeds (not the ones measured) visit with the
    unguarded robot."""
    from rnnpb.safety import ExplorationConfig, learn_safety_map, safety_map_path

    jobs = [
        (str(model_path), online, user, config.visited_steps, seeds.map_users[k], set_name)
        for k, user in enumerate(USERS)
    ]
    visits = list(pool.map(visit_job, *zip(*jobs, strict=True)))
    also = visits[0]
    for more in visits[1:]:
        also = also.joined(more)
    maps = learn_safety_map(
        model, ExplorationConfig(samples=config.samples, seed=seeds.model), also=also
    )
    maps.save(safety_map_path(model_path))
    return maps


def run_guards(pool, model_path: Path, meta, set_name: str, config, online, seeds, runs_file):
    """Every adversarial user with every guard, and the learned patterns per guard: (the
    adversarial runs by ``user/guard``, the cost per guard). Each adversarial run is appended
    to ``runs_file`` as it comes (a long study interrupted keeps what it measured)."""
    jobs = {
        pool.submit(
            adversarial_job, str(model_path), meta, online, guard, user, config.steps,
            seeds.users[k], set_name,
        ): f"{user}/{guard}"
        for k, user in enumerate(USERS)
        for guard in GUARDS
    }  # fmt: skip
    learned_jobs = {
        guard: pool.submit(learned_job, str(model_path), meta, online, guard, seeds.learned)
        for guard in GUARDS
    }
    adversarial = {}
    for future in as_completed(jobs):
        adversarial[jobs[future]] = future.result()
        with open(runs_file, "a", encoding="utf-8") as handle:
            handle.write(json.dumps({"set": set_name, **adversarial[jobs[future]]}) + "\n")
        print(
            f"  set {set_name}: {jobs[future]} done ({len(adversarial)}/{len(jobs)})",
            file=sys.stderr,
            flush=True,
        )
    adversarial = {key: adversarial[key] for key in jobs.values()}
    return adversarial, {guard: future.result() for guard, future in learned_jobs.items()}


def within_limits(cost: dict[str, Any], guard: str, lock_steps: int, switch_steps: int) -> bool:
    """Whether every learned pattern locks on within ``lock_steps`` and switches within
    ``switch_steps`` with ``guard``, recognised as with the guard off."""
    locks = list(cost[guard]["lock"].values())
    switches = list(cost[guard]["switch"].values())
    return (
        all(v is not None and v <= lock_steps for v in locks)
        and all(v is not None and v <= switch_steps for v in switches)
        and cost[guard]["recognised"] == cost["off"]["recognised"]
    )
