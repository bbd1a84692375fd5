"""The numerics side by side in one run, on one core: the on-line step and 16 sessions in one
call, each with the native loop (rnnpb.model.native) and with the loop compiled by numba
(rnnpb.model.online), timed alternately; the learning iteration native and in JAX; the
processor and the instruction sets the code was built for; and the numerics' lines
(tools/numerics_lines.py).

The network is the bench's (``rnnpb bench``): the paper's sizes, random weights, learning set
1's taught hands, so that every step pays for recognition's structure test::

    PYTHONPATH=src .venv/bin/python benchmarks/numerics.py [--steps 300]

For the code an AVX2 processor runs, on a machine with AVX-512::

    RNNPB_NATIVE_CPU=haswell NUMBA_CPU_NAME=haswell NUMBA_CPU_FEATURES= \\
        PYTHONPATH=src .venv/bin/python benchmarks/numerics.py
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

SESSIONS = 16


def main() -> None:
    parser = argparse.ArgumentParser(description=str(__doc__).splitlines()[0])
    parser.add_argument("--steps", type=int, default=300, help="timed steps of each")
    args = parser.parse_args()
    from rnnpb import _xla

    _xla.configure()
    _xla.single_threaded()
    _xla.compilation_cache()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    import numpy as np

    from rnnpb.commands.bench import bench_model, learning_chunk_times, processor_note
    from rnnpb.demonstrator import learning_set
    from rnnpb.model import BatchedMirror, MirrorSystem, NetworkConfig, learning
    from rnnpb.robot import JOINT_LIMITS

    print(processor_note())
    network = NetworkConfig()
    sequences = learning_set("1", seed=0)
    data = learning.prepare_data(sequences, JOINT_LIMITS)
    model = bench_model(network, sequences, data)
    stream = np.concatenate([s.sensory for s in sequences])
    offsets = np.arange(SESSIONS) * 7
    runs = {
        "step, native loop": MirrorSystem(model),
        "step, numba loop": MirrorSystem(model, native=False),
        f"{SESSIONS} sessions, native loop": BatchedMirror(model, SESSIONS),
        f"{SESSIONS} sessions, numba loop": BatchedMirror(model, SESSIONS, native=False),
    }

    def hands(name: str, t: int) -> np.ndarray:
        if "sessions" in name:
            return stream[(t + offsets) % len(stream)]
        return stream[t % len(stream)]

    for t in range(40):
        for name, system in runs.items():
            system.step(hands(name, t))
    times: dict[str, list[float]] = {name: [] for name in runs}
    for t in range(40, 40 + args.steps):
        for name, system in runs.items():
            t0 = time.perf_counter()
            system.step(hands(name, t))
            times[name].append((time.perf_counter() - t0) * 1e3)
    print(
        f"the default on-line step (L = 30, 100 iterations), {args.steps} steps each, alternately:"
    )
    for name, values in times.items():
        one = "step, native loop" if "native" in name else "step, numba loop"
        ratio = np.median(values) / np.median(times[one])
        print(
            f"  {name + ':':<28}{np.median(values):8.3f} ms median, "
            f"{np.percentile(values, 99):8.3f} ms p99 ({ratio:.2f}x one step, same loop)"
        )

    chunk_times = learning_chunk_times(data, network)
    print(
        "the learning iteration (6 sequences x 50 steps, the paper's), medians of 7 chunks of 200:"
    )
    for name, values in chunk_times.items():
        print(f"  {name + ':':<28}{np.median(values):8.4f} ms")
    tool = Path(__file__).resolve().parent.parent / "tools" / "numerics_lines.py"
    print(subprocess.run([sys.executable, str(tool)], capture_output=True, text=True).stdout)


if __name__ == "__main__":
    main()
