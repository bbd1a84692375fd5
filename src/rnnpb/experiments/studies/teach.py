"""``rnnpb study teach``: teaching by showing, end to end (paper 4.1; docs/teaching.md).

A scripted user stands in front of the robot and performs, one after another: a learned
pattern; a new shape the robot never learned, for several cycles; the other learned patterns;
unstructured movement (a random walk, then jerky movement); and the new shape again. The
interaction loop runs with the :class:`rnnpb.interaction.teaching.Teacher` subscribed, as fast
as possible — so the loop waits between two steps for each consolidation, and the run repeats.
Per learning set (1–4 and the larger set) and new shape of the demonstrator
(:data:`rnnpb.demonstrator.NEW_SHAPES`):

- the timeline (figure): what the user does, the novelty word, the pattern recognised, the
  episode cutter's state, the motor error, where the episode was kept, the consolidation and
  the swap;
- the detection delay (steps from the new shape's first step until the detector says
  ``novel``), the episode kept (its steps and what the user did in them), the consolidation's
  time — CPU time of the background process (all of it: start, imports, compilation,
  rehearsal, learning, writing) and wall time;
- after learning: the lock-on to the new shape on its next performance (the steps from its
  start until the robot is locked on, :func:`rnnpb.analysis.metrics.steps_to_lock`), the
  paper's lock-on from rest (:func:`rnnpb.experiments.paper.synchronization`) for every
  pattern of the new model and switching for every ordered pair
  (:func:`rnnpb.experiments.paper.switching`), against the same measures of the model before;
- the episodes kept from the unstructured part (the target: none).

**Interaction time to follow** a new shape: the steps from its first step until the episode is
kept, plus the steps a paced loop runs while the consolidation takes its time (the person
keeps moving; the swap comes between two steps), plus the lock-on steps on its next
performance, at dt 0.4 s. The consolidation's time that enters is its **CPU time on one
core**: the loop and the consolidation each take a core of their own (the machine the study
runs on is shared, so its wall time is the load's, and is reported beside it).

**Deadlines** are measured in a real paced run at dt 0.4: the loop plays the new shape held
while the background process consolidates the kept episode of one run, and the new model is
swapped in between two steps; counted are the loop's missed deadlines (a step whose work took
longer than dt), the steps whose late start plus work ran past the end of their slot (the
deadline the target judges), and the lateness of each step's start after its due time
(jitter within the slot, reported beside).

Models: the full form reads the paper-learned models of ``rnnpb demo`` from ``--models DIR``
(default :data:`DEFAULT_MODELS`): ``set1.npz`` … ``set4.npz`` and the larger set's
``full.npz`` or ``full_seed0.npz``; they are copied into ``OUT/runs/`` and never written. The
quick form teaches the shipped fast-preset model of learning set 1 one shape.
"""

from __future__ import annotations

import math
import resource
import shutil
import time
from concurrent.futures import Future, as_completed
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb.analysis import metrics
from rnnpb.errors import ConfigError
from rnnpb.experiments.reporting import embed, fmt, table, versions, write_outputs
from rnnpb.experiments.studies import StudyOptions, StudyOutcome, demo_model_names
from rnnpb.experiments.studies._pool import study_pool
from rnnpb.experiments.summary import Target
from rnnpb.interaction.teaching import TeachingConfig, episode_steps
from rnnpb.model import OnlineConfig

NAME = "teach"
SUMMARY = "teach a new shape on-line: notice it, keep it, consolidate it while moving, follow it"

DEFAULT_MODELS = Path("results/demo/models")
"""Where the full form finds its models when ``--models`` names none: `rnnpb demo`'s output."""
FOLLOW_LIMIT_S = 90.0
"""Interaction time from a new shape's first cycle until the robot follows it (the issue)."""
LATE_S = 0.04
"""A step that starts more than this after its due time (a tenth of dt 0.4) is counted late:
the loop's own wait polls every 20 ms."""
UNSTRUCTURED_MOVEMENTS = ("random-walk", "jerky")
PERIOD = 12  # the demonstrator's period, steps (PatternConfig.period_steps)


@dataclass(frozen=True)
class TeachConfig:
    """What the study runs.

    ``models``: the directory of the starting models (full form); ``shipped``: teach the
    shipped fast-preset model instead (quick form). ``consolidation_iterations``: None keeps
    the consolidation's own default (:data:`rnnpb.model.consolidation.CONSOLIDATION_ITERATIONS`),
    so that what improves there is what this study measures. The scripted user: ``lead_steps``
    of a learned pattern, ``new_steps`` of the new shape, ``other_steps`` of each other
    learned pattern, ``unstructured_steps`` of each unstructured movement, ``again_steps`` of
    the new shape again. ``paced``: the (learning set, shape) whose kept episode is
    consolidated again during a paced run; ``paced_max_steps`` ends that run early (the
    consolidation is then cancelled: the quick form), else it ends ``paced_after_swap`` steps
    after the swap.
    """

    quick: bool = False
    models: str | None = str(DEFAULT_MODELS)
    shipped: bool = False
    learning_sets: tuple[str, ...] = ("1", "2", "3", "4", "full")
    shapes: tuple[str, ...] = ("figure-eight", "diagonal", "one-arm", "asymmetric")
    online: OnlineConfig = field(default_factory=OnlineConfig)
    teaching: TeachingConfig = field(default_factory=TeachingConfig)
    consolidation_iterations: int | None = None
    dt: float = 0.4
    lead_steps: int = 36
    new_steps: int = 96
    other_steps: int = 36
    unstructured_steps: int = 60
    again_steps: int = 48
    scenario_seed: int = 100
    # The paper's measures after learning: the demo's 75 steps before the pause; switching is
    # judged within 15 steps, so 30 of each pattern (the demo's 50) still show "never".
    sync_before: int = 75
    switch_steps_each: int = 30
    switching_pairs: str = "all"  # "all", or "new": the pairs with the new pattern only
    # The paper's measures before and after teaching (the quick form judges the old patterns
    # by their lock-on in the timeline only).
    paper_measures: bool = True
    paced: tuple[str, str] | None = ("1", "figure-eight")
    paced_max_steps: int | None = None
    paced_after_swap: int = 36
    workers: int = 2

    def __post_init__(self) -> None:
        from rnnpb.demonstrator import NEW_SHAPES, learning_set_patterns

        for name in self.learning_sets:
            learning_set_patterns(name)
        unknown = [s for s in self.shapes if s not in NEW_SHAPES]
        if unknown or not self.shapes or not self.learning_sets:
            raise ConfigError(
                f"the study teaches new shapes of the demonstrator ({', '.join(NEW_SHAPES)}) "
                f"to one or more learning sets; got shapes {self.shapes}"
            )
        if self.switching_pairs not in ("all", "new"):
            raise ConfigError(f"switching_pairs must be 'all' or 'new', got {self.switching_pairs}")
        if self.new_steps < 4 * PERIOD or self.again_steps < 2 * PERIOD:
            raise ConfigError("the new shape needs time: new_steps >= 48, again_steps >= 24")

    @classmethod
    def quick_run(cls, seed: int = 0) -> TeachConfig:
        """The shipped model of learning set 1, one shape, the pairs with the new pattern;
        the paced run stops (and cancels its consolidation) after 8 steps."""
        return cls(
            quick=True,
            models=None,
            shipped=True,
            learning_sets=("1",),
            shapes=("figure-eight",),
            online=OnlineConfig.ungated(),
            scenario_seed=100 + seed,
            other_steps=30,
            unstructured_steps=40,
            again_steps=36,
            sync_before=36,
            switch_steps_each=30,
            switching_pairs="new",
            paper_measures=False,
            paced_max_steps=8,
            workers=1,
        )


# --- results --------------------------------------------------------------------------------


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
    """One background consolidation: ``cpu_s`` of its process (user + system, from the
    process's start to its end), ``wall_s`` from its start to the swap, ``worker_s`` the time
    the process itself recorded (from loading the model to writing the memory)."""

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


@dataclass(frozen=True)
class TeachRun:
    """One learning set taught one new shape."""

    learning_set: str
    shape: str
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


# --- running ---------------------------------------------------------------------------------


def _children_cpu() -> float:
    """CPU seconds of this process's finished and reaped children (the consolidations)."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _segments(patterns: tuple[str, ...], shape: str, index: int, config: TeachConfig):
    lead = patterns[index % len(patterns)]
    others = [p for p in patterns if p != lead]
    return [
        (lead, config.lead_steps),
        (shape, config.new_steps),
        *((p, config.other_steps) for p in others),
        *((m, config.unstructured_steps) for m in UNSTRUCTURED_MOVEMENTS),
        (shape, config.again_steps),
    ]


def _spec(segments) -> str:
    return "scenario:steps:" + ",".join(f"{m}*{n}" for m, n in segments)


class _Watch:
    """Around a Teacher: times each consolidation (CPU of its process, wall) and records the
    cutter's state and the consolidation per step."""

    def __init__(self, teacher, loop) -> None:
        self.teacher = teacher
        self.loop = loop
        self.records: list = []
        self.cutter: list[str] = []
        self.times: list[tuple[int, float, float, float]] = []  # (step, cpu, wall, worker)
        self._started: tuple[int, float, float] | None = None
        self.stop_after: int | None = None
        self.step_limit: int | None = None
        self._ending: list = []  # (job, step, cpu, wall) of consolidations whose process ends

    def started(self) -> None:
        """A consolidation was started outside a step (confirmed before the run)."""
        self._started = (self.loop.steps, _children_cpu(), time.perf_counter())

    def on_step(self, record) -> None:
        self.records.append(record)
        self.cutter.append(self.teacher.keeper.cutter.status.state)
        if self.teacher.job is not None and self._started is None:
            self._started = (self.loop.steps, _children_cpu(), time.perf_counter())

    def _record_ended(self, block: bool = False) -> None:
        """A finished consolidation's CPU time counts among the children's once its process
        has ended and been reaped, a moment after it reported: recorded then, without
        holding up the loop (``block``: after the run, wait for it)."""
        for item in list(self._ending):
            job, step, cpu, wall = item
            process = getattr(job, "_process", None)
            if process is not None and block:
                process.join(120.0)
            if process is None or not process.is_alive():
                self._ending.remove(item)
                self.times.append((step, _children_cpu() - cpu, wall, job.state.seconds))

    def finish(self) -> None:
        """After the run: the consolidations still ending are waited for and recorded."""
        self._record_ended(block=True)

    def between_steps(self, wait_s: float) -> None:
        job = self.teacher.job
        self.teacher.between_steps(wait_s)
        if job is not None and self.teacher.job is None and self._started is not None:
            step, cpu, wall = self._started
            self._started = None
            self._ending.append((job, step, cpu, time.perf_counter() - wall))
        self._record_ended()
        if self.stop_after is not None and self.loop.steps >= self.stop_after:
            self.loop.stop()
        if self.step_limit is not None and self.loop.steps >= self.step_limit:
            self.loop.stop()


def _episodes(memory, teacher, labels) -> list[KeptEpisode]:
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


def _locks(motor_error, sensory_error, segments, after: int) -> dict[str, int | None]:
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
            _shape_of(model, name),
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
        if all(_shape_of(model, p) == p for p in model.patterns):
            pairs = switching(
                model,
                config.online,
                limits,
                seed=config.scenario_seed,
                steps_each=config.switch_steps_each,
            ).pairs
            return PaperMeasures(lock, recognised, pairs)
    pairs = {}
    from itertools import permutations

    for a, b in permutations(model.patterns, 2):
        if config.switching_pairs == "new" and new_pattern not in (a, b):
            continue
        scenario = switch_scenario(
            (_shape_of(model, a), _shape_of(model, b)),
            steps_each=config.switch_steps_each,
            seed=config.scenario_seed,
        )
        run = run_scenario(model, scenario, config.online, limits)
        pairs[f"{a}->{b}"] = metrics.steps_to_lock(
            run.motor_error, run.sensory_error, config.switch_steps_each
        )
    return PaperMeasures(lock, recognised, pairs)


def _shape_of(model, pattern: str) -> str:
    """The demonstrator's movement a pattern of ``model`` was learned from: a taught pattern
    (``new-N``) records its shape in ``meta["taught"]``, the others are the demonstrator's."""
    return model.meta.get("taught", {}).get(pattern, pattern)


def teach_job(
    set_name: str, shape: str, index: int, start_path: str, config: TeachConfig, folder: str
) -> TeachRun:
    """One learning set taught one shape, as fast as possible (module doc)."""
    from rnnpb import _xla
    from rnnpb.demonstrator import ScenarioSource, learning_set_patterns, make_scenario
    from rnnpb.interaction import InteractionLoop, LoopConfig
    from rnnpb.interaction.teaching import Teacher
    from rnnpb.memory import MemoryStore
    from rnnpb.model import MirrorSystem, TrainedModel
    from rnnpb.model.consolidation import model_joint_limits

    _xla.configure()
    began = time.perf_counter()
    run_dir = Path(folder)
    if run_dir.exists():
        shutil.rmtree(run_dir)  # a run repeats: no versions or memory of an earlier one
    run_dir.mkdir(parents=True)
    path = run_dir / "model.npz"
    shutil.copyfile(start_path, path)
    model = TrainedModel.load(path)
    segments = _segments(learning_set_patterns(set_name), shape, index, config)
    scenario = make_scenario(segments, seed=config.scenario_seed + index)
    online = config.online
    with ScenarioSource(scenario) as source, MemoryStore(path) as memory:
        loop = InteractionLoop(MirrorSystem(model, online), source, config=LoopConfig(config.dt))
        teacher = Teacher(
            loop,
            path,
            memory,
            make_mirror=lambda m: MirrorSystem(m, online),
            source=_spec(segments),
            config=config.teaching,
            iterations=config.consolidation_iterations,
        )
        watch = _Watch(teacher, loop)
        loop.run(on_step=watch.on_step, between_steps=watch.between_steps)
        if teacher.job is not None:  # kept on the last step: consolidate before measuring
            watch.between_steps(0.0)
        watch.finish()
        labels = list(scenario.labels)
        episodes = _episodes(memory, teacher, labels)
    records = watch.records
    limits = model_joint_limits(model)
    motor_error = metrics.motor_error(np.array([r.motor for r in records]), scenario.motor, limits)
    sensory_error = metrics.sensory_error(
        np.array([r.predicted for r in records]), np.array([r.observed for r in records])
    )
    new_start = config.lead_steps
    novelty = [r.novelty for r in records]
    delay = next(
        (
            t - new_start
            for t in range(new_start, new_start + config.new_steps)
            if novelty[t] == "novel"
        ),
        None,
    )
    final = TrainedModel.load(teacher.model_path)
    new_names = [p for p in final.patterns if p not in model.patterns]
    # The episodes of the new shape: most of their steps are the shape's.
    from_shape = [e for e in episodes if max(e.movements, key=e.movements.get) == shape]
    new_pattern = next((e.pattern for e in from_shape if e.pattern in new_names), "")
    if new_pattern:
        # Which demonstrator movement each taught pattern is, for the paper's measures.
        taught = {e.pattern: max(e.movements, key=e.movements.get) for e in episodes}
        final = replace(final, meta={**final.meta, "taught": taught})
    again_start = len(labels) - config.again_steps
    lock_next = metrics.steps_to_lock(motor_error, sensory_error, again_start, len(labels))
    recognised_next = (
        float(np.mean([r.recognised == new_pattern for r in records[again_start:]]))
        if new_pattern
        else 0.0
    )
    consolidations = [
        ConsolidationTime(
            step, cpu, wall, worker, "done" if k < len(teacher.swapped_at) else "failed"
        )
        for k, (step, cpu, wall, worker) in enumerate(watch.times)
    ]
    follow_s, follow_steps = None, {}
    first_kept = min(from_shape, key=lambda e: e.kept_at, default=None)
    if first_kept is not None and consolidations and lock_next is not None:
        consolidation = consolidations[0]
        follow_steps = {
            "until_kept": first_kept.kept_at - new_start + 1,
            "consolidation": math.ceil(consolidation.cpu_s / config.dt),
            "lock_on": lock_next,
        }
        follow_s = sum(follow_steps.values()) * config.dt
    swap = teacher.swapped_at[0] if teacher.swapped_at else len(labels)
    timeline = {
        "movement": labels,
        "novelty": novelty,
        "recognised": [r.recognised or "" for r in records],
        "cutter": watch.cutter,
        "motor_error": motor_error,
        "kept": [(e.first_step, e.last_step, e.kept_at) for e in episodes],
        "consolidations": [
            (
                c.started_at,
                f"consolidation {c.cpu_s:.0f} s CPU, {c.wall_s:.0f} s wall "
                f"(= {math.ceil(c.cpu_s / config.dt)} steps paced)",
            )
            for c in consolidations
        ],
        "swaps": list(teacher.swapped_at),
        "unstructured": list(UNSTRUCTURED_MOVEMENTS),
        # The movement each newly learned pattern was taught from (its colour in the figure).
        "taught": {
            e.pattern: max(e.movements, key=e.movements.get)
            for e in episodes
            if e.pattern in new_names
        },
    }
    return TeachRun(
        learning_set=set_name,
        shape=shape,
        new_pattern=new_pattern,
        segments=segments,
        detection_delay=delay,
        episodes=episodes,
        consolidations=consolidations,
        swaps=list(teacher.swapped_at),
        lock_next=lock_next,
        recognised_next=recognised_next,
        lock_in_timeline=_locks(motor_error, sensory_error, segments, swap),
        follow_s=follow_s,
        follow_steps=follow_steps,
        after=(
            paper_measures(final, config, new_pattern)
            if new_pattern and config.paper_measures
            else None
        ),
        loop_steps=len(records),
        seconds=time.perf_counter() - began,
        timeline=timeline,
    )


def before_job(set_name: str, start_path: str, config: TeachConfig) -> tuple[str, PaperMeasures]:
    """The paper's measures of a starting model, to compare with after teaching."""
    from rnnpb import _xla
    from rnnpb.model import TrainedModel

    _xla.configure()
    return set_name, paper_measures(TrainedModel.load(start_path), config)


def paced_job(
    set_name: str, shape: str, run_folder: str, start_path: str, config: TeachConfig, folder: str
) -> PacedRun:
    """At dt 0.4, paced: the user keeps performing ``shape`` while the episode the fast run
    kept is consolidated again in the background, and the new model is swapped in."""
    from rnnpb import _xla
    from rnnpb.demonstrator import ScenarioSource, make_scenario
    from rnnpb.interaction import InteractionLoop, LoopConfig
    from rnnpb.interaction.teaching import Teacher
    from rnnpb.memory import MemoryStore
    from rnnpb.model import MirrorSystem, TrainedModel
    from rnnpb.model.consolidation import model_joint_limits

    _xla.configure()
    run_dir = Path(folder)
    if run_dir.exists():
        shutil.rmtree(run_dir)
    run_dir.mkdir(parents=True)
    path = run_dir / "model.npz"
    shutil.copyfile(start_path, path)
    model = TrainedModel.load(path)
    with MemoryStore(Path(run_folder) / "model.npz", create=False) as taught:
        episode = next(e for e in taught.episodes() if e.pattern == "new-1")
        movement = taught.episode(episode.id)
    scenario = make_scenario([(shape, 120)], seed=config.scenario_seed + 7)
    online = config.online
    with ScenarioSource(scenario, loop=True) as source, MemoryStore(path) as memory:
        episode_id = memory.add_episode(
            movement.sensory,
            movement.motor,
            source=movement.summary.source,
            model=str(path),
            pattern=movement.summary.pattern,
            n_cycles=movement.summary.n_cycles,
            note=movement.summary.note,
        )
        mirror = MirrorSystem(model, online)
        loop = InteractionLoop(mirror, source, config=LoopConfig(config.dt, paced=True))
        # Compiled before the clock starts, as a session's first step would be at its start.
        mirror.step(scenario.sensory[0])
        mirror.reset()
        teacher = Teacher(
            loop,
            path,
            memory,
            make_mirror=lambda m: MirrorSystem(m, online),
            source="paced",
            config=config.teaching,
            auto=False,
            iterations=config.consolidation_iterations,
        )
        watch = _Watch(teacher, loop)
        watch.step_limit = config.paced_max_steps
        teacher.pending.append(episode_id)
        teacher.confirm()
        watch.started()

        def between(wait_s: float) -> None:
            watch.between_steps(wait_s)
            if teacher.swapped_at and watch.stop_after is None:
                watch.stop_after = teacher.swapped_at[0] + config.paced_after_swap
            elif teacher.job is None and not teacher.swapped_at:
                loop.stop()  # the consolidation failed: nothing more to measure

        loop.run(on_step=watch.on_step, between_steps=between)
        if teacher.job is not None:
            teacher.job.cancel()
        watch.finish()
        summary = loop.summary()
    records = watch.records
    starts = np.array([r.time_s for r in records])
    lateness = np.maximum(np.diff(starts) - config.dt, 0.0) if len(starts) > 1 else np.zeros(0)
    work = np.array([sum(r.timings.values()) for r in records]) * 1e3
    swap = teacher.swapped_at[0] if teacher.swapped_at else None
    limits = model_joint_limits(model)
    n = len(records)
    truth_motor = np.array([r.truth["motor"] for r in records])
    motor_error = metrics.motor_error(np.array([r.motor for r in records]), truth_motor, limits)
    sensory_error = metrics.sensory_error(
        np.array([r.predicted for r in records]), np.array([r.observed for r in records])
    )
    time_record = watch.times[0] if watch.times else None
    return PacedRun(
        learning_set=set_name,
        shape=shape,
        steps=n,
        dt=config.dt,
        missed_deadlines=int(summary.missed_deadlines),
        late_steps=int(np.sum(lateness > LATE_S)),
        overrun_steps=int(np.sum(lateness + work[1:] / 1e3 > config.dt)) if n > 1 else 0,
        max_lateness_ms=float(lateness.max() * 1e3) if len(lateness) else 0.0,
        p99_step_ms=float(np.percentile(work, 99)) if n else 0.0,
        max_step_ms=float(work.max()) if n else 0.0,
        consolidation_steps=swap,
        consolidation=ConsolidationTime(*time_record, "done") if time_record else None,
        swap_step=swap,
        lock_after_swap=(
            metrics.steps_to_lock(motor_error, sensory_error, swap, n) if swap is not None else None
        ),
        swap_step_ms=float(work[swap]) if swap is not None and swap < n else None,
    )


def _start_models(config: TeachConfig) -> dict[str, str]:
    if config.shipped:
        from rnnpb.models import SHIPPED_MODEL

        return {"1": str(SHIPPED_MODEL)}
    folder = Path(config.models or DEFAULT_MODELS)
    out = {}
    for name in config.learning_sets:
        names = demo_model_names(name)
        found = next((folder / n for n in names if (folder / n).is_file()), None)
        if found is None:
            raise ConfigError(
                f"{folder}: no model {' or '.join(names)} for learning set {name} (the models "
                "`rnnpb demo` learns; run it first or give --models DIR)"
            )
        out[name] = str(found)
    return out


# --- the study -----------------------------------------------------------------------------


def run_study(out: Path, config: TeachConfig, log=print) -> StudyOutcome:
    """Run the study and write ``out/report.md``, ``out/results.json`` and the figures."""
    from rnnpb.analysis.figures import plot_teaching_timeline

    began = time.perf_counter()
    out = Path(out)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    (out / "runs").mkdir(parents=True, exist_ok=True)
    starts = _start_models(config)
    runs: dict[tuple[str, str], TeachRun] = {}
    before: dict[str, PaperMeasures] = {}
    paced: PacedRun | None = None

    def write(done: int, total: int) -> StudyOutcome:
        # After every job: a run stopped early keeps what it measured, marked partial.
        ordered = [
            runs[(n, s)] for n in config.learning_sets for s in config.shapes if (n, s) in runs
        ]
        targets = judge(ordered, before, paced, config)
        runtime = time.perf_counter() - began
        write_outputs(
            out,
            _report(config, ordered, before, paced, targets, runtime, (done, total)),
            _results(config, ordered, before, paced, targets, runtime, starts, (done, total)),
        )
        return StudyOutcome(runtime, targets)

    total = len(config.learning_sets) * (len(config.shapes) + int(config.paper_measures))
    total += int(config.paced is not None)
    # One core here too: the jobs may run here, and the consolidations they start inherit it.
    with study_pool(config.workers, init_here=True) as pool:
        jobs: dict[Future, Any] = {}
        if config.paper_measures:
            for name in config.learning_sets:
                jobs[pool.submit(before_job, name, starts[name], config)] = "before"
        # Shape by shape: a run stopped early has every learning set of the first shapes.
        for k, shape in enumerate(config.shapes):
            for name in config.learning_sets:
                folder = str(out / "runs" / f"set{name}_{shape}")
                jobs[pool.submit(teach_job, name, shape, k, starts[name], config, folder)] = "teach"
        for done, future in enumerate(as_completed(jobs), start=1):
            result = future.result()
            if jobs[future] == "before":
                before[result[0]] = result[1]
                log(f"  [{done}/{total}] set {result[0]}: measured before teaching")
            else:
                runs[(result.learning_set, result.shape)] = result
                plot_teaching_timeline(
                    result.timeline,
                    out / "figures" / f"timeline_set{result.learning_set}_{result.shape}.png",
                    f"Learning set {result.learning_set} taught {result.shape}",
                    config.dt,
                    metrics.MOTOR_LOCK_THRESHOLD,
                )
                log(
                    f"  [{done}/{total}] set {result.learning_set} {result.shape}: "
                    f"{len(result.episodes)} episode(s), follow {fmt(result.follow_s)} s"
                )
            outcome = write(done, total)
    if config.paced is not None and config.paced in runs and runs[config.paced].new_pattern:
        # Alone, after the others: the loop and the consolidation each have a core.
        set_name, shape = config.paced
        paced = paced_job(
            set_name,
            shape,
            str(out / "runs" / f"set{set_name}_{shape}"),
            starts[set_name],
            config,
            str(out / "runs" / f"paced_set{set_name}_{shape}"),
        )
        log(f"  paced run: {paced.missed_deadlines} missed deadline(s)")
        outcome = write(total, total)
    return outcome


def run(out: Path, options: StudyOptions) -> StudyOutcome:
    """``rnnpb study teach``: the full form reads ``--models DIR`` (default
    ``results/demo/models``, the models ``rnnpb demo`` learns)."""
    if options.quick:
        config = TeachConfig.quick_run(options.seed)
    else:
        config = TeachConfig(
            models=options.models or str(DEFAULT_MODELS),
            scenario_seed=100 + options.seed,
            workers=options.workers,
        )
    return run_study(Path(out), config)


# --- targets and report ----------------------------------------------------------------------


def _old_pairs(measures: PaperMeasures, old: tuple[str, ...]) -> dict[str, int | None]:
    return {k: v for k, v in measures.switching.items() if all(p in old for p in k.split("->"))}


def _worst(values) -> int | None:
    values = list(values)
    return None if not values or any(v is None for v in values) else max(values)


def _locked(steps: int | None) -> bool:
    """Whether a lock-on meets the paper's target (within :data:`metrics.LOCK_LIMIT`)."""
    return steps is not None and steps <= metrics.LOCK_LIMIT


def judge(
    runs: list[TeachRun],
    before: dict[str, PaperMeasures],
    paced: PacedRun | None,
    config: TeachConfig,
) -> dict[str, Target]:
    targets = {}
    # Following is the paper's lock-on (within LOCK_LIMIT steps) on the new shape's next
    # performance; the time counts to the step it locked on.
    locked = [r.follow_s for r in runs if _locked(r.lock_next) and r.follow_s is not None]
    met = [f for f in locked if f <= FOLLOW_LIMIT_S]
    late = [r.lock_next for r in runs if r.lock_next is not None and not _locked(r.lock_next)]
    never = sum(r.lock_next is None or r.follow_s is None for r in runs)
    targets["follow_within_90s"] = Target(
        len(met) == len(runs) > 0,
        f"{len(met)}/{len(runs)} runs locked on within {metrics.LOCK_LIMIT} steps of the "
        f"shape's next performance, within {FOLLOW_LIMIT_S:.0f} s of interaction "
        f"(worst {fmt(max(locked)) if locked else 'none'} s"
        + (
            f"; {len(late)} locked on later ({', '.join(str(v) for v in sorted(late))} steps)"
            if late
            else ""
        )
        + (f"; {never} never followed" if never else "")
        + ")",
    )
    if paced is not None:
        full = paced.swap_step is not None
        # A deadline is the end of a step's slot: missed when the step's work took longer
        # than dt (the loop's count) or its late start plus its work ran past the slot. A
        # start later than LATE_S within the slot is jitter, reported but not a miss.
        targets["no_missed_deadline"] = Target(
            paced.missed_deadlines == 0 and paced.overrun_steps == 0,
            f"{paced.missed_deadlines} missed, {paced.overrun_steps} ran past their slot; "
            f"{paced.late_steps} started > {LATE_S * 1e3:.0f} ms late (latest "
            f"{paced.max_lateness_ms:.0f} ms) over {paced.steps} paced steps at dt {paced.dt:g}"
            + (" through the consolidation and the swap" if full else " (consolidation cut short)"),
        )
    locks, switches, misses = [], [], []
    for run in runs:
        if not run.new_pattern:
            misses.append(f"set {run.learning_set} {run.shape}: nothing learned")
            continue
        if run.after is None:  # no paper measures (the quick form): the timeline's lock-on
            for segment, v in run.lock_in_timeline.items():
                if segment.split(":", 1)[1] != run.shape:
                    locks.append(v)
                    if not _locked(v):
                        misses.append(f"set {run.learning_set}: lock {segment} {fmt(v)}")
            continue
        old = tuple(p for p in run.after.lock if p != run.new_pattern)
        for p in old:
            v = run.after.lock[p]
            locks.append(v)
            if not _locked(v):
                misses.append(f"set {run.learning_set} {run.shape}: lock {p} {fmt(v)}")
        for pair, v in _old_pairs(run.after, old).items():
            switches.append(v)
            if v is None or v > metrics.SWITCH_LIMIT:
                misses.append(f"set {run.learning_set} {run.shape}: switch {pair} {fmt(v)}")
    targets["old_patterns_keep_paper_targets"] = Target(
        not misses and bool(locks),
        f"old lock-on {sum(map(_locked, locks))}/"
        f"{len(locks)} within {metrics.LOCK_LIMIT}, old switches "
        f"{sum(v is not None and v <= metrics.SWITCH_LIMIT for v in switches)}/{len(switches)} "
        f"within {metrics.SWITCH_LIMIT}"
        + (
            f"; missed: {'; '.join(misses[:12])}" + (" …" if len(misses) > 12 else "")
            if misses
            else ""
        ),
    )
    unstructured = sum(r.episodes_unstructured for r in runs)
    targets["nothing_kept_from_unstructured"] = Target(
        unstructured == 0,
        f"{unstructured} episode(s) with unstructured movement, over {len(runs)} runs "
        f"({sum(len(r.episodes) for r in runs)} episodes kept in all)",
    )
    return targets


def _report(config, runs, before, paced, targets, runtime, progress) -> list[str]:
    lines = [
        "# Study: teaching by showing — the robot learns a new shape on-line",
        "",
        "Per learning set and new shape, a scripted user performs: "
        + " → ".join(f"{m} ×{n}" for m, n in (runs[0].segments if runs else []))
        + " (steps; the first of the learned patterns is another per shape). The loop runs "
        "as fast as possible with the teacher: it waits between two steps for each "
        "consolidation, so a run repeats. *Follow*: steps from the new shape's first step "
        "until its episode is kept, plus the steps a paced loop runs while the consolidation "
        "takes its CPU time on one core, plus the lock-on steps on the shape's next "
        f"performance, × dt {config.dt:g} s (target ≤ {FOLLOW_LIMIT_S:.0f} s, and the "
        f"lock-on itself within {metrics.LOCK_LIMIT} steps, the paper's). The "
        "consolidation's wall time on this shared machine is the load's and is shown beside.",
        "",
        f"{'Quick form (shipped fast-preset model)' if config.quick else 'Full form'}; models "
        f"{'shipped' if config.shipped else config.models}; consolidation iterations "
        f"{config.consolidation_iterations or 'the consolidation default'}; user draws "
        f"(scenario seeds) {config.scenario_seed}+shape index; runtime {runtime:.0f} s"
        + (
            "."
            if progress[0] == progress[1]
            else f"; **partial: {progress[0]} of {progress[1]} jobs done**."
        ),
        "",
        "## Targets",
        "",
        *table(
            ("target", "met", "measured"),
            [(k, "yes" if t.met else "**no**", t.detail) for k, t in targets.items()],
        ),
        "",
        "## Per learning set and shape",
        "",
    ]
    rows = []
    for r in runs:
        c = r.consolidations[0] if r.consolidations else None
        shape_episodes = [e for e in r.episodes if not e.unstructured]
        first = shape_episodes[0] if shape_episodes else None
        rows.append(
            (
                r.learning_set,
                r.shape,
                fmt(r.detection_delay),
                f"{first.first_step}–{first.last_step} at {first.kept_at}" if first else "none",
                len(r.episodes),
                f"{c.cpu_s:.1f} / {c.wall_s:.0f}" if c else "–",
                r.new_pattern or "–",
                fmt(r.lock_next),
                fmt(100 * r.recognised_next, 0),
                (
                    " + ".join(str(v) for v in r.follow_steps.values())
                    + f" steps = {fmt(r.follow_s)} s"
                    if r.follow_s is not None
                    else "never"
                ),
                r.episodes_unstructured,
            )
        )
    lines += table(
        (
            "set",
            "shape",
            "detection delay (steps)",
            "episode (steps, kept at)",
            "episodes",
            "consolidation CPU / wall (s)",
            "learned as",
            "lock-on next time",
            "recognised next time %",
            "follow (kept + consolidation + lock)",
            "episodes from unstructured",
        ),
        rows,
    )
    lines += [
        "",
        "## Old patterns after teaching (the paper's measures)",
        "",
        "Lock-on from rest (paper 3.1, target ≤ "
        f"{metrics.LOCK_LIMIT}) and switching for every ordered pair (3.2, ≤ "
        f"{metrics.SWITCH_LIMIT}), before teaching and after; worst over the old patterns.",
        "",
    ]
    rows = []
    for name, measures in before.items():
        rows.append(
            (
                name,
                "before",
                ", ".join(f"{p}: {fmt(v)}" for p, v in measures.lock.items()),
                fmt(_worst(measures.switching.values())),
                "–",
                "–",
            )
        )
        for r in runs:
            if r.learning_set != name or r.after is None:
                continue
            old = tuple(p for p in r.after.lock if p != r.new_pattern)
            new_pairs = {k: v for k, v in r.after.switching.items() if r.new_pattern in k}
            rows.append(
                (
                    name,
                    f"+{r.shape}",
                    ", ".join(f"{p}: {fmt(r.after.lock[p])}" for p in old),
                    fmt(_worst(_old_pairs(r.after, old).values())),
                    fmt(r.after.lock.get(r.new_pattern)),
                    fmt(_worst(new_pairs.values())),
                )
            )
    lines += table(
        (
            "set",
            "model",
            "old lock-on from rest",
            "old switching (worst)",
            "new lock-on from rest",
            "switching with the new (worst)",
        ),
        rows,
    )
    if paced is not None:
        c = paced.consolidation
        lines += [
            "",
            "## Deadlines during the background consolidation (paced)",
            "",
            f"Learning set {paced.learning_set}: the user keeps performing {paced.shape} while "
            "the episode kept in its run is consolidated again in the background process; "
            f"the loop paced at dt {paced.dt:g} s, the new model swapped in between two steps.",
            "",
            *table(
                ("measure", "value"),
                [
                    ("paced steps", paced.steps),
                    ("missed deadlines (a step's work over dt)", paced.missed_deadlines),
                    (f"steps started > {LATE_S * 1e3:.0f} ms late", paced.late_steps),
                    ("steps whose late start plus work ran past their slot", paced.overrun_steps),
                    ("latest start (ms after due)", fmt(paced.max_lateness_ms)),
                    (
                        "step work p99 / max (ms)",
                        f"{paced.p99_step_ms:.1f} / {paced.max_step_ms:.1f}",
                    ),
                    ("steps during the consolidation", fmt(paced.consolidation_steps)),
                    (
                        "consolidation CPU / wall (s)",
                        f"{c.cpu_s:.1f} / {c.wall_s:.1f}" if c else "cut short",
                    ),
                    ("first step with the new model (ms)", fmt(paced.swap_step_ms)),
                    ("lock-on after the swap (steps)", fmt(paced.lock_after_swap)),
                ],
            ),
        ]
    lines += ["", "## Timelines", ""]
    lines += [
        embed(
            f"set {r.learning_set} taught {r.shape}", f"timeline_set{r.learning_set}_{r.shape}.png"
        )
        for r in runs
    ]
    lines.append("")
    return lines


def _results(config, runs, before, paced, targets, runtime, starts, progress) -> dict[str, Any]:
    def run_json(r: TeachRun) -> dict[str, Any]:
        out = asdict(r)
        out.pop("timeline")
        out["timeline"] = {k: v for k, v in r.timeline.items() if k != "motor_error"}
        out["motor_error"] = r.timeline["motor_error"]
        return out

    return {
        "study": NAME,
        "config": asdict(config),
        "models": starts,
        "versions": versions(),
        "runtime_s": runtime,
        "jobs_done": progress[0],
        "jobs": progress[1],
        "targets": {k: t.to_json() for k, t in targets.items()},
        "runs": [run_json(r) for r in runs],
        "before": {k: asdict(v) for k, v in before.items()},
        "paced": asdict(paced) if paced is not None else None,
    }
