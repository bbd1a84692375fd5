"""The safety study's scenarios and measures (``rnnpb study safety``, docs/safety.md).

The meta-level is judged on what it is for (paper section 4.1): knowing the robot's *own*
behaviour, steering the PB where the PB drives the motion, and inhibiting a recognised unsafe
pattern while following.

Users (generated here, seeded): random walks of both hands, jerky targets (a new random
target every 1–4 steps), fast scribbles (sums of sinusoids with periods of 2–5 steps), a full
swing (each hand coordinate jumping between the view's edges every step), the paper's novel
pattern (the pattern the learning set left out), lost hands (a pattern performed, then the
hands lost, in turns), still hands (a pattern performed, then the hands held still, in
turns) and an unsafe pattern (the hands the network itself predicts while generating from a
PB whose own generation is unsafe from every start, a new such PB every 100 steps: the
paper's case of perceiving a pattern the robot must not regenerate); and a person performing
each learned pattern.

Each user's stream runs three times through the mirror system (:func:`session_job`):
``unguarded`` (no map), ``steered`` (the map's guard where the PB drives, no inhibition) and
``everything`` (steering, inhibition and the command filter). What the network generated is
checked with :class:`rnnpb.safety.SafetyChecker` against the command before (the filter's
view of it, without the filter changing it: the network's motor input is its own prediction),
and each unsafe command is attributed (:class:`rnnpb.safety.Attribution`) to the seen
movement or the generation.
"""

from __future__ import annotations

import sys
from concurrent.futures import as_completed
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from rnnpb.errors import ConfigError
from rnnpb.experiments.exams import Exam
from rnnpb.experiments.scenarios import study_models as shared
from rnnpb.experiments.studies import StudyOptions

USERS = (
    "random_walk",
    "jerky_targets",
    "fast_scribbles",
    "full_swing",
    "novel_pattern",
    "lost_hands",
    "still_hands",
    "unsafe_pattern",
)
ARMS = ("unguarded", "steered", "everything")
PHYSICAL = ("collision", "speed")


@dataclass(frozen=True)
class SafetyStudyConfig:
    sets: tuple[str, ...]
    steps: int  # per user and arm
    learned_steps: int  # per learned pattern performed
    samples: int  # explored PBs for the map
    held_out: int  # explored PBs of other draws, to judge the map's prediction
    starts: int  # starts per explored PB
    lived_every: int  # every how many steps of a lived session a PB joins the experience
    train_iterations: int | None  # None: the paper's
    quick: bool

    @classmethod
    def for_options(cls, options: StudyOptions) -> SafetyStudyConfig:
        if options.quick:
            return cls(("1",), 60, 40, 120, 80, 2, 10, 4000, True)
        return cls(("1",), 1000, 300, 2000, 1000, 4, 5, None, False)


def _pattern_stream(pattern: str, n_steps: int, seed: int) -> np.ndarray:
    from rnnpb.demonstrator import held_scenario

    return held_scenario(pattern, n_steps=n_steps, seed=seed).sensory


def user_stream(
    kind: str, n_steps: int, seed: int, learning_set: str, patterns=(), model=None
) -> np.ndarray:
    """A user's hands (n_steps, 4) in [0, 1] (NaN where lost) of the given kind;
    ``patterns``: the learned patterns (for ``lost_hands`` and ``still_hands``); ``model``:
    the robot's (for ``unsafe_pattern``)."""
    rng = np.random.default_rng(seed)
    if kind == "unsafe_pattern":
        if model is None:
            raise ConfigError("the unsafe_pattern user needs the model")
        return _unsafe_pattern(model, n_steps, seed)
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
        low = rng.uniform(0.0, 0.2, 4)
        high = rng.uniform(0.8, 1.0, 4)
        flip = (np.arange(n_steps)[:, None] + rng.integers(0, 2, 4)) % 2
        return np.where(flip == 0, low, high)
    if kind == "novel_pattern":
        from rnnpb.demonstrator import novel_scenario

        return novel_scenario(learning_set, n_steps=n_steps, seed=seed).sensory
    if kind in ("lost_hands", "still_hands"):
        if not patterns:
            raise ConfigError(f"the {kind} user needs the learned patterns")
        out = np.empty((n_steps, 4))
        t, turn = 0, 0
        while t < n_steps:
            pattern = patterns[int(rng.integers(len(patterns)))]
            shown = _pattern_stream(pattern, 30, seed * 100 + turn)
            gap = int(rng.integers(20, 41))
            end = min(t + 30, n_steps)
            out[t:end] = shown[: end - t]
            rest = np.nan if kind == "lost_hands" else shown[end - t - 1]
            out[end : min(end + gap, n_steps)] = rest
            t, turn = end + gap, turn + 1
        return out
    raise ValueError(kind)


def _unsafe_pattern(model, n_steps: int, seed: int, each: int = 100) -> np.ndarray:
    """The hands the network predicts generating from the PBs whose own generation is most
    often unsafe (found by an exploration of the user's seed: unsafe from every start where
    any PB is; a model with none such still has PBs unsafe from some starts), each for
    ``each`` steps after the transient. :class:`NoUnsafeMovement` when no explored PB's
    generation is ever unsafe: then there is no such movement to perform."""
    from rnnpb.safety import ExplorationConfig, explore, generate_from, sample_starts

    config = ExplorationConfig(samples=200, starts=2, seed=seed)
    found = explore(model, config)
    worst = float(found.share.max(initial=0.0))
    if worst <= 0.0:
        raise NoUnsafeMovement(f"no PB of the model generates unsafe movement (exploration {seed})")
    unsafe = found.pb[found.share >= worst - 1e-9]
    rng = np.random.default_rng([seed, 2])
    parts = []
    for _ in range(-(-n_steps // each)):
        pb = unsafe[rng.integers(len(unsafe))][None]
        contexts, inputs = sample_starts(model, 1, config, rng)
        hands = generate_from(model, pb, contexts, inputs, config.transient + each, sensory=True)
        parts.append(hands[config.transient :, 0])
    return np.clip(np.concatenate(parts)[:n_steps], 0.0, 1.0)


@dataclass(frozen=True)
class SafetySeeds:
    """The study's seeds: the model's learning and the map's exploration (``model``), the
    users whose sessions the map learns from (``map_users``, one per kind in :data:`USERS`
    order), those measured (``users``, likewise), the person performing the learned patterns
    (``learned``), the held-out exploration judging the map's prediction (``held_out``) and
    the never-experienced PBs judging its familiarity (``unknown``)."""

    model: int
    map_users: tuple[int, ...]
    users: tuple[int, ...]
    learned: int
    held_out: int
    unknown: int

    @classmethod
    def from_first(cls, seed: int) -> SafetySeeds:
        """``--seed``'s: the model, exploration and map users from ``seed`` on, the measured
        users from ``seed + 1000`` on, the learned patterns' person 7, the held-out
        exploration ``seed + 2000``, the unknown PBs ``seed + 3000``."""
        return cls(
            seed,
            tuple(seed + k for k in range(len(USERS))),
            tuple(seed + 1000 + k for k in range(len(USERS))),
            7,
            seed + 2000,
            seed + 3000,
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
            exam.seed_list("held_out")[0],
            exam.seed_list("unknown")[0],
        )


def study_models(
    directory: str | None, config: SafetyStudyConfig, seed: int, out: Path
) -> dict[str, Any]:
    """Each learning set's model and where it came from: ``directory``'s ``setK.npz`` (a
    missing one is a clear error), or learned into ``out`` with the paper's algorithm (the
    quick form with fewer iterations): the fast preset's models never generate unsafe
    movement on their own, so there would be nothing for the meta-level to know."""
    from rnnpb.model import TrainedModel

    def learning(name: str):
        train = shared.paper_training(name, seed=seed)
        if config.train_iterations is not None:
            train = replace(train, iterations=config.train_iterations)
        return train

    paths = shared.study_models(config.sets, directory, out, learning, seed)
    source = None if directory is not None else "learned here (the paper's algorithm)"
    return {name: (TrainedModel.load(path), source or path) for name, path in paths.items()}


# --- one session ---------------------------------------------------------------------------


def session_job(
    model_path: str, meta, online, arm: str, stream: np.ndarray, label: str
) -> dict[str, Any]:
    """One user's stream through one arm (:data:`ARMS`): per step the regime, the PB, the
    command generated, the command after inhibition, the one sent (after the filter, in
    ``everything``), why each was unsafe and the cause of the generated one."""
    from rnnpb.model import MirrorSystem, TrainedModel
    from rnnpb.robot import ELBOW_AT_ZERO_PITCH
    from rnnpb.safety import Attribution, CommandFilter, SafetyChecker

    model = TrainedModel.load(model_path)
    if arm == "unguarded":
        mirror = MirrorSystem(model, online)
    else:
        mirror = MirrorSystem(
            model, online, meta=meta, steering="pb_driven", inhibition=arm == "everything"
        )
    rest = np.array([0.0, 0.0, 0.0, ELBOW_AT_ZERO_PITCH] * 2)
    checker = SafetyChecker()
    command_filter = CommandFilter(checker, initial=rest) if arm == "everything" else None
    attribution = Attribution(checker)
    rows: dict[str, list[Any]] = {
        k: []
        for k in (
            "regime",
            "pb",
            "inhibited",
            "generated_unsafe",
            "cause",
            "commanded_unsafe",
            "sent_unsafe",
            "recognised",
        )
    }
    before = sent_before = rest
    sents = []
    for u in stream:
        result = mirror.step(u)
        generated = result.generated if result.generated is not None else result.motor
        why = _physical(checker.command_reasons(before, generated))
        rows["generated_unsafe"].append(why)
        rows["commanded_unsafe"].append(_physical(checker.command_reasons(before, result.motor)))
        sent = result.motor
        if command_filter is not None:
            sent = command_filter(result.motor).command
        rows["sent_unsafe"].append(_physical(checker.command_reasons(sent_before, sent)))
        sents.append(sent)
        rows["regime"].append(result.regime)
        rows["pb"].append(result.pb)
        rows["inhibited"].append(bool(result.inhibited))
        rows["recognised"].append(result.recognised or "")
        before, sent_before = result.motor, sent
    rows["cause"] = attribution.attribute_sequence(stream, rows["generated_unsafe"])
    rows["sent_judged"] = judged_commands(np.array(sents).reshape(-1, 8), rest, model.dt)
    out: dict[str, Any] = {k: np.array(v) for k, v in rows.items()}
    out["label"], out["arm"] = label, arm
    return out


def judged_commands(commands: np.ndarray, previous: np.ndarray, dt: float) -> list[str]:
    """Why each command of a path (T, 8), sent after ``previous``, is unsafe by the judges
    that share nothing with the safety module (:mod:`rnnpb.analysis.judges`): ``collision``
    (MuJoCo's contacts at the posture or on the way to it), ``speed`` (further than the
    servo turns in ``dt``), ``limits`` (outside the MJCF's ranges); "" for a safe one."""
    from rnnpb.analysis.judges import CollisionJudge, judge_limits, judge_speed

    reasons: list[list[str]] = [[] for _ in commands]
    if not len(commands):
        return []
    verdicts = (
        ("collision", CollisionJudge().judge(commands, previous).colliding),
        ("speed", judge_speed(commands, dt, previous).too_fast),
        ("limits", judge_limits(commands).outside),
    )
    for name, steps in verdicts:
        for t in steps:
            reasons[t].append(name)
    return [" ".join(r) for r in reasons]


def _physical(reasons: list[str]) -> str:
    return " ".join(w for w in reasons if w.split(":")[0] in PHYSICAL)


# --- the map ---------------------------------------------------------------------------------


def learn_map(pool, model, model_path: Path, config, online, seeds: SafetySeeds, set_name: str):
    """The safety map of ``model`` (saved beside ``model_path``): explored, and the PBs lived
    through in unguarded sessions of the map's users and the learned patterns (their own
    generation from many starts)."""
    from rnnpb.safety import ExplorationConfig, learn_safety_map, safety_map_path

    streams = _streams(model, config, seeds.map_users, seeds.model + 500, set_name)
    jobs = [
        pool.submit(session_job, str(model_path), None, online, "unguarded", s, label)
        for label, s in streams.items()
    ]
    lived = np.concatenate([job.result()["pb"][:: config.lived_every] for job in jobs])
    exploration = ExplorationConfig(samples=config.samples, starts=config.starts, seed=seeds.model)
    maps = learn_safety_map(model, exploration, lived=lived)
    maps.save(safety_map_path(model_path))
    return maps


class NoUnsafeMovement(ConfigError):
    """The model's generation is never unsafe where the unsafe-pattern user looked."""


def _streams(model, config, user_seeds, learned_seed: int, set_name: str) -> dict[str, Any]:
    """Every user's stream and the learned patterns'. A model that generates no unsafe
    movement has no unsafe-pattern user: that kind is left out, said on stderr, and the
    report names it (``absent_users``)."""
    streams = {}
    for user, seed in zip(USERS, user_seeds, strict=True):
        try:
            streams[user] = user_stream(user, config.steps, seed, set_name, model.patterns, model)
        except NoUnsafeMovement as error:
            print(f"  set {set_name}: no {user} user: {error}", file=sys.stderr, flush=True)
    for pattern in model.patterns:
        streams[f"learned_{pattern}"] = _pattern_stream(pattern, config.learned_steps, learned_seed)
    return streams


def prediction(model, maps, config, seeds: SafetySeeds) -> dict[str, Any]:
    """The map on PBs it never saw: held-out exploration (other PBs, other starts) labelled
    the same way, and the ROC AUC of the learned risk; the familiarity's AUC for PBs lived
    through in the measured sessions (experienced kinds of behaviour, new draws) against PBs
    drawn uniformly from the PB space (never experienced)."""
    from rnnpb.safety import ExplorationConfig, explore

    held = explore(
        model,
        ExplorationConfig(samples=config.held_out, starts=config.starts, seed=seeds.held_out),
    )
    risk = maps.risk(held.pb)
    return {
        "held_out": len(held.pb),
        "held_out_unsafe": int(held.unsafe.sum()),
        "risk_auc": roc_auc(risk, held.unsafe),
    }


def familiarity(maps, lived: np.ndarray, seed: int) -> dict[str, Any]:
    rng = np.random.default_rng(seed)
    unknown = rng.uniform(size=(len(lived), lived.shape[1]))
    scores = np.concatenate([maps.familiarity(lived), maps.familiarity(unknown)])
    labels = np.concatenate([np.ones(len(lived), bool), np.zeros(len(unknown), bool)])
    return {
        "lived": len(lived),
        "familiarity_auc": roc_auc(scores, labels),
        "lived_median": float(np.median(maps.familiarity(lived))),
        "unknown_median": float(np.median(maps.familiarity(unknown))),
    }


def roc_auc(scores: ArrayLike, labels: ArrayLike) -> float:
    """The area under the ROC curve of ``scores`` for the True ``labels`` (ties count half);
    NaN when one class is missing."""
    scores = np.asarray(scores, dtype=np.float64)
    labels = np.asarray(labels, bool)
    positive, negative = scores[labels], scores[~labels]
    if not len(positive) or not len(negative):
        return float("nan")
    order = np.argsort(np.concatenate([positive, negative]), kind="mergesort")
    ranks = np.empty(len(order))
    values = np.concatenate([positive, negative])[order]
    ranks[order] = np.arange(1, len(order) + 1)
    for value in np.unique(values):  # ties: the mean rank
        tied = np.concatenate([positive, negative]) == value
        if tied.sum() > 1:
            ranks[tied] = ranks[tied].mean()
    n_pos, n_neg = len(positive), len(negative)
    return float((ranks[:n_pos].sum() - n_pos * (n_pos + 1) / 2) / (n_pos * n_neg))


# --- the sessions measured -------------------------------------------------------------------


def run_sessions(pool, model, model_path, meta, config, online, seeds, set_name) -> dict:
    """Every measured user and learned pattern through every arm: (label, arm) → run."""
    streams = _streams(model, config, seeds.users, seeds.learned, set_name)
    jobs = {
        pool.submit(session_job, str(model_path), meta, online, arm, stream, label): (label, arm)
        for label, stream in streams.items()
        for arm in ARMS
    }
    runs = {}
    for future in as_completed(jobs):
        runs[jobs[future]] = future.result()
        print(
            f"  set {set_name}: {'/'.join(jobs[future])} done ({len(runs)}/{len(jobs)})",
            file=sys.stderr,
            flush=True,
        )
    return runs


def measure(runs: dict, maps, risk_level: float) -> dict[str, Any]:
    """The study's measures over the runs (:func:`run_sessions`)."""
    from rnnpb.model.meta import PB_DRIVEN
    from rnnpb.safety import GENERATION

    def pb_driven_unsafe(run, generation_only=False):
        driven = np.isin(run["regime"], list(PB_DRIVEN))
        unsafe = run["generated_unsafe"] != ""
        if generation_only:
            unsafe &= run["cause"] == GENERATION
        return int((driven & unsafe).sum())

    per_user: dict[str, dict[str, Any]] = {}
    totals = dict.fromkeys(
        (
            "steer_unguarded",
            "steer_steered",
            "steer_unguarded_generation",
            "steer_steered_generation",
            "inhibit_cases",
            "inhibit_prevented",
            "following_generation_unsafe",
            "following_generation_inhibited",
            "sent_unsafe",
            "sent_judged_unsafe",
            "learned_steps",
            "learned_inhibited",
        ),
        0,
    )
    for (label, arm), run in runs.items():
        row = per_user.setdefault(label, {})
        regimes, counts = np.unique(run["regime"], return_counts=True)
        row[arm] = {
            "steps": len(run["regime"]),
            "regimes": {str(r): int(c) for r, c in zip(regimes, counts, strict=True)},
            "generated_unsafe": int((run["generated_unsafe"] != "").sum()),
            "generated_unsafe_generation": int(
                ((run["generated_unsafe"] != "") & (run["cause"] == GENERATION)).sum()
            ),
            "pb_driven_unsafe": pb_driven_unsafe(run),
            "inhibited": int(run["inhibited"].sum()),
            "sent_unsafe": int((run["sent_unsafe"] != "").sum()),
            "sent_judged_unsafe": int((run["sent_judged"] != "").sum()),
        }
        if arm == "unguarded":
            totals["steer_unguarded"] += pb_driven_unsafe(run)
            totals["steer_unguarded_generation"] += pb_driven_unsafe(run, True)
        elif arm == "steered":
            totals["steer_steered"] += pb_driven_unsafe(run)
            totals["steer_steered_generation"] += pb_driven_unsafe(run, True)
        else:
            following = run["regime"] == "following"
            generation = (run["generated_unsafe"] != "") & (run["cause"] == GENERATION)
            in_region = maps.risk(run["pb"]) > risk_level
            cases = following & generation & in_region
            totals["inhibit_cases"] += int(cases.sum())
            totals["inhibit_prevented"] += int((cases & (run["commanded_unsafe"] == "")).sum())
            totals["following_generation_unsafe"] += int((following & generation).sum())
            totals["following_generation_inhibited"] += int(
                (following & generation & run["inhibited"]).sum()
            )
            totals["sent_unsafe"] += int((run["sent_unsafe"] != "").sum())
            totals["sent_judged_unsafe"] += int((run["sent_judged"] != "").sum())
            if label.startswith("learned_"):
                totals["learned_steps"] += len(run["regime"])
                totals["learned_inhibited"] += int(run["inhibited"].sum())
    return {"per_user": per_user, "totals": totals}


def learned_job(model_path: str, meta, online, arm: str, seed: int) -> dict[str, Any]:
    """Lock-on, recognition and switching of the learned patterns
    (:func:`rnnpb.experiments.paper.synchronization` and ``switching``, paper 3.1–3.2),
    unguarded or with everything on (steering, inhibition; the filter changes no command of
    a learned pattern, tests/safety)."""
    from rnnpb.experiments.paper import switching, synchronization
    from rnnpb.model import TrainedModel
    from rnnpb.robot import JOINT_LIMITS

    model = TrainedModel.load(model_path)
    on = arm == "everything"
    options = {
        "meta": meta if on else None,
        "steering": "pb_driven",
        "inhibition": on,
    }
    lock, recognised = {}, {}
    for pattern in model.patterns:
        sync = synchronization(model, pattern, online, JOINT_LIMITS, seed=seed, **options)
        lock[pattern] = sync.steps_to_lock
        recognised[pattern] = sync.recognized_pattern
    switch = switching(model, online, JOINT_LIMITS, seed=seed, **options).pairs
    return {"lock": lock, "recognised": recognised, "switch": switch}


def within_limits(cost: dict[str, Any], lock_steps: int, switch_steps: int) -> bool:
    """Whether every learned pattern locks on within ``lock_steps`` and switches within
    ``switch_steps`` with everything on, recognised as unguarded."""
    on, off = cost["everything"], cost["unguarded"]
    return (
        all(v is not None and v <= lock_steps for v in on["lock"].values())
        and all(v is not None and v <= switch_steps for v in on["switch"].values())
        and on["recognised"] == off["recognised"]
    )


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
