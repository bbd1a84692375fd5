"""What a preset's learning reaches on a learning set, and its variants beside it.

Learns one learning set of the demonstrator (its draw ``--data-seed``, the weights' seed
``--seed``) with the preset's ``[learning]`` values and with each variant, and prints per
variant: the worst output's training error (MSE, the paper's "< 0.0003" read as a mean
square), the learning's wall-clock and CPU seconds on this machine, and how the learned PBs
lie: the largest distance of a sequence's PB from the centre (0.5 in every unit; "every PB
near 0.5" when small), the least distance between two patterns' mean PBs and the largest
between two demonstrations of one pattern ("each pattern its own region" when the first is
larger than the second), and the demonstrations whose PB is nearest their own pattern's mean.
The evidence of ``[learning]`` and ``[learning.pb]`` in both preset files
(``[sources.learning-rates]``, ``[sources.fast-learning]``).

    PYTHONPATH=src .venv/bin/python benchmarks/learning_presets.py --preset paper \\
        --variants default learning_rate=0.3 pb.learning_rate=0.05 [--json FILE]
    PYTHONPATH=src .venv/bin/python benchmarks/learning_presets.py --preset fast \\
        --variants default iterations=4000

A variant is ``default`` or ``key=value[,key=value]`` over ``[learning]`` (``pb.KEY`` for
``[learning.pb]``; ``iterations`` and ``input_noise`` are settings, replaced as given). The
models are learned in this process, one after the other, with the package's native
iterations where they apply (as ``rnnpb train``). A seeded learning repeats bit for bit on
one machine; the errors agree to about 1e-6 across machines.
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _settings import apply_variant, processor  # noqa: E402


def pb_layout(model) -> dict[str, float]:
    """Where the learned PBs lie (see the module)."""
    pbs = np.asarray(model.sequence_pb)
    names = np.asarray(model.sequence_patterns)
    means = model.pattern_pb
    between = [
        float(np.linalg.norm(means[a] - means[b]))
        for a, b in itertools.combinations(model.patterns, 2)
    ]
    within = [
        float(np.linalg.norm(x - y))
        for name in model.patterns
        for x, y in itertools.combinations(pbs[names == name], 2)
    ]
    order = list(model.patterns)
    nearest = [order[int(np.argmin([np.linalg.norm(pb - means[n]) for n in order]))] for pb in pbs]
    return {
        "pb_from_centre_max": round(float(np.abs(pbs - 0.5).max()), 4),
        "pb_nearest_own": int(sum(a == b for a, b in zip(nearest, names, strict=True))),
        "sequences": len(pbs),
        "pb_between_patterns_min": round(min(between), 4) if between else float("nan"),
        "pb_within_pattern_max": round(max(within), 4) if within else 0.0,
    }


def learn(preset: str, variant: str, set_name: str, data_seed: int, seed: int) -> dict:
    """One variant's learning and its figures."""
    from rnnpb.demonstrator import learning_set
    from rnnpb.model import TrainConfig, train
    from rnnpb.robot import JOINT_LIMITS

    config = apply_variant(TrainConfig.from_preset(preset, seed=seed), variant, "learning")
    data = learning_set(set_name, seed=data_seed)
    wall, cpu = time.perf_counter(), time.process_time()
    model = train(data, JOINT_LIMITS, config=config)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    training = model.meta["training"]
    return {
        "iterations": int(training["iterations"]),
        "mse_max": float(f"{training['mse_max']:.4g}"),
        "mse_mean": float(f"{training['mse_mean']:.4g}"),
        "seconds": round(wall, 2),
        "cpu_seconds": round(cpu, 2),
        **pb_layout(model),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    parser.add_argument("--preset", choices=("paper", "fast"), default="paper")
    parser.add_argument("--set", default="1", help="the learning set (1-4, full)")
    parser.add_argument("--data-seed", type=int, default=0, help="the demonstrations' draw")
    parser.add_argument("--seed", type=int, default=0, help="the weights' seed")
    parser.add_argument(
        "--variants", nargs="+", default=["default"], help="default, or key=value[,key=value]"
    )
    parser.add_argument("--json", type=Path, help="also write the figures here")
    args = parser.parse_args(argv)
    from rnnpb import _xla

    _xla.configure()
    figures = {}
    for variant in args.variants:
        figures[variant] = learn(args.preset, variant, args.set, args.data_seed, args.seed)
        print(f"{variant}: {json.dumps(figures[variant])}", flush=True)
    result = {
        "preset": args.preset,
        "set": args.set,
        "data_seed": args.data_seed,
        "seed": args.seed,
        "machine": processor(),
        "figures": figures,
    }
    if args.json:
        args.json.write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
