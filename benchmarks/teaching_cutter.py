"""How often the episode cutter keeps each new shape of the teach study's script.

Runs the scripted user of `rnnpb study teach` (a learned pattern, the new shape for 96 steps,
the other learned patterns, a random walk, jerky movement, the new shape again) through the
mirror system of each paper-learned model with no teacher, records each step's novelty word,
and replays `EpisodeCutter` over them with the settings given: per (learning set, shape),
whether an episode of the new shape was kept within its 96 steps, after how many steps, and
whether any episode held unstructured movement or another pattern (docs/teaching.md).

    .venv/bin/python benchmarks/teaching_cutter.py --models results/demo/models --draw 100
        [--workers 2] [--compare episode_cycles=4,interruption_steps=0,min_novel_share=1]

The draw is the study's: the scenario seed is draw + shape index.
"""

from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

SETS = ("1", "2", "3", "4", "full")
SHAPES = ("figure-eight", "diagonal", "one-arm", "asymmetric")


def record(job):
    """The novelty words of one (learning set, shape) run, and what the user did."""
    models, set_name, shape, index, draw = job
    from rnnpb import _xla

    _xla.configure()
    _xla.single_threaded()
    import numpy as np

    from rnnpb.demonstrator import ScenarioSource, learning_set_patterns, make_scenario
    from rnnpb.experiments.scenarios.teaching_scenario import (
        TeachConfig,
        segments,
        starting_models,
    )
    from rnnpb.interaction import InteractionLoop, LoopConfig
    from rnnpb.model import MirrorSystem, OnlineConfig, TrainedModel

    config = TeachConfig(models=models, learning_sets=(set_name,))
    model = TrainedModel.load(starting_models(config, Path(models))[set_name])
    performed = segments(learning_set_patterns(set_name), shape, index, config)
    records = []
    with ScenarioSource(make_scenario(performed, seed=draw + index)) as source:
        mirror = MirrorSystem(model, OnlineConfig.for_model(model).config)
        InteractionLoop(mirror, source, config=LoopConfig(config.dt)).run(on_step=records.append)
    labels = [m for m, n in performed for _ in range(n)][: len(records)]
    return (
        set_name,
        shape,
        np.array([r.observed for r in records]),
        [r.novelty for r in records],
        np.array(labels),
    )


def replay(runs, config) -> dict:
    import numpy as np

    from rnnpb.interaction.teaching import EpisodeCutter

    kept, delays, unstructured, mixed, missed = 0, [], 0, 0, []
    for set_name, shape, observed, words, labels in runs:
        first = int(np.argmax(labels == shape))
        cutter, found = EpisodeCutter(config), None
        for t in range(len(observed)):
            episode = cutter.observe(t, observed[t], words[t])
            if episode is None:
                continue
            span = labels[episode.first_step : episode.last_step + 1]
            if np.isin(span, ("random-walk", "jerky")).any():
                unstructured += 1
            elif not (span == shape).all():
                mixed += 1
            if found is None and (span == shape).any() and episode.first_step < first + 96:
                found = episode.last_step - first
        if found is None:
            missed.append(f"{set_name}/{shape}")
        else:
            kept += 1
            delays.append(found)
    return {
        "kept": f"{kept} of {len(runs)}",
        "median_steps": float(np.median(delays)) if delays else None,
        "worst_steps": max(delays) if delays else None,
        "from_unstructured": unstructured,
        "with_another_pattern": mixed,
        "missed": missed,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--models", default="results/demo/models")
    parser.add_argument("--draw", type=int, default=100)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument(
        "--compare",
        default="episode_cycles=4,interruption_steps=0,min_novel_share=1",
        help="TeachingConfig fields of the other cutter to replay (the former defaults)",
    )
    args = parser.parse_args()
    from rnnpb.interaction.teaching import TeachingConfig

    jobs = [(args.models, s, shape, i, args.draw) for s in SETS for i, shape in enumerate(SHAPES)]
    with ProcessPoolExecutor(args.workers) as pool:
        runs = list(pool.map(record, jobs))
    other = {
        k: (float(v) if "." in v or k == "min_novel_share" else int(v))
        for k, v in (item.split("=") for item in args.compare.split(","))
    }
    compared = TeachingConfig().with_tuning(**other)
    for name, config in (("defaults", TeachingConfig()), (args.compare, compared)):
        print(f"{name}: {replay(runs, config)}", flush=True)


if __name__ == "__main__":
    main()
