"""Soak test: the interaction loop for many steps — memory footprint and step time must not drift.

Runs :class:`rnnpb.interaction.InteractionLoop` with a :class:`rnnpb.model.MirrorSystem`, the
synthetic demonstrator switching between patterns 1, 2 and 3 on a loop, a
:class:`rnnpb.robot.KinematicRobot` and a session recording to a temporary file, as fast as
possible. Every block of steps it prints the resident memory (VmRSS), the median and 99th
percentile step time, the held steps and the recording's size; at the end, the drift: the
last block's median step time and memory over the first block's.

Run: ``.venv/bin/python benchmarks/soak.py [--steps 100000] [--block 10000] [--model M.npz]``
(without ``--model`` it trains a model on learning set 1 with the fast preset first).
"""

from __future__ import annotations

import argparse
import platform
import resource
import tempfile
import time
from pathlib import Path

import numpy as np


def resident_mib() -> float:
    """The process's resident memory now, MiB (VmRSS; ru_maxrss where /proc is missing)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=100_000, help="steps (default 100000)")
    parser.add_argument(
        "--block", type=int, default=10_000, help="steps per reported block (default 10000)"
    )
    parser.add_argument("--model", help="trained model (.npz); default: train one quickly")
    parser.add_argument("--keep", metavar="CSV", help="keep the session recording here")
    args = parser.parse_args()
    if args.steps < 1 or args.block < 1:
        parser.error("--steps and --block must be >= 1")

    from rnnpb.demonstrator import ScenarioSource, learning_set, switch_scenario
    from rnnpb.interaction import InteractionLoop, LoopConfig, SessionRecorder, read_session
    from rnnpb.model import MirrorSystem, TrainConfig, TrainedModel, train
    from rnnpb.robot import JOINT_LIMITS, KinematicRobot

    if args.model:
        model = TrainedModel.load(args.model)
    else:
        t0 = time.perf_counter()
        model = train(learning_set("1"), JOINT_LIMITS, config=TrainConfig.fast())
        print(
            f"trained a model on learning set 1 (fast preset) in {time.perf_counter() - t0:.1f} s"
        )

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(args.keep) if args.keep else Path(tmp) / "soak-session.csv"
        mirror = MirrorSystem(model)
        source = ScenarioSource(switch_scenario(("1", "2", "3"), seed=0), loop=True)
        robot = KinematicRobot()
        blocks: list[dict[str, float]] = []
        print(
            f"soak: {args.steps} steps, blocks of {args.block}, "
            f"{platform.python_implementation()} {platform.python_version()}, "
            f"{platform.machine()}"
        )
        print(
            f"{'block':>5} {'steps':>9} {'RSS MiB':>8} {'median ms':>10} {'p99 ms':>8} "
            f"{'held':>5} {'file MiB':>9}"
        )
        with source, robot, SessionRecorder(path, model.network.pb_size) as recorder:
            loop = InteractionLoop(mirror, source, robot, recorder, LoopConfig())
            done = 0
            while done < args.steps:
                n = min(args.block, args.steps - done)
                times = np.empty(n)
                held = 0
                for i in range(n):
                    t0 = time.perf_counter()
                    record = loop.step()
                    times[i] = time.perf_counter() - t0
                    held += int(record.held)
                    if not np.all(np.isfinite(record.motor)):
                        raise SystemExit(f"step {record.step}: non-finite motor command")
                done += n
                block = {
                    "steps": done,
                    "rss": resident_mib(),
                    "median": float(np.median(times)) * 1e3,
                    "p99": float(np.percentile(times, 99)) * 1e3,
                    "held": held,
                    "file": path.stat().st_size / 2**20,
                }
                blocks.append(block)
                print(
                    f"{len(blocks):>5} {done:>9} {block['rss']:>8.1f} "
                    f"{block['median']:>10.3f} {block['p99']:>8.3f} {held:>5} "
                    f"{block['file']:>9.2f}",
                    flush=True,
                )
        rows = len(read_session(path)["step"])
    first, last = blocks[0], blocks[-1]
    print(f"recording read back: {rows} rows (expected {args.steps})")
    print(
        f"drift, last block / first block: median step time "
        f"{last['median'] / first['median']:.3f}, resident memory "
        f"{last['rss'] / first['rss']:.3f} ({last['rss'] - first['rss']:+.1f} MiB)"
    )
    if len(blocks) > 2:
        second = blocks[1]
        print(
            f"drift, last block / second block (after warm-up): median step time "
            f"{last['median'] / second['median']:.3f}, resident memory "
            f"{last['rss'] - second['rss']:+.1f} MiB"
        )


if __name__ == "__main__":
    main()
