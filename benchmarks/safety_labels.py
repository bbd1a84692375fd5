"""How the safety map labels a PB: the transient skipped and the share of starts that must be
unsafe (rnnpb.safety.ExplorationConfig ``transient`` and ``unsafe_share``), on development
draws only.

For a model, generate closed-loop from many PBs (the exploration's sampling) and from several
starts each, and from the learned PBs from many starts; for each (transient, share) report the
share of explored PBs labelled unsafe and how many learned PBs would be labelled unsafe (a
learned pattern was taught safe: its PB must not be). Usage:

    python benchmarks/safety_labels.py MODEL.npz [--samples 600] [--starts 6] [--seed 0]
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from rnnpb.model import TrainedModel
from rnnpb.safety import ExplorationConfig, SafetyChecker
from rnnpb.safety._explore import generate_from, sample_pbs, sample_starts


def first_unsafe(model, pbs, config, rng, checker):
    """For each PB and start, the first unsafe step (steps when none), (n, starts)."""
    runs = np.repeat(pbs, config.starts, axis=0)
    contexts, inputs = sample_starts(model, len(runs), config, rng)
    motor = generate_from(model, runs, contexts, inputs, config.steps)
    first = np.full(len(runs), config.steps)
    last = np.full(len(runs), -1)
    for i in range(len(runs)):
        unsafe = np.flatnonzero(checker.check(motor[:, i]).unsafe)
        if len(unsafe):
            first[i], last[i] = unsafe[0], unsafe[-1]
    return last.reshape(-1, config.starts)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("model")
    parser.add_argument("--samples", type=int, default=600)
    parser.add_argument("--starts", type=int, default=6)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    model = TrainedModel.load(args.model)
    config = ExplorationConfig(samples=args.samples, starts=args.starts, seed=args.seed)
    checker = SafetyChecker()
    rng = np.random.default_rng([args.seed, 1])
    explored = first_unsafe(model, sample_pbs(model, config), config, rng, checker)
    learned = np.array(list(model.pattern_pb.values()))
    many = ExplorationConfig(samples=1, starts=50, seed=args.seed)
    on_learned = first_unsafe(model, learned, many, rng, checker)
    rows = []
    for transient in (0, 5, 10, 20):
        for share in (1 / args.starts, 0.5, 1.0):
            # A start is unsafe when its last unsafe step comes after the transient.
            unsafe = (explored >= transient).mean(axis=1) >= share - 1e-9
            learned_share = (on_learned >= transient).mean(axis=1)
            rows.append(
                {
                    "transient": transient,
                    "share": round(share, 3),
                    "explored_unsafe": round(float(unsafe.mean()), 3),
                    "learned_unsafe_share_of_starts": [round(float(v), 3) for v in learned_share],
                    "learned_labelled_unsafe": int((learned_share >= share - 1e-9).sum()),
                }
            )
            print(json.dumps(rows[-1]), flush=True)


if __name__ == "__main__":
    main()
