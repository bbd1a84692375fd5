"""The incremental study's jobs (each runs in a worker process): a learning set's model
measured, or a pattern added to it by one method and the result measured; the chain; the
larger set's model with each new shape added.
"""

from __future__ import annotations

from collections.abc import Iterator
from concurrent.futures import as_completed
from dataclasses import replace
from pathlib import Path
from typing import Any

from rnnpb.experiments.scenarios.incremental_measures import ModelMeasures, measure
from rnnpb.experiments.scenarios.incremental_scenario import (
    IncrementalConfig,
    add_patterns,
    demonstrations,
    starting_model,
)
from rnnpb.model import TrainedModel, train


def set_job(
    set_name: str,
    method: str | None,
    start_path: str,
    config: IncrementalConfig,
    out_path: str,
    added: str | None = None,
) -> tuple[str, str | None, ModelMeasures]:
    """Measure the starting model (``method`` None) or add a pattern to it by ``method`` —
    ``added``, by default the set's left-out pattern — and measure the result."""
    from rnnpb.demonstrator import learning_set, novel_pattern

    start = TrainedModel.load(start_path)
    original = learning_set(set_name, seed=config.data_seed)
    if method is None:
        return set_name, None, measure(start, "before", config, original)
    added = added or novel_pattern(set_name)
    new = demonstrations((added,), config.new_data_seed)
    model, cpu = add_patterns(start, new, method, config, start_path, replay_data=original)
    model.save(out_path)
    pairs = added if config.quick else None
    measured = measure(model, method, config, [*original, *new], before=start, pairs_with=pairs)
    return set_name, method, replace(measured, cpu_seconds=cpu)


def chain_job(config: IncrementalConfig, out: Path) -> list[ModelMeasures]:
    """Learn ``chain_start``, then add each of ``chain_added`` by rehearsal; measure each."""
    from rnnpb.robot import JOINT_LIMITS

    data = demonstrations(config.chain_start, config.data_seed)
    model = train(data, JOINT_LIMITS, config=config.start_train)
    model.save(out / "models" / "chain_0.npz")
    results = [measure(model, "+".join(config.chain_start), config, data)]
    for k, pattern in enumerate(config.chain_added, start=1):
        new = demonstrations((pattern,), config.new_data_seed)
        parent = str(out / "models" / f"chain_{k - 1}.npz")
        grown, cpu = add_patterns(model, new, "rehearsal", config, parent)
        grown.save(out / "models" / f"chain_{k}.npz")
        data = [*data, *new]
        measured = measure(
            grown,
            f"+{pattern}",
            config,
            data,
            before=model,
            pairs_with=pattern if config.quick else None,
        )
        results.append(replace(measured, cpu_seconds=cpu))
        model = grown
    return results


def study_jobs(pool, config: IncrementalConfig, out: Path) -> Iterator[tuple[int, str, Any]]:
    """Submit the study's jobs to ``pool`` and yield (jobs in all, kind, result) as each
    finishes; kind ``"set"`` (result: learning set, method or None, measures), ``"chain"``
    (the chain's measures) or ``"larger:SHAPE"`` (``"larger:before"``: the larger set's
    model). Method by method, the chain after rehearsal: what the targets judge comes first."""
    models = out / "models"
    starts = {name: starting_model(name, config, models) for name in config.learning_sets}
    jobs = {
        pool.submit(set_job, name, None, starts[name], config, ""): "set"
        for name in config.learning_sets
    }
    for k, method in enumerate(config.methods):
        for name in config.learning_sets:
            path = str(models / f"set{name}_{method}.npz")
            jobs[pool.submit(set_job, name, method, starts[name], config, path)] = "set"
        if k == 0:
            jobs[pool.submit(chain_job, config, out)] = "chain"
            jobs.update(_larger_set_jobs(pool, config, models))
    for future in as_completed(jobs):
        yield len(jobs), jobs[future], future.result()


def _larger_set_jobs(pool, config: IncrementalConfig, models: Path) -> dict[Any, str]:
    """The larger set measured, then each of ``larger_set_shapes`` added to it by rehearsal."""
    if not config.larger_set_shapes:
        return {}
    start = starting_model("full", config, models)
    jobs = {pool.submit(set_job, "full", None, start, config, ""): "larger:before"}
    for shape in config.larger_set_shapes:
        path = str(models / f"full_{shape}_rehearsal.npz")
        jobs[pool.submit(set_job, "full", "rehearsal", start, config, path, shape)] = (
            f"larger:{shape}"
        )
    return jobs
