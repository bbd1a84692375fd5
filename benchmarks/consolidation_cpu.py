"""What one teaching consolidation costs on one core: the CPU seconds of the process that
does it, as teaching's background process does it (docs/teaching.md).

A new shape of the demonstrator, performed twice (two draws of the user, three cycles each,
as teaching keeps them), is consolidated into a model with teaching's policy
(`rnnpb.interaction.background.teaching_consolidation`), in a fresh process pinned to one core
with nothing else running: first with an empty compilation cache (a machine's first
teaching), then again with the cache it left (every later teaching of the same shape of
data). Each line gives the process's CPU seconds (user + system, from its start to its end,
the figure the teach study records), the consolidation's own and its learning iterations'.

    PYTHONPATH=src .venv/bin/python benchmarks/consolidation_cpu.py \
        --model results/demo/models/set1.npz [--shape figure-eight] [--repeats 2]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time


def consolidate_once(model_path: str, shape: str) -> dict:
    """In this process: one teaching consolidation of ``shape`` into the model."""
    from rnnpb import _xla

    _xla.single_threaded()
    _xla.configure()
    _xla.compilation_cache()
    from rnnpb.demonstrator import make_scenario
    from rnnpb.interaction.background import teaching_consolidation
    from rnnpb.model import TrainedModel, consolidate, rehearse
    from rnnpb.sequences import Sequence

    model = TrainedModel.load(model_path)
    performances = []
    for draw in (1, 2):
        scenario = make_scenario([(shape, 36)], seed=draw, novel=(shape,))
        performances.append(Sequence(scenario.sensory, scenario.motor, "new-1", f"draw {draw}"))
    config = teaching_consolidation(model)
    start = time.process_time()
    learned = consolidate(model, performances, config, grow=True)
    rehearse(model, config.rehearsal_steps, config.rehearsal_transient, config.rehearsal_source)
    history = learned.meta["training"]
    return {
        "consolidation_cpu_s": time.process_time() - start,
        "iterations": history["iterations"],
        "learning_s": history["seconds"],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=str(__doc__).splitlines()[0])
    parser.add_argument("--model", required=True, help="a learned model (.npz)")
    parser.add_argument("--shape", default="figure-eight", help="a new shape of the demonstrator")
    parser.add_argument("--repeats", type=int, default=2, help="runs with the warm cache")
    parser.add_argument("--core", type=int, default=0, help="the core to pin the runs to")
    parser.add_argument("--inner", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.inner:
        print(json.dumps(consolidate_once(args.model, args.shape)))
        return
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "RNNPB_XLA_CACHE": cache, "JAX_COMPILATION_CACHE_DIR": ""}
        for run in ["empty cache", *["warm cache"] * args.repeats]:
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            result = subprocess.run(
                ["taskset", "-c", str(args.core), sys.executable, __file__, "--inner",
                 "--model", args.model, "--shape", args.shape],
                capture_output=True, text=True, env=env, check=True,
            )  # fmt: skip
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            process_cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
            figures = json.loads(str(result.stdout).strip().splitlines()[-1])
            print(
                f"{run:12s} process {process_cpu:5.1f} s CPU, consolidation "
                f"{figures['consolidation_cpu_s']:5.1f} s, its learning "
                f"({figures['iterations']} iterations) {figures['learning_s']:5.1f} s",
                flush=True,
            )


if __name__ == "__main__":
    main()
