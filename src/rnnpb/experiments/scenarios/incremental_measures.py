"""The incremental study's measures of a model, for its old and new patterns: closed-loop
generation from each learned PB against the model's own generation before and against the
data, lock-on and recognition (paper 3.1), switching for every ordered pair (3.2), the
training error and the time the learning took.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from rnnpb.analysis import metrics
from rnnpb.experiments.paper import (
    Attractor,
    learned_attractors,
    run_scenario,
    switching,
    synchronization,
)
from rnnpb.experiments.scenarios.incremental_scenario import IncrementalConfig
from rnnpb.model import TrainedModel
from rnnpb.model.consolidation import model_joint_limits


@dataclass(frozen=True)
class PatternMeasures:
    """One pattern of one model. ``recognized``: what the on-line recognition said the user
    performs before the pause (:mod:`rnnpb.model.recognition`; None: nothing);
    ``nearest_pb``: the learned pattern whose PB was nearest then (the paper's reading);
    ``generation_vs_before``: RMS distance (normalized joints) of its closed-loop cycle from
    the starting model's, or of the runs as point sets where either is no limit cycle
    (:func:`generation_distance`; None: a pattern the start did not hold);
    ``generation_vs_data``: from the nearest demonstration's cycle."""

    pattern: str
    steps_to_lock: int | None
    recognized: str | None
    nearest_pb: str
    period: float | None
    generation_vs_before: float | None
    generation_vs_data: float


@dataclass(frozen=True)
class ModelMeasures:
    """One model: its patterns' measures, switching per ordered pair, training error.
    ``seconds``: the learning's wall-clock time as the model records it; ``cpu_seconds``: the
    CPU time of the whole consolidation (rehearsal included) in its single-threaded worker,
    which the load of a shared machine does not inflate (None: not measured here)."""

    label: str
    patterns: tuple[str, ...]
    pattern: dict[str, PatternMeasures]
    switching: dict[str, int | None]
    train_mse_max: float
    seconds: float
    iterations: int
    cpu_seconds: float | None = None

    def followed(
        self, lock_limit: float = metrics.LOCK_LIMIT, switch_limit: float = metrics.SWITCH_LIMIT
    ) -> bool:
        """Every pattern locked on within ``lock_limit`` steps and recognised, every switch
        within ``switch_limit`` (default: the paper's)."""
        locks = all(
            m.steps_to_lock is not None
            and m.steps_to_lock <= lock_limit
            and m.recognized == m.pattern
            for m in self.pattern.values()
        )
        switches = all(v is not None and v <= switch_limit for v in self.switching.values())
        return locks and switches

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> ModelMeasures:
        """The measures as ``results.json`` holds them."""
        pattern = {name: PatternMeasures(**m) for name, m in data["pattern"].items()}
        return cls(**{**data, "patterns": tuple(data["patterns"]), "pattern": pattern})

    def old_generation(self) -> list[float]:
        """How far each old pattern's generation moved from the starting model's."""
        return [
            m.generation_vs_before
            for m in self.pattern.values()
            if m.generation_vs_before is not None
        ]


def data_cycles(model: TrainedModel, sequences) -> dict[str, list[np.ndarray]]:
    """The last cycle of each demonstration's motor sequence (normalized joints), by pattern."""
    s = model.network.sensory_size
    out: dict[str, list[np.ndarray]] = {}
    for seq in sequences:
        motor = (seq.motor - model.lower[s:]) / (model.upper[s:] - model.lower[s:])
        found = metrics.periodicity(motor)
        period = found.period or found.best_period
        out.setdefault(seq.pattern, []).append(metrics.last_cycle(motor, period))
    return out


def measure(
    model: TrainedModel,
    label: str,
    config: IncrementalConfig,
    data,
    before: TrainedModel | None = None,
    pairs_with: str | None = None,
) -> ModelMeasures:
    """Every measure of one model (``data``: the demonstrations of its patterns)."""
    limits = model_joint_limits(model)
    attractors = learned_attractors(model, config.attractor_steps, config.attractor_transient)
    start = (
        learned_attractors(before, config.attractor_steps, config.attractor_transient)
        if before is not None
        else {}
    )
    cycles = data_cycles(model, data)
    per_pattern = {}
    for name in model.patterns:
        sync = synchronization(
            model,
            name,
            config.online,
            limits,
            seed=config.scenario_seed,
            before=config.sync_before,
            after=config.sync_before // 2,
        )
        vs_before = generation_distance(attractors[name], start[name]) if name in start else None
        vs_data = (
            min(metrics.cycle_distance(attractors[name].cycle, c) for c in cycles.get(name, []))
            if name in cycles
            else math.nan
        )
        per_pattern[name] = PatternMeasures(
            name,
            sync.steps_to_lock,
            sync.detected_pattern,
            sync.recognized_pattern,
            attractors[name].period,
            vs_before,
            vs_data,
        )
    if pairs_with is None:
        switched = switching(
            model,
            config.online,
            limits,
            seed=config.scenario_seed,
            steps_each=config.switch_steps_each,
        ).pairs
    else:  # the quick form: the pairs with the new pattern only
        switched = switching_with(model, pairs_with, config, limits)
    info = model.meta["training"]
    return ModelMeasures(
        label,
        model.patterns,
        per_pattern,
        switched,
        info["mse_max"],
        float(info["seconds"]),
        int(info["iterations"]),
    )


def generation_distance(after: Attractor, before: Attractor) -> float:
    """How far a pattern's closed-loop generation moved: the distance of the two limit cycles
    (:func:`rnnpb.analysis.metrics.cycle_distance`), or, where either generation is no limit
    cycle, of the two post-transient runs as sets of points
    (:func:`rnnpb.analysis.metrics.attractor_distance`): one period's window of a
    quasi-periodic run depends on where the run stops."""
    if after.period is not None and before.period is not None:
        return metrics.cycle_distance(after.cycle, before.cycle)
    return metrics.attractor_distance(after.motor, before.motor)


def switching_with(
    model: TrainedModel, pattern: str, config: IncrementalConfig, limits: np.ndarray
) -> dict[str, int | None]:
    """:func:`rnnpb.experiments.paper.switching` for the ordered pairs with ``pattern``."""
    from rnnpb.demonstrator import switch_scenario

    pairs = {}
    for other in model.patterns:
        if other == pattern:
            continue
        for a, b in ((other, pattern), (pattern, other)):
            scenario = switch_scenario(
                (a, b), steps_each=config.switch_steps_each, seed=config.scenario_seed
            )
            run = run_scenario(model, scenario, config.online, limits)
            pairs[f"{a}->{b}"] = metrics.steps_to_lock(
                run.motor_error, run.sensory_error, config.switch_steps_each
            )
    return pairs
