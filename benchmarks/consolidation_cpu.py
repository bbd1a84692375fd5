"""What one teaching consolidation costs on one core: the CPU seconds of the process that
does it, as teaching's background process does it (docs/teaching.md).

A new shape of the demonstrator, performed twice (two draws of the user, three cycles each,
as teaching keeps them), is kept in a model's memory and consolidated by
`rnnpb.interaction.background.BackgroundConsolidation` with teaching's policy: in a process
forked from the server that imported JAX ahead, on one core, with nothing else running. First
with an empty compilation cache (a machine's first teaching), then again with the cache it
left (every later teaching of the same shape of data). Each line gives the process's CPU
seconds (user + system, from its start to its report: the figure the teach study records) and
its learning's. The server's imports, paid once per session while the loop runs, are timed
apart: a fresh interpreter importing what the server imports.

    PYTHONPATH=src .venv/bin/python benchmarks/consolidation_cpu.py \
        --model results/demo/models/set1.npz [--shape figure-eight] [--repeats 2]
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path


def kept_shape(model_path: str, shape: str, folder: Path) -> tuple[str, list[int]]:
    """A copy of the model in ``folder`` with ``shape`` performed twice kept in its memory."""
    from rnnpb.demonstrator import make_scenario
    from rnnpb.memory import MemoryStore

    path = folder / "model.npz"
    shutil.copyfile(model_path, path)
    with MemoryStore(path) as memory:
        ids = [
            memory.add_episode(
                scenario.sensory,
                scenario.motor,
                source="benchmark",
                model=str(path),
                pattern="new-1",
                n_cycles=3,
            )
            for scenario in (make_scenario([(shape, 36)], seed=d, novel=(shape,)) for d in (1, 2))
        ]
    return str(path), ids


def server_imports_cpu() -> float:
    """CPU seconds of a fresh interpreter importing what the consolidations' server imports."""
    from rnnpb.interaction.background import PRELOAD

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([sys.executable, "-c", "; ".join(f"import {m}" for m in PRELOAD)], check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    parser = argparse.ArgumentParser(description=str(__doc__).splitlines()[0])
    parser.add_argument("--model", required=True, help="a learned model (.npz)")
    parser.add_argument("--shape", default="figure-eight", help="a new shape of the demonstrator")
    parser.add_argument("--repeats", type=int, default=2, help="runs with the warm cache")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as scratch:
        # Set before anything imports JAX or starts the server: a cache of this run's own.
        os.environ["RNNPB_XLA_CACHE"] = str(Path(scratch) / "cache")
        os.environ.pop("JAX_COMPILATION_CACHE_DIR", None)
        from rnnpb import _xla
        from rnnpb.interaction.background import BackgroundConsolidation, start_process_server
        from rnnpb.model import TrainedModel

        _xla.configure()
        _xla.compilation_cache()
        start_process_server()
        print(f"the server's imports (once per session): {server_imports_cpu():.1f} s CPU")
        for k, run in enumerate(["empty cache", *["warm cache"] * args.repeats]):
            folder = Path(scratch) / f"run{k}"
            folder.mkdir()
            path, ids = kept_shape(args.model, args.shape, folder)
            out = folder / "model.v2.npz"
            state = BackgroundConsolidation(path, path, ids, out).wait()
            if state.state != "done":
                raise SystemExit(f"the consolidation failed: {state.message}")
            history = TrainedModel.load(out).meta["training"]
            print(
                f"{run:12s} process {state.cpu_s:5.1f} s CPU, its learning "
                f"({history['iterations']} iterations) {history['seconds']:5.1f} s",
                flush=True,
            )


if __name__ == "__main__":
    main()
