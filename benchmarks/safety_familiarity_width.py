"""The familiarity's kernel width (rnnpb.safety.MetaConfig.familiarity_width), chosen on
development draws: the safety study's familiarity AUC (PBs lived through in the measured
sessions with everything on against as many uniform PBs) for several widths, with the map a
development run of the study learned.

    python benchmarks/safety_familiarity_width.py STUDY_OUT [--seed 0] [--workers 2]

STUDY_OUT: the output of `rnnpb study safety --models DIR --out STUDY_OUT` (its model and
map under STUDY_OUT/models).
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from rnnpb.experiments.scenarios.safety import (
    SafetySeeds,
    SafetyStudyConfig,
    _streams,
    familiarity,
    session_job,
)
from rnnpb.experiments.studies import StudyOptions
from rnnpb.experiments.studies._pool import worker_init
from rnnpb.model import OnlineConfig, TrainedModel
from rnnpb.safety import load_safety_map, new_map


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("out")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    model_path = Path(args.out) / "models" / "set1.npz"
    model = TrainedModel.load(model_path)
    maps = load_safety_map(model_path.with_name("set1.safety.npz"), model)
    config = SafetyStudyConfig.for_options(StudyOptions(seed=args.seed))
    seeds = SafetySeeds.from_first(args.seed)
    streams = _streams(model, config, seeds.users, seeds.learned, "1")
    spawn = multiprocessing.get_context("spawn")  # JAX runs here already: no fork
    with ProcessPoolExecutor(args.workers, mp_context=spawn, initializer=worker_init) as pool:
        jobs = [
            pool.submit(session_job, str(model_path), maps.meta, OnlineConfig(), "everything", s, k)
            for k, s in streams.items()
        ]
        lived = np.concatenate([job.result()["pb"] for job in jobs])[:: config.lived_every]
    for width in (0.02, 0.03, 0.04, 0.05, 0.08):
        changed = new_map(model, maps.meta, maps.experienced, maps.unsafe, width, maps.info)
        print(json.dumps({"width": width, **familiarity(changed, lived, seeds.unknown)}))


if __name__ == "__main__":
    main()
