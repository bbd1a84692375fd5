"""One run of a sweep: train (or reuse the cached model) and measure; its record.

A run's measures are rows ``(measure, key, value)``: ``key`` names the pattern, the ordered pair
of a switch or the novel-pattern input, empty when the measure has one value per run; ``value``
is ``None`` when the event never happened (no lock-on, no cycle). The measures are the paper's
section 3 (:mod:`rnnpb.experiments.paper`, defined in :mod:`rnnpb.analysis.metrics`).
"""

from __future__ import annotations

import math
import os
import time
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rnnpb import __version__
from rnnpb.sweeps._spec import AnyRun, RunSpec, StudyRunSpec

MODELS_DIR = "models"
# The measures, in the order a run's record holds them.
MEASURES = {
    "train_mse_max": "final training error (MSE, worst output)",
    "train_rms_max": "final training error as RMS",
    "steps_to_lock": "steps until locked on a learned pattern (3.1)",
    "pb_settle_steps": "steps until the PB settles (3.1)",
    "phase_lag_steps": "phase lag once locked, steps (3.1)",
    "recognised": "learned pattern recognised, 1 or 0 (3.1)",
    "pause_relative_motion": "robot motion during the pause relative to before (3.1)",
    "pause_steps_to_relock": "steps to re-lock after the pause (3.1)",
    "switch_steps": "steps until the robot follows a switch (3.2)",
    "closed_loop_period": "closed-loop period of a learned pattern, steps (3.3)",
    "novel_case": "novel-pattern response case 1, 2 or 3 (3.3)",
    "novel_period": "period of the novel-pattern response, steps (3.3)",
    "steps_to_follow": "larger set: steps until the robot follows a pattern (3.4)",
    "follows_all": "larger set: follows every pattern, 1 or 0 (3.4)",
    "study_target_met": "a study's target (the key) met, 1 or 0",
    "study_runtime_s": "a study's run time, seconds",
}
STUDIES_DIR = "studies"

Measure = tuple[str, str, float | None]


@dataclass(frozen=True)
class RunRecord:
    """What a run left: its measures, or the error it failed with."""

    run_id: str
    status: str  # "ok" or "failed"
    measures: list[Measure]
    error: str  # "" when ok
    model: str  # the cached model file, relative to the sweep's folder
    seconds: float
    rnnpb_version: str = __version__

    def to_json(self) -> dict[str, Any]:
        return {
            "run_id": self.run_id,
            "status": self.status,
            "measures": [list(m) for m in self.measures],
            "error": self.error,
            "model": self.model,
            "seconds": self.seconds,
            "rnnpb_version": self.rnnpb_version,
        }

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> RunRecord:
        return cls(
            run_id=data["run_id"],
            status=data["status"],
            measures=[(m[0], m[1], m[2]) for m in data["measures"]],
            error=data["error"],
            model=data["model"],
            seconds=data["seconds"],
            rnnpb_version=data["rnnpb_version"],
        )


def failed(run: AnyRun, error: str, seconds: float = 0.0) -> RunRecord:
    return RunRecord(run.run_id, "failed", [], error, "", seconds)


def _value(value: Any) -> float | None:
    if value is None:
        return None
    value = float(value)
    return None if math.isnan(value) else value


def cached_model(run: RunSpec, out: Path):
    """The model of ``run``'s data, training config and seed: loaded from the cache, or trained
    and saved there (atomically, so a killed worker leaves no half-written model)."""
    from rnnpb.demonstrator import learning_set
    from rnnpb.model import TrainedModel, train
    from rnnpb.robot import JOINT_LIMITS

    path = out / MODELS_DIR / f"{run.model_key}.npz"
    if path.exists():
        return TrainedModel.load(path), path
    sequences = learning_set(
        run.learning_set, seed=run.data_seed, samples_per_pattern=run.samples_per_pattern
    )
    model = train(sequences, JOINT_LIMITS, config=run.train_config)
    path.parent.mkdir(parents=True, exist_ok=True)
    model.save(path)
    return model, path


def measure(run: RunSpec, model) -> list[Measure]:
    """Every measure of ``run.experiments`` on ``model``."""
    from rnnpb.experiments import paper
    from rnnpb.robot import JOINT_LIMITS

    online = run.online.config
    info = model.meta["training"]
    rows: list[Measure] = [
        ("train_mse_max", "", _value(info["mse_max"])),
        ("train_rms_max", "", _value(math.sqrt(info["mse_max"]))),
    ]
    if "synchronization" in run.experiments:
        draw = run.user_draw
        each = paper.synchronizations(model, model.patterns, online, JOINT_LIMITS, (draw,))
        for pattern, sync in zip(model.patterns, each[draw], strict=True):
            rows += [
                ("steps_to_lock", pattern, _value(sync.steps_to_lock)),
                ("pb_settle_steps", pattern, _value(sync.pb_settle_steps)),
                ("phase_lag_steps", pattern, _value(sync.phase_lag_steps)),
                ("recognised", pattern, float(sync.recognized_pattern == pattern)),
                ("pause_relative_motion", pattern, _value(sync.pause_relative_motion)),
                ("pause_steps_to_relock", pattern, _value(sync.pause_steps_to_relock)),
            ]
    if "switching" in run.experiments:
        pairs = paper.switching(model, online, JOINT_LIMITS, seed=run.user_draw).pairs
        rows += [("switch_steps", pair, _value(steps)) for pair, steps in pairs.items()]
    attractors = {}
    if "attractors" in run.experiments or "novel" in run.experiments:
        attractors = paper.learned_attractors(model, run.attractor_steps, run.attractor_transient)
    if "attractors" in run.experiments:
        rows += [("closed_loop_period", name, _value(a.period)) for name, a in attractors.items()]
    if "novel" in run.experiments:
        # Every run together (paper.novel_responses): the cycles at each size, then by hand.
        answers = paper.novel_responses(
            model,
            run.learning_set,
            online,
            attractors,
            run.attractor_steps,
            run.attractor_transient,
            amplitudes=run.novel_amplitudes,
            by_hand=(run.user_draw,),
        )
        keys = [*(f"cycle x{a:g}" for a in run.novel_amplitudes), "by hand"]
        responses = list(zip(keys, answers, strict=True))
        for key, response in responses:
            rows += [
                ("novel_case", key, float(response.case)),
                ("novel_period", key, _value(response.period)),
            ]
    if "follows" in run.experiments:
        follows = paper.follows_every_pattern(model, online, JOINT_LIMITS, seed=run.user_draw)
        rows += [("steps_to_follow", p, _value(v)) for p, v in follows.steps_to_follow.items()]
        rows.append(("follows_all", "", float(follows.follows_all)))
    return rows


def study_folder(out: Path, run: StudyRunSpec) -> Path:
    """Where a study run's own files go (its report.md, results.json, figures …)."""
    return out / STUDIES_DIR / run.run_id


def run_study(run: StudyRunSpec, out: Path) -> tuple[list[Measure], Path]:
    """Run the study into a temporary folder and rename it into place when it has finished,
    so that ``DIR/studies/RUN/`` is either a whole study's output or absent. Measures: each
    of the study's targets, met (1) or not (0), and its run time."""
    import shutil

    from rnnpb.experiments.studies import StudyOptions, load_study

    final = study_folder(out, run)
    partial = final.with_name(f".{final.name}.tmp")
    shutil.rmtree(partial, ignore_errors=True)  # a killed worker's leftover
    partial.mkdir(parents=True)
    try:
        outcome = load_study(run.study).run(
            partial,
            StudyOptions(quick=run.quick, workers=1, seed=run.seed, models=run.models),
        )
    except BaseException:
        shutil.rmtree(partial, ignore_errors=True)  # the error is the record; no half a study
        raise
    shutil.rmtree(final, ignore_errors=True)  # a failed run's earlier try is replaced
    partial.rename(final)
    rows: list[Measure] = [
        ("study_target_met", key, float(target.met)) for key, target in outcome.targets.items()
    ]
    rows.append(("study_runtime_s", "", _value(outcome.runtime_s)))
    return rows, final


def execute_run(run: AnyRun, out: str) -> RunRecord:
    """Train or reuse the model, measure (or run the study); an exception is the run's
    failure, recorded with its error (a worker that dies is the runner's to retry)."""
    start = time.perf_counter()
    folder = Path(out)
    try:
        if isinstance(run, StudyRunSpec):
            rows, path = run_study(run, folder)
        else:
            model, path = cached_model(run, folder)
            rows = measure(run, model)
    except Exception as error:  # noqa: BLE001 - a failed run is recorded, the sweep goes on
        last = traceback.extract_tb(error.__traceback__)[-1]
        where = f" ({os.path.basename(last.filename)}:{last.lineno})"
        return failed(run, f"{type(error).__name__}: {error}{where}", time.perf_counter() - start)
    return RunRecord(
        run.run_id, "ok", rows, "", str(path.relative_to(folder)), time.perf_counter() - start
    )
