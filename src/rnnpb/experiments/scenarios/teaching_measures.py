"""The teach study's measures: what a run kept, how long its consolidations took, how soon the
robot followed, the paper's measures of a model, and the paced run's deadlines.

**Interaction time to follow** a new shape (:func:`follow_time`): the steps from its first
step until the episode is kept, plus the steps a paced loop runs while the consolidation
takes its time (the person keeps moving; the swap comes between two steps), plus the lock-on
steps on its next performance, at dt 0.4 s. The consolidation's time that enters is its
**CPU time on one core**: the loop and the consolidation each take a core of their own (the
machine the study runs on may be shared, so its wall time is the load's, reported beside).

**Deadlines** (:func:`paced_timing`): counted are the loop's missed deadlines (a step whose
work took longer than dt), the steps whose late start plus work ran past the end of their
slot, and the lateness of each step's start after its due time (jitter within the slot).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from itertools import permutations
from typing import Any

import numpy as np

from rnnpb.analysis import metrics
from rnnpb.experiments.reporting import fmt
from rnnpb.experiments.scenarios.teaching_scenario import UNSTRUCTURED_MOVEMENTS, TeachConfig
from rnnpb.interaction.teaching import episode_steps

LATE_S = 0.04
"""A step that starts more than this after its due time (a tenth of dt 0.4) is counted late:
the loop's own wait polls every 20 ms."""


@dataclass(frozen=True)
class KeptEpisode:
    """An episode the teacher kept: its id and name, the loop steps it spans, what the user
    did in them (step counts per movement) and the step it was kept at."""

    episode_id: int
    pattern: str
    first_step: int
    last_step: int
    kept_at: int
    movements: dict[str, int]

    @property
    def unstructured(self) -> bool:
        return any(m in UNSTRUCTURED_MOVEMENTS for m in self.movements)


@dataclass(frozen=True)
class ConsolidationTime:
    """One background consolidation: ``cpu_s`` of its process (user + system, from its start,
    forked with JAX imported, to its report; NaN if it ended without one), ``wall_s`` from its
    start to the swap, ``worker_s`` the time the process itself recorded (from loading the
    model to writing the memory)."""

    started_at: int
    cpu_s: float
    wall_s: float
    worker_s: float
    state: str


@dataclass(frozen=True)
class PaperMeasures:
    """The paper's measures of one model: lock-on from rest and recognition per pattern,
    steps to follow per ordered pair."""

    lock: dict[str, int | None]
    recognised: dict[str, str]
    switching: dict[str, int | None]

    def switching_among(self, patterns: tuple[str, ...]) -> dict[str, int | None]:
        """Steps to follow for the ordered pairs of ``patterns`` only."""
        return {
            k: v for k, v in self.switching.items() if all(p in patterns for p in k.split("->"))
        }


@dataclass(frozen=True)
class TeachRun:
    """One learning set taught one new shape."""

    learning_set: str
    shape: str
    dt: float
    new_pattern: str  # the name it was learned as ("" when nothing was learned)
    segments: list[tuple[str, int]]
    detection_delay: int | None  # steps from the new shape's start until "novel"
    episodes: list[KeptEpisode]
    consolidations: list[ConsolidationTime]
    swaps: list[int]
    lock_next: int | None  # lock-on to the new shape on its next performance, steps
    recognised_next: float  # share of its next performance's steps recognised as the new name
    lock_in_timeline: dict[str, int | None]  # each segment after the swap: lock-on, steps
    follow_s: float | None  # interaction time from its first step to following it
    follow_steps: dict[str, int]  # the parts of follow_s, in steps
    after: PaperMeasures | None
    loop_steps: int
    seconds: float
    timeline: dict[str, Any]

    @property
    def episodes_unstructured(self) -> int:
        return sum(e.unstructured for e in self.episodes)

    def to_json(self) -> dict[str, Any]:
        """The run as ``results.json`` holds it: the motor error beside the timeline."""
        out = asdict(self)
        out.pop("timeline")
        out["timeline"] = {k: v for k, v in self.timeline.items() if k != "motor_error"}
        out["motor_error"] = self.timeline["motor_error"]
        return out

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> TeachRun:
        """The run :meth:`to_json` wrote."""
        fields = {key: value for key, value in data.items() if key != "motor_error"}
        return cls(
            **{
                **fields,
                "segments": [tuple(s) for s in data["segments"]],
                "episodes": [KeptEpisode(**e) for e in data["episodes"]],
                "consolidations": [ConsolidationTime(**c) for c in data["consolidations"]],
                "after": PaperMeasures(**data["after"]) if data["after"] else None,
                "timeline": {**data["timeline"], "motor_error": data.get("motor_error", [])},
            }
        )


@dataclass(frozen=True)
class PacedRun:
    """The paced run at dt 0.4 during a background consolidation and the swap."""

    learning_set: str
    shape: str
    steps: int
    dt: float
    missed_deadlines: int
    late_steps: int
    overrun_steps: int  # steps whose late start plus work ran past the end of their slot
    max_lateness_ms: float
    p99_step_ms: float
    max_step_ms: float
    consolidation_steps: int | None  # steps the loop ran while the consolidation did
    consolidation: ConsolidationTime | None
    swap_step: int | None
    lock_after_swap: int | None
    swap_step_ms: float | None  # the first step with the new model: its work

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> PacedRun:
        """The paced run as ``results.json`` holds it."""
        consolidation = data["consolidation"]
        return cls(
            **{
                **data,
                "consolidation": ConsolidationTime(**consolidation) if consolidation else None,
            }
        )


def kept_episodes(memory, teacher, labels: list[str]) -> list[KeptEpisode]:
    """The episodes ``teacher`` kept in ``memory``, with what the user did in their steps."""
    kept_at = {e.episode_id: e.step for e in teacher.events if e.kind == "kept"}
    out = []
    for episode in memory.episodes():
        steps = episode_steps(episode.note)
        if steps is None:  # not kept by this study's teacher: it writes every episode's steps
            continue
        first, last = steps
        movements: dict[str, int] = {}
        for label in labels[first : last + 1]:
            movements[label] = movements.get(label, 0) + 1
        out.append(
            KeptEpisode(
                episode.id,
                episode.pattern,
                first,
                last,
                kept_at.get(episode.id, last),
                movements,
            )
        )
    return out


def segment_locks(motor_error, sensory_error, segments, after: int) -> dict[str, int | None]:
    """Lock-on in each segment that starts after step ``after`` (key ``k:movement``)."""
    out, start = {}, 0
    for k, (movement, n) in enumerate(segments):
        if start >= after and movement not in UNSTRUCTURED_MOVEMENTS:
            out[f"{k}:{movement}"] = metrics.steps_to_lock(
                motor_error, sensory_error, start, start + n
            )
        start += n
    return out


def paper_measures(model, config: TeachConfig, new_pattern: str = "") -> PaperMeasures:
    """Lock-on from rest per pattern and switching per ordered pair, as the paper measures
    them (``switching_pairs`` "new": only the pairs with ``new_pattern``)."""
    from rnnpb.demonstrator import switch_scenario
    from rnnpb.experiments.paper import run_scenario, switching, synchronization
    from rnnpb.model.consolidation import model_joint_limits

    limits = model_joint_limits(model)
    lock, recognised = {}, {}
    for name in model.patterns:
        # A learned new shape is performed by the demonstrator under its shape's name.
        sync = synchronization(
            model,
            shape_of(model, name),
            config.online,
            limits,
            seed=config.scenario_seed,
            before=config.sync_before,
            after=config.sync_before // 2,
        )
        lock[name] = sync.steps_to_lock
        recognised[name] = sync.recognized_pattern
    if config.switching_pairs == "all" or not new_pattern:
        # switching() names the demonstrator's movements by the model's pattern names.
        if all(shape_of(model, p) == p for p in model.patterns):
            pairs = switching(
                model,
                config.online,
                limits,
                seed=config.scenario_seed,
                steps_each=config.switch_steps_each,
            ).pairs
            return PaperMeasures(lock, recognised, pairs)
    pairs = {}
    for a, b in permutations(model.patterns, 2):
        if config.switching_pairs == "new" and new_pattern not in (a, b):
            continue
        scenario = switch_scenario(
            (shape_of(model, a), shape_of(model, b)),
            steps_each=config.switch_steps_each,
            seed=config.scenario_seed,
        )
        run = run_scenario(model, scenario, config.online, limits)
        pairs[f"{a}->{b}"] = metrics.steps_to_lock(
            run.motor_error, run.sensory_error, config.switch_steps_each
        )
    return PaperMeasures(lock, recognised, pairs)


def shape_of(model, pattern: str) -> str:
    """The demonstrator's movement a pattern of ``model`` was learned from: a taught pattern
    (``new-N``) records its shape in ``meta["taught"]``, the others are the demonstrator's."""
    return model.meta.get("taught", {}).get(pattern, pattern)


def worst(values) -> int | None:
    """The largest of some step counts; None (never) when there are none or one is None."""
    values = list(values)
    return None if not values or any(v is None for v in values) else max(values)


def most_performed(episode: KeptEpisode) -> str:
    """The movement the user performed on most of an episode's steps."""
    return max(episode.movements, key=episode.movements.__getitem__)


def detection_delay(novelty: list[str], start: int, steps: int) -> int | None:
    """Steps from ``start`` until the detector first says ``novel``, within ``steps``."""
    return next((t - start for t in range(start, start + steps) if novelty[t] == "novel"), None)


def follow_time(
    first_kept: KeptEpisode | None,
    consolidation: ConsolidationTime | None,
    lock_next: int | None,
    new_start: int,
    dt: float,
) -> tuple[float | None, dict[str, int]]:
    """The interaction time to follow a new shape that started at step ``new_start`` (module
    doc), and its parts in steps; None when it was not kept, consolidated and locked onto."""
    if first_kept is None or consolidation is None or lock_next is None:
        return None, {}
    steps = {
        "until_kept": first_kept.kept_at - new_start + 1,
        "consolidation": math.ceil(consolidation.cpu_s / dt),
        "lock_on": lock_next,
    }
    return sum(steps.values()) * dt, steps


def paced_timing(records, dt: float) -> dict[str, Any]:
    """The deadlines of a paced run's steps (module doc): the late and overrunning steps, the
    latest start and each step's work (ms; ``work_ms`` per step)."""
    starts = np.array([r.time_s for r in records])
    lateness = np.maximum(np.diff(starts) - dt, 0.0) if len(starts) > 1 else np.zeros(0)
    work = np.array([sum(r.timings.values()) for r in records]) * 1e3
    n = len(records)
    return {
        "late_steps": int(np.sum(lateness > LATE_S)),
        "overrun_steps": int(np.sum(lateness + work[1:] / 1e3 > dt)) if n > 1 else 0,
        "max_lateness_ms": float(lateness.max() * 1e3) if len(lateness) else 0.0,
        "p99_step_ms": float(np.percentile(work, 99)) if n else 0.0,
        "max_step_ms": float(work.max()) if n else 0.0,
        "work_ms": work,
    }


def old_pattern_misses(
    runs: list[TeachRun], lock: float, switch: float
) -> tuple[list[int | None], list[int | None], list[str]]:
    """The old patterns' lock-ons and switches after teaching, over ``runs``, and those beyond
    ``lock`` and ``switch`` steps (or never), in words; a run that learned nothing is a miss.
    Without the paper's measures (the quick form) a run's old patterns are judged by their
    lock-on in the timeline after the swap."""

    def locked(v: int | None) -> bool:
        return v is not None and v <= lock

    locks, switches, misses = [], [], []
    for run in runs:
        where = f"set {run.learning_set}"
        if not run.new_pattern:
            misses.append(f"{where} {run.shape}: nothing learned")
            continue
        if run.after is None:
            for segment, v in run.lock_in_timeline.items():
                if segment.split(":", 1)[1] != run.shape:
                    locks.append(v)
                    if not locked(v):
                        misses.append(f"{where}: lock {segment} {fmt(v)}")
            continue
        old = tuple(p for p in run.after.lock if p != run.new_pattern)
        for p in old:
            locks.append(run.after.lock[p])
            if not locked(run.after.lock[p]):
                misses.append(f"{where} {run.shape}: lock {p} {fmt(run.after.lock[p])}")
        for pair, v in run.after.switching_among(old).items():
            switches.append(v)
            if v is None or v > switch:
                misses.append(f"{where} {run.shape}: switch {pair} {fmt(v)}")
    return locks, switches, misses
