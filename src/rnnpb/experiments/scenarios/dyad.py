"""The dyad study's scenarios and measures (``rnnpb study dyad``, docs/dyad.md): two robots
imitating each other from random starts, over a grid of adaptation rates, and a robot with a
scripted subject; each run a job for a worker process, the cells of the phase diagram, and the
study's targets measured from its results (:func:`measured`).

Coherence is judged from the agents' movements (:mod:`rnnpb.analysis.dyad`): both on the same
learned pattern — as taught, or as the robot's own network plays it in closed loop — and
phase-locked.
"""

from __future__ import annotations

import time
from concurrent.futures import Future, as_completed
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb.analysis import dyad as measures
from rnnpb.errors import ConfigError
from rnnpb.experiments.exams import Exam
from rnnpb.experiments.scenarios import study_models as shared
from rnnpb.experiments.studies import StudyOptions
from rnnpb.experiments.studies._pool import study_pool
from rnnpb.interaction.dyad import AgentConfig, DyadRun, robot_pair
from rnnpb.interaction.person_space import pattern_references
from rnnpb.interaction.recorder import DyadRecorder
from rnnpb.interaction.subject import SubjectConfig, robot_and_subject
from rnnpb.model.io import TrainedModel
from rnnpb.model.online_config import OnlineConfig

SETS = ("set1", "set2", "set3", "set4")
DT = 0.4
PATIENCE = 6  # steps of not predicting the partner before a robot initiates
PERSISTENCE = 60  # steps of stable interaction before a robot initiates (the "shifting" runs)
CHUNK = 60  # steps of a subject session between checks whether all is found
SUBJECT_MINUTES = 10.0  # a full-form subject session's length: the target's limit


@dataclass(frozen=True)
class DyadStudySize:
    """How much the study runs: seeds per random-start condition and its steps; the phase
    diagram's adaptation rates, seeds, steps and persistences (over the grid) and the
    persistences of the line at adaptation 1 for both; the subject protocol's sets, seeds and
    simulated minutes."""

    start_seeds: int
    start_steps: int
    same_sets: tuple[str, ...]
    mixed_sets: tuple[tuple[str, str], ...]
    rates: tuple[float, ...]
    grid_seeds: int
    grid_steps: int
    grid_persistence: tuple[int | None, ...]
    line_persistence: tuple[int, ...]
    subject_sets: tuple[str, ...]
    subject_seeds: int
    subject_minutes: float

    @classmethod
    def for_options(cls, options: StudyOptions) -> DyadStudySize:
        if options.quick:
            return cls(2, 80, ("set1",), (("set1", "set2"),), (0.1, 1.0), 1, 200,
                       (None, PERSISTENCE), (30,), ("set1",), 1, 2.0)  # fmt: skip
        # Sized to run in about half an hour on 2 cores (docs/dyad.md).
        return cls(
            start_seeds=5,
            start_steps=80,
            same_sets=SETS,
            mixed_sets=(("set1", "set2"), ("set3", "set4")),
            rates=(0.03, 0.1, 0.3, 1.0),
            grid_seeds=3,
            grid_steps=300,
            grid_persistence=(None, PERSISTENCE),
            line_persistence=(30,),
            subject_sets=SETS,
            subject_seeds=12,
            subject_minutes=SUBJECT_MINUTES,
        )

    def needed_sets(self) -> tuple[str, ...]:
        """The learning sets whose models the runs use (the phase diagram's: set 1)."""
        pairs = [name for pair in self.mixed_sets for name in pair]
        used = {"set1", *self.same_sets, *pairs, *self.subject_sets}
        return tuple(name for name in SETS if name in used)


@dataclass(frozen=True)
class DyadSeeds:
    """The seeds of each part: random starts (per pair of sets), the phase diagram's runs
    (per cell) and the subject sessions (one each); ``training``: the models' learning."""

    starts: tuple[int, ...]
    grid: tuple[int, ...]
    subject: tuple[int, ...]
    training: int = 0

    @classmethod
    def from_exam(cls, exam: Exam) -> DyadSeeds:
        starts, grid, subject = (exam.seed_list(k) for k in ("starts", "grid", "subject"))
        return cls(starts, grid, subject, training=exam.seed_list("training")[0])

    def sized(self, size: DyadStudySize) -> DyadStudySize:
        """``size`` with these seeds' counts."""
        return replace(size, start_seeds=len(self.starts), grid_seeds=len(self.grid),
                       subject_seeds=len(self.subject))  # fmt: skip

    @classmethod
    def from_first(cls, size: DyadStudySize, first: int) -> DyadSeeds:
        return cls(
            tuple(range(first, first + size.start_seeds)),
            tuple(range(first, first + size.grid_seeds)),
            tuple(range(first, first + size.subject_seeds)),
        )


def study_config(
    size: DyadStudySize, paths: dict[str, str], options: StudyOptions
) -> dict[str, Any]:
    """What results.json records of the study's settings."""
    return {
        "dt": DT,
        "patience": PATIENCE,
        "persistence": PERSISTENCE,
        "size": asdict(size),
        "agent": asdict(AgentConfig(patience=PATIENCE)),
        "subject": asdict(SubjectConfig()),
        "online": OnlineConfig().to_dict(),
        "coherence": {
            "class_window": measures.CLASS_WINDOW,
            "class_tolerance": measures.CLASS_TOLERANCE,
            "max_lag": measures.MAX_LAG,
            "lock_correlation": measures.LOCK_CORRELATION,
            "lock_steady": measures.LOCK_STEADY,
            "moving_level": measures.MOVING_LEVEL,
        },
        "models": paths,
        "quick": options.quick,
        "workers": options.workers,
    }


def model_paths(
    directory: str | None, needed: tuple[str, ...], out: Path, quick: bool, seed: int
) -> dict[str, str]:
    """The model file of each needed learning set (``setK``): ``directory``'s ``setK.npz`` (a
    missing one is a clear error), or, without a directory, learned into ``out/models``: the
    paper's algorithm on the demo's data (the demo's models), the quick form the fast preset."""
    from rnnpb.model import TrainConfig

    config = TrainConfig.fast(iterations=1500, seed=seed) if quick else TrainConfig.paper(seed=seed)
    sets = [name.removeprefix("set") for name in needed]
    paths = shared.study_models(sets, directory, out / "models", lambda _: config, seed)
    if directory is not None:
        for path in paths.values():
            TrainedModel.load(path)  # a model that does not load fails here, once
    return {f"set{name}": path for name, path in paths.items()}


_LOADED: dict[str, tuple[TrainedModel, dict[str, np.ndarray]]] = {}


def _load(path: str) -> tuple[TrainedModel, dict[str, np.ndarray]]:
    """A model and its patterns' closed-loop references, once per process."""
    if path not in _LOADED:
        model = TrainedModel.load(path)
        _LOADED[path] = (model, pattern_references(model))
    return _LOADED[path]


def _figure_arrays(arrays: dict[str, np.ndarray], found: measures.DyadMeasures) -> dict[str, Any]:
    return {
        "arrays": {k: arrays[k] for k in ("a_shown", "b_shown", "a_pb", "b_pb")},
        "coherent": found.coherent,
        "shifts": [(s.step, s.leader) for s in found.shifts],
    }


def robots_job(
    path_a: str,
    path_b: str,
    a: AgentConfig,
    b: AgentConfig,
    seed: int,
    steps: int,
    record: str | None = None,
    keep: bool = False,
) -> dict[str, Any]:
    """One robot–robot run from a random start, measured: its summary (coherence judged by
    each robot's learned patterns as taught and as its network plays them) and
    ``first_coherent_by_templates`` (as taught only); with ``keep``, what its figure needs."""
    cpu = time.process_time()
    (model_a, refs_a), (model_b, refs_b) = _load(path_a), _load(path_b)
    pair = robot_pair(model_a, model_b, a, b, seed=seed)
    if record is not None:
        with DyadRecorder(Path(record), model_a.network.pb_size, DT) as recorder:
            run = pair.run(steps, on_step=recorder.write)
    else:
        run = pair.run(steps)
    shared = tuple(p for p in model_a.patterns if p in model_b.patterns)
    found = measures.measure_dyad(
        run["a_shown"],
        run["b_shown"],
        shared,
        run["a_pb"],
        run["b_pb"],
        references_a=refs_a,
        references_b=refs_b,
    )
    looks = measures.measure_dyad(run["a_shown"], run["b_shown"], shared, run["a_pb"], run["b_pb"])
    out: dict[str, Any] = {
        "summary": {
            **found.summary(DT),
            "first_coherent_by_templates": looks.first_coherent,
            "coherent_share_by_templates": looks.coherent_share,
            "cpu_s": time.process_time() - cpu,
        }
    }
    if keep:
        out["figure"] = _figure_arrays(run.arrays, found)
    return out


def subject_job(
    path: str, seed: int, n_steps: int, record: str | None = None, keep: bool = False
) -> dict[str, Any]:
    """One subject session, up to ``n_steps`` steps, a cycle at a time: it ends once every
    learned pattern is found (nothing after that changes what the protocol measures)."""
    if n_steps < 1:
        raise ConfigError(f"a subject session needs at least one step, got {n_steps}")
    cpu = time.process_time()
    model, refs = _load(path)
    dyad = robot_and_subject(model, AgentConfig(), SubjectConfig(), seed=seed)
    steps: list = []
    recorder = DyadRecorder(Path(record), model.network.pb_size, DT) if record is not None else None

    def keep_step(step: Any) -> None:
        steps.append(step)
        if recorder is not None:
            recorder.write(step)

    try:
        while True:  # until every pattern is found or the steps are run (at least once)
            dyad.run(min(CHUNK, n_steps - len(steps)), on_step=keep_step)
            arrays = DyadRun.from_steps(steps).arrays
            found = measures.measure_dyad(
                arrays["a_shown"], arrays["b_shown"], model.patterns, arrays["a_pb"],
                references_a=refs,
            )  # fmt: skip
            if found.found[-1] >= len(model.patterns) or len(steps) >= n_steps:
                break
    finally:
        if recorder is not None:
            recorder.close()
    looks = measures.measure_dyad(
        arrays["a_shown"], arrays["b_shown"], model.patterns, arrays["a_pb"]
    )
    all_found = np.flatnonzero(found.found >= len(model.patterns))
    all_looks = np.flatnonzero(looks.found >= len(model.patterns))
    minutes = int(round(n_steps * DT / 60))
    out: dict[str, Any] = {
        "summary": {
            **found.summary(DT),
            "minutes_to_all": float(all_found[0] * DT / 60) if all_found.size else None,
            "minutes_to_all_by_templates": (
                float(all_looks[0] * DT / 60) if all_looks.size else None
            ),
            "steps_run": len(found.found),
            "cpu_s": time.process_time() - cpu,
            "per_minute": [
                int(found.found[min(int(m * 60 / DT), len(found.found)) - 1])
                for m in range(1, minutes + 1)
            ],
        },
        "found": found.found,
    }
    if keep:
        out["figure"] = _figure_arrays(arrays, found)
    return out


def run_jobs(
    paths: dict[str, str], size: DyadStudySize, seeds: DyadSeeds, out: Path, workers: int
) -> list[tuple[dict[str, Any], dict[str, Any]]]:
    """Every run of the study as a job, the longest first so that the workers end together:
    (its key, with ``part`` one of starts, grid, subject; its result). The first seed's runs
    are recorded in ``out/sessions``; the first of each part keeps what its figure needs."""
    jobs: dict[Future, tuple[str, dict[str, Any]]] = {}
    done: list[tuple[dict[str, Any], dict[str, Any]]] = []
    subject_steps = int(round(size.subject_minutes * 60 / DT))
    follower = AgentConfig(patience=PATIENCE)
    # Kept to one core here too when workers are started: they inherit it.
    with study_pool(workers, init_here=workers > 1) as pool:

        def submit(part: str, key: dict[str, Any], function: Any, *args: Any) -> None:
            jobs[pool.submit(function, *args)] = (part, key)

        for k, seed in enumerate(seeds.subject):
            # Each seed its own session, the sets in turn.
            name = size.subject_sets[k % len(size.subject_sets)]
            record = (
                str(out / "sessions" / f"subject_{name}_seed{seed}.csv")
                if k < len(size.subject_sets)
                else None
            )
            submit("subject", {"set": name, "seed": seed}, subject_job, paths[name], seed,
                   subject_steps, record, k == 0)  # fmt: skip
        grid = [
            (persistence, ra, rb)
            for persistence in size.grid_persistence
            for ra in size.rates
            for rb in size.rates
        ] + [(persistence, 1.0, 1.0) for persistence in size.line_persistence]
        for persistence, ra, rb in grid:
            for seed in seeds.grid:
                a = AgentConfig(adaptation=ra, patience=PATIENCE, persistence=persistence)
                b = AgentConfig(adaptation=rb, patience=PATIENCE, persistence=persistence)
                key = {"persistence": persistence, "adaptation_a": ra, "adaptation_b": rb,
                       "seed": seed}  # fmt: skip
                submit("grid", key, robots_job, paths["set1"], paths["set1"], a, b, seed,
                       size.grid_steps)  # fmt: skip
        pairs = [("same", (n, n)) for n in size.same_sets] + [
            ("different", p) for p in size.mixed_sets
        ]
        first = seeds.starts[0]
        for kind, (name_a, name_b) in pairs:
            for seed in seeds.starts:
                record = (
                    str(out / "sessions" / f"robots_{name_a}_{name_b}_seed{seed}.csv")
                    if seed == first
                    else None
                )
                keep = (kind, name_a, seed) == ("same", size.same_sets[0], first)
                key = {"kind": kind, "a": name_a, "b": name_b, "seed": seed}
                submit("starts", key, robots_job, paths[name_a], paths[name_b], follower,
                       follower, seed, size.start_steps, record, keep)  # fmt: skip
        for future in as_completed(jobs):
            part, key = jobs[future]
            done.append(({"part": part, **key}, future.result()))
    return done


def part_rows(done: list[tuple[dict[str, Any], dict[str, Any]]], part: str) -> list[dict]:
    """One part's runs, each its key and summary, in the order of their keys."""
    keys = [k for k, _ in done if k["part"] == part]
    order = sorted(range(len(keys)), key=lambda i: str(keys[i]))
    picked = [(k, r) for k, r in done if k["part"] == part]
    return [{**picked[i][0], **picked[i][1]["summary"]} for i in order]


def part_figure(done: list[tuple[dict[str, Any], dict[str, Any]]], part: str) -> dict[str, Any]:
    """What the figure of one part's kept run needs."""
    return next(r["figure"] for k, r in done if k["part"] == part and "figure" in r)


def median_first(rows: list[dict[str, Any]], key: str = "first_coherent") -> float:
    return float(np.median([r[key] if r[key] is not None else np.inf for r in rows]))


def within(rows: list[dict[str, Any]], limit: float, key: str = "first_coherent") -> int:
    """How many runs' ``key`` (a step or a minute; None: never) is at most ``limit``."""
    return sum(r[key] is not None and r[key] <= limit for r in rows)


def phase_cell(
    cells: list[dict[str, Any]],
    persistence: int | None,
    ra: float,
    rb: float,
    hold_share: float,
    shift_rate: float,
) -> dict[str, Any]:
    """One setting of the phase diagram over its seeds: coherent share, shifts per 200 steps,
    who led, and whether joint attention holds (coherent at least ``hold_share`` of the time)
    or shifts spontaneously (at least ``shift_rate`` shifts per 200 steps, both leading)."""
    group = [
        c
        for c in cells
        if (c["persistence"], c["adaptation_a"], c["adaptation_b"]) == (persistence, ra, rb)
    ]
    led_a = sum(c["led_by_a"] for c in group)
    led_b = sum(c["led_by_b"] for c in group)
    share = float(np.mean([c["coherent_share"] for c in group]))
    shift = float(np.mean([c["pattern_shifts"] * 200 / c["steps"] for c in group]))
    return {
        "persistence": persistence,
        "adaptation_a": ra,
        "adaptation_b": rb,
        "runs": len(group),
        "coherent_share": share,
        "shifts_per_200": shift,
        "led_by_a": led_a,
        "led_by_b": led_b,
        "leader_index": (led_a - led_b) / (led_a + led_b) if led_a + led_b else float("nan"),
        "holds": share >= hold_share,
        "shifts": shift >= shift_rate and led_a > 0 and led_b > 0,
    }


def measured(results: dict[str, Any], exam: Exam) -> dict[str, dict[str, Any]]:
    """Each target's measured value (``value``) and the counts its detail gives, from the
    study's results, by the exam's definitions."""
    lock = exam.target("robots_lock_from_random_starts").parameter("steps")
    same = [s for s in results["random_starts"] if s["kind"] == "same"]
    regimes = exam.target("phase_diagram_both_regimes")
    hold, shift = regimes.parameter("hold_share"), regimes.parameter("shift_rate")
    settings = list(
        {
            (c["persistence"], c["adaptation_a"], c["adaptation_b"]): c
            for c in results["phase_cells"] + results["persistence_line"]
        }.values()
    )
    holding = [c for c in settings if c["coherent_share"] >= hold]
    shifting = [
        c
        for c in settings
        if c["shifts_per_200"] >= shift and c["led_by_a"] > 0 and c["led_by_b"] > 0
    ]
    minutes = exam.target("subject_finds_all").parameter("minutes")
    sessions = results["subject"]
    in_time = within(sessions, minutes, "minutes_to_all")
    return {
        "robots_lock_from_random_starts": {
            "value": within(same, lock) / len(same),
            "locked": within(same, lock),
            "by_templates": within(same, lock, "first_coherent_by_templates"),
            "runs": len(same),
        },
        "phase_diagram_both_regimes": {
            "value": min(len(holding), len(shifting)),
            "holding": len(holding),
            "shifting": len(shifting),
        },
        "subject_finds_all": {
            "value": in_time / len(sessions),
            "in_time": in_time,
            "sessions": len(sessions),
        },
    }
