"""Which PB guard steers better where the PB drives: the barrier or the projection.

Runs the safety study's measured users (development draws, ``SafetySeeds.from_first(SEED)``)
through the study's model and safety map — the folder a development run of
``rnnpb study safety --out DIR`` wrote, DIR/models/set1.npz and set1.safety.npz — unguarded
and steered (steering where the PB drives, no inhibition, no filter) with each guard, and
prints the unsafe commands generated in the PB-driven regimes, all of them and those the
attribution lays on the network's generation, as the study counts them.

The development run's output is kept in ``safety_steering_guard_dev.txt``.

Usage: ``PYTHONPATH=src .venv/bin/python benchmarks/safety_steering_guard.py --study DIR
[--seed 0] [--workers 2]``.
"""

from __future__ import annotations

import argparse
import multiprocessing
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path

import numpy as np


def main() -> None:
    from rnnpb.experiments.scenarios import safety as scenario
    from rnnpb.experiments.studies._pool import worker_init
    from rnnpb.model import OnlineConfig, TrainedModel
    from rnnpb.model.meta import PB_DRIVEN
    from rnnpb.safety import GENERATION, load_safety_map

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--study", required=True, help="a development safety study's folder")
    parser.add_argument("--seed", type=int, default=0, help="the study's first seed")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    model_path = Path(args.study) / "models" / "set1.npz"
    model = TrainedModel.load(model_path)
    meta = load_safety_map(model_path.with_suffix(".safety.npz"), model).meta
    seeds = scenario.SafetySeeds.from_first(args.seed)
    config = scenario.SafetyStudyConfig(("1",), 1000, 300, 2000, 1000, 4, 5, None, False)
    streams = scenario._streams(model, config, seeds.users, seeds.learned, "1")
    arms = {
        "unguarded": (OnlineConfig(), "unguarded"),
        "barrier": (replace(OnlineConfig(), safety_guard="barrier"), "steered"),
        "projection": (replace(OnlineConfig(), safety_guard="projection"), "steered"),
    }
    worker_init()
    pool = ProcessPoolExecutor(
        args.workers, mp_context=multiprocessing.get_context("spawn"), initializer=worker_init
    )
    with pool:
        jobs = {
            (name, label): pool.submit(
                scenario.session_job, str(model_path), meta, online, arm, stream, label
            )
            for name, (online, arm) in arms.items()
            for label, stream in streams.items()
        }
        runs = {key: job.result() for key, job in jobs.items()}
    for name in arms:
        every = generation = 0
        for (arm, _), run in runs.items():
            if arm != name:
                continue
            driven = np.isin(run["regime"], list(PB_DRIVEN)) & (run["generated_unsafe"] != "")
            every += int(driven.sum())
            generation += int((driven & (run["cause"] == GENERATION)).sum())
        where = f"{name:<11} unsafe where the PB drives: {every:5d}"
        print(f"{where}; laid on the generation: {generation}")


if __name__ == "__main__":
    main()
