"""The teach study's jobs: one learning set taught one movement as fast as possible, the
paper's measures of a starting model, and the paced run (each runs in a worker process).

The interaction loop runs with the :class:`rnnpb.interaction.teaching.Teacher` subscribed, as
fast as possible — so the loop waits between two steps for each consolidation, and a run
repeats. The paced run plays the new movement at the run's step while the background process
consolidates the kept episodes of one run again, and the new model is swapped in between two
steps. Each job copies its starting model into its own folder and never writes the original.
"""

from __future__ import annotations

import math
import shutil
import time
from collections.abc import Iterator
from concurrent.futures import as_completed
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb.analysis import metrics
from rnnpb.experiments.scenarios.teaching_measures import (
    ConsolidationTime,
    PacedRun,
    PaperMeasures,
    TeachRun,
    detection_delay,
    follow_time,
    kept_episodes,
    most_performed,
    paced_timing,
    paper_measures,
    segment_locks,
)
from rnnpb.experiments.scenarios.teaching_scenario import (
    UNSTRUCTURED_MOVEMENTS,
    TeachConfig,
    period_of,
    segments,
    showing_stream,
    source_spec,
)


class Watch:
    """Around a Teacher: times each consolidation (the CPU its process reported, wall) and
    records the cutter's state and the consolidation per step."""

    def __init__(self, teacher, loop) -> None:
        self.teacher = teacher
        self.loop = loop
        self.records: list = []
        self.cutter: list[str] = []
        self.times: list[tuple[int, float, float, float]] = []  # (step, cpu, wall, worker)
        self._started: tuple[int, float] | None = None
        self.stop_after: int | None = None
        self.step_limit: int | None = None

    def started(self) -> None:
        """A consolidation was started outside a step (confirmed before the run)."""
        self._started = (self.loop.steps, time.perf_counter())

    def on_step(self, record) -> None:
        self.records.append(record)
        self.cutter.append(self.teacher.keeper.cutter.status.state)
        if self.teacher.job is not None and self._started is None:
            self._started = (self.loop.steps, time.perf_counter())

    def between_steps(self, wait_s: float) -> None:
        job = self.teacher.job
        self.teacher.between_steps(wait_s)
        if job is not None and self.teacher.job is None and self._started is not None:
            step, wall = self._started
            self._started = None
            state = job.state
            self.times.append((step, state.cpu_s, time.perf_counter() - wall, state.seconds))
        if self.stop_after is not None and self.loop.steps >= self.stop_after:
            self.loop.stop()
        if self.step_limit is not None and self.loop.steps >= self.step_limit:
            self.loop.stop()


def fresh_copy(start_path: str, folder: str) -> Path:
    """Copy a starting model into an empty ``folder`` (a run repeats: no versions or memory of
    an earlier one) and return the copy's path."""
    run_dir = Path(folder)
    if run_dir.exists():
        shutil.rmtree(run_dir)
    run_dir.mkdir(parents=True)
    path = run_dir / "model.npz"
    shutil.copyfile(start_path, path)
    return path


def teacher_for(loop, path: Path, memory, config: TeachConfig, **options) -> Any:
    """The :class:`~rnnpb.interaction.teaching.Teacher` of a run: the one place where the
    study says how the teacher consolidates (``config.teaching``, and the consolidation's
    iterations)."""
    from rnnpb.interaction.teaching import Teacher
    from rnnpb.model import MirrorSystem

    return Teacher(
        loop,
        path,
        memory,
        make_mirror=lambda m: MirrorSystem(m, config.online),
        config=config.teaching,
        iterations=config.consolidation_iterations,
        **options,
    )


def teach_job(
    set_name: str,
    shape: str,
    index: int,
    start_path: str,
    config: TeachConfig,
    folder: str,
    seed: int | None = None,
) -> TeachRun:
    """One learning set taught one shape, the ``index``-th, as fast as possible (module doc);
    the scripted user's draw is ``seed`` (None: ``config.scenario_seed + index``)."""
    from rnnpb import _xla
    from rnnpb.demonstrator import ScenarioSource, learning_set_patterns
    from rnnpb.interaction import InteractionLoop, LoopConfig
    from rnnpb.memory import MemoryStore
    from rnnpb.model import MirrorSystem, TrainedModel
    from rnnpb.model.consolidation import model_joint_limits

    _xla.configure()
    began = time.perf_counter()
    path = fresh_copy(start_path, folder)
    model = TrainedModel.load(path)
    performed = segments(learning_set_patterns(set_name), shape, index, config)
    seed = config.scenario_seed + index if seed is None else seed
    scenario = showing_stream(performed, seed, config.dt)
    online = config.online
    with ScenarioSource(scenario) as source, MemoryStore(path) as memory:
        loop = InteractionLoop(MirrorSystem(model, online), source, config=LoopConfig(config.dt))
        teacher = teacher_for(loop, path, memory, config, source=source_spec(performed))
        watch = Watch(teacher, loop)
        loop.run(on_step=watch.on_step, between_steps=watch.between_steps)
        if teacher.job is not None:  # kept on the last step: consolidate before measuring
            watch.between_steps(0.0)
        labels = list(scenario.labels)
        episodes = kept_episodes(memory, teacher, labels)
    records = watch.records
    limits = model_joint_limits(model)
    motor_error = metrics.motor_error(np.array([r.motor for r in records]), scenario.motor, limits)
    sensory_error = metrics.sensory_error(
        np.array([r.predicted for r in records]), np.array([r.observed for r in records])
    )
    new_start = performed[0][1]
    novelty = [r.novelty for r in records]
    final = TrainedModel.load(teacher.model_path)
    new_names = [p for p in final.patterns if p not in model.patterns]
    # The episodes of the new shape: most of their steps are the shape's.
    from_shape = [e for e in episodes if most_performed(e) == shape]
    new_pattern = next((e.pattern for e in from_shape if e.pattern in new_names), "")
    if new_pattern:
        # Which demonstrator movement each taught pattern is, for the paper's measures.
        taught = {e.pattern: most_performed(e) for e in episodes}
        final = replace(final, meta={**final.meta, "taught": taught})
    again_start = len(labels) - performed[-1][1]
    lock_next = metrics.steps_to_lock(motor_error, sensory_error, again_start, len(labels))
    # Judged from one cycle of the third showing on (at least 12 steps: the detector's cycle).
    settle = max(12, period_of(shape))
    recognised_next = (
        float(np.mean([r.recognised == new_pattern for r in records[again_start + settle :]]))
        if new_pattern
        else 0.0
    )
    consolidations = [
        ConsolidationTime(
            step, cpu, wall, worker, "done" if k < len(teacher.swapped_at) else "failed"
        )
        for k, (step, cpu, wall, worker) in enumerate(watch.times)
    ]
    # Followed from the episode that made the shape ready to learn: the last of the shape's
    # kept before the first consolidation started (its second performance's).
    ready = [
        e for e in from_shape if not consolidations or e.kept_at <= consolidations[0].started_at
    ]
    follow_s, follow_steps = follow_time(
        max(ready, key=lambda e: e.kept_at, default=None),
        consolidations[0] if consolidations else None,
        lock_next,
        new_start,
        config.dt,
    )
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
        "third_showing": again_start,
        "unstructured": list(UNSTRUCTURED_MOVEMENTS),
        # The movement each newly learned pattern was taught from (its colour in the figure).
        "taught": {e.pattern: most_performed(e) for e in episodes if e.pattern in new_names},
    }
    return TeachRun(
        learning_set=set_name,
        shape=shape,
        dt=config.dt,
        new_pattern=new_pattern,
        segments=performed,
        detection_delay=detection_delay(novelty, new_start, performed[1][1]),
        episodes=episodes,
        consolidations=consolidations,
        swaps=list(teacher.swapped_at),
        lock_next=lock_next,
        recognised_next=recognised_next,
        lock_in_timeline=segment_locks(motor_error, sensory_error, performed, swap),
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


def job_count(config: TeachConfig) -> int:
    """The study's jobs: those of :func:`study_jobs` and the paced run."""
    per_set = len(config.movements) + int(config.paper_measures)
    return len(config.learning_sets) * per_set + int(config.paced is not None)


def study_jobs(
    pool, config: TeachConfig, starts: dict[str, str], runs: Path
) -> Iterator[TeachRun | tuple[str, PaperMeasures]]:
    """Submit the study's jobs to ``pool`` — the paper's measures of each starting model, then
    each learning set taught each shape, in ``runs/setK_SHAPE``, the larger sets first — and
    yield each result as its job finishes."""
    from rnnpb.demonstrator import learning_set_patterns

    # The sets with the most patterns first: their jobs take longest, and a long job begun
    # last keeps one worker busy while the other has nothing left to do.
    sets = sorted(config.learning_sets, key=lambda name: -len(learning_set_patterns(name)))
    jobs = []
    if config.paper_measures:
        jobs += [pool.submit(before_job, name, starts[name], config) for name in sets]
    # Shape by shape: a run stopped early has every learning set of the first shapes. Run k
    # of the step time (over the learning sets in their order, then the movements) draws the
    # user ``seed + k``.
    order = {name: i for i, name in enumerate(config.learning_sets)}
    movements = config.movements
    for k, shape in enumerate(movements):
        for name in sets:
            folder = str(runs / f"set{name}_{shape}")
            seed = config.scenario_seed + order[name] * len(movements) + k
            jobs.append(pool.submit(teach_job, name, shape, k, starts[name], config, folder, seed))
    for future in as_completed(jobs):
        yield future.result()


def paced_job(
    set_name: str, shape: str, start_path: str, config: TeachConfig, runs: Path, seed: int
) -> PacedRun:
    """At the run's step, paced, in ``runs/paced_setK_SHAPE``: the user keeps performing
    ``shape`` while the episodes the fast run (``runs/setK_SHAPE``) kept of it are consolidated
    again in the background, and the new model is swapped in."""
    run_folder = runs / f"set{set_name}_{shape}"
    folder = str(runs / f"paced_set{set_name}_{shape}")
    from rnnpb import _xla
    from rnnpb.demonstrator import ScenarioSource
    from rnnpb.interaction import InteractionLoop, LoopConfig
    from rnnpb.memory import MemoryStore
    from rnnpb.model import MirrorSystem, TrainedModel
    from rnnpb.model.consolidation import model_joint_limits

    _xla.configure()
    path = fresh_copy(start_path, folder)
    model = TrainedModel.load(path)
    with MemoryStore(Path(run_folder) / "model.npz", create=False) as taught:
        movements = [taught.episode(i) for i in taught.group("new-1")]
    scenario = showing_stream([(shape, 120)], seed, config.dt)
    online = config.online
    with ScenarioSource(scenario, loop=True) as source, MemoryStore(path) as memory:
        episode_ids = [
            memory.add_episode(
                movement.sensory,
                movement.motor,
                source=movement.summary.source,
                model=str(path),
                pattern=movement.summary.pattern,
                n_cycles=movement.summary.n_cycles,
                note=movement.summary.note,
            )
            for movement in movements
        ]
        mirror = MirrorSystem(model, online)
        loop = InteractionLoop(mirror, source, config=LoopConfig(config.dt, paced=True))
        # Compiled before the clock starts, as a session's first step would be at its start.
        mirror.step(scenario.sensory[0])
        mirror.reset()
        teacher = teacher_for(loop, path, memory, config, source="paced", auto=False)
        watch = Watch(teacher, loop)
        watch.step_limit = config.paced_max_steps
        teacher.pending.extend(episode_ids)
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
        summary = loop.summary()
    records = watch.records
    timing = paced_timing(records, config.dt)
    work = timing.pop("work_ms")
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
        **timing,
        consolidation_steps=swap,
        consolidation=ConsolidationTime(*time_record, "done") if time_record else None,
        swap_step=swap,
        lock_after_swap=(
            metrics.steps_to_lock(motor_error, sensory_error, swap, n) if swap is not None else None
        ),
        swap_step_ms=float(work[swap]) if swap is not None and swap < n else None,
    )
