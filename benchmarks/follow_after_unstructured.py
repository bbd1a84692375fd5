"""How often a shape is followed within 10 steps when it comes right after unstructured
movement: a shape learned with the others from the start, against the same shape taught.

The teach study judges a taught shape by its next performance, which comes after 60 steps of
jerky movement. This asks how often any learned pattern is followed there: each of ``--draws``
development draws of the user performs 60 steps of jerky movement, then 48 of the shape; the
lock-on (the paper's definition, `rnnpb.analysis.metrics.steps_to_lock`) is counted from the
shape's first step. The models:

- ``start``: learning set 1's patterns and the shape learned together with the paper's
  algorithm (two demonstrations of 50 steps each, `rnnpb demo`'s learning);
- ``taught-D-C``: learning set 1's model (``--model``) with the shape consolidated into it by
  teaching's policy from user draw D's two performances in the teach study's scenario, C whole
  cycles (12 steps each) of each (``A+B``: A of the first, B of the second), beginning 21
  steps into each performance (where teaching's keeper begins its episode of three).

    PYTHONPATH=src .venv/bin/python benchmarks/follow_after_unstructured.py \
        --model results/demo/models/set1.npz [--shape figure-eight] [--taught 101,7320] \
        [--cycles 3,6,6+3] [--draws 9000:40] [--out results/follow-after-unstructured]
"""

from __future__ import annotations

import argparse
import json
from dataclasses import replace
from pathlib import Path

import numpy as np

LEAD_IN = 21  # steps into a performance where the keeper's episode begins
CYCLE = 12  # the demonstrator's period, steps


def learned_from_start(shape: str, path: Path):
    """Learning set 1's patterns and ``shape`` learned together, as the demo learns set 1."""
    from rnnpb.demonstrator import learning_set_patterns, pattern_dataset
    from rnnpb.experiments.scenarios.study_models import paper_training
    from rnnpb.model import TrainedModel, train
    from rnnpb.robot import JOINT_LIMITS

    if not path.exists():
        data = pattern_dataset(0, (*learning_set_patterns("1"), shape))
        train(data, JOINT_LIMITS, config=paper_training("1")).save(path)
    return TrainedModel.load(path)


def performances(set_name: str, shape: str, draw: int, cycles: tuple[int, int]) -> list:
    """The first two performances of ``shape`` by user draw ``draw`` in the teach study's
    scenario for learning set ``set_name``, ``cycles`` whole cycles of each from where the
    keeper's episode begins (sequences named ``new-1``)."""
    from rnnpb.demonstrator import learning_set_patterns, make_scenario
    from rnnpb.experiments.scenarios.teaching_scenario import TeachConfig, segments
    from rnnpb.sequences import Sequence

    performed = segments(learning_set_patterns(set_name), shape, 0, TeachConfig())
    scenario = make_scenario(performed, seed=draw)
    starts = np.cumsum([0] + [n for _, n in performed])[:-1]
    firsts = [int(s) for s, (m, _) in zip(starts, performed, strict=True) if m == shape][:2]
    sequences = []
    for first, count in zip(firsts, cycles, strict=True):
        a, b = first + LEAD_IN, first + LEAD_IN + count * CYCLE
        sequences.append(Sequence(scenario.sensory[a:b], scenario.motor[a:b], "new-1"))
    return sequences


def taught(model_path: str, shape: str, draw: int, cycles: tuple[int, int], path: Path):
    """``shape`` consolidated into the model from draw ``draw``'s two performances."""
    from rnnpb.interaction.background import teaching_consolidation
    from rnnpb.model import TrainedModel, consolidate

    if not path.exists():
        sequences = performances("1", shape, draw, cycles)
        model = TrainedModel.load(model_path)
        learned = consolidate(model, sequences, teaching_consolidation(model), grow=True)
        learned.save(path)
    model = TrainedModel.load(path)
    return replace(model, meta={**model.meta, "taught": {"new-1": shape}})


def locks_after_jerky(model, pattern: str, shape: str, draws: range) -> dict:
    """Lock-on to ``shape`` (the model's ``pattern``) after 60 steps of jerky movement."""
    from rnnpb.analysis import metrics
    from rnnpb.demonstrator import make_scenario
    from rnnpb.experiments.paper import run_scenarios
    from rnnpb.model import OnlineConfig
    from rnnpb.model.consolidation import model_joint_limits

    scenarios = [make_scenario([("jerky", 60), (shape, 48)], seed=d) for d in draws]
    runs = run_scenarios(model, scenarios, OnlineConfig(), model_joint_limits(model))
    locks = [metrics.steps_to_lock(r.motor_error, r.sensory_error, 60) for r in runs]
    settled = np.concatenate([r.sensory_error[72:] for r in runs])
    recognised = np.mean([r.recognised[-1] == pattern for r in runs])
    return {
        "within_10": sum(1 for lock in locks if lock is not None and lock <= 10),
        "runs": len(locks),
        "locks": locks,
        "sensory_error_median": float(np.nanmedian(settled)),
        "sensory_error_p90": float(np.nanpercentile(settled, 90)),
        # the settled steps that alone break a lock-on's run of locked steps
        "settled_above_lock_level": float(
            np.mean(settled[np.isfinite(settled)] >= metrics.SENSORY_LOCK_THRESHOLD)
        ),
        "recognised_at_end": float(recognised),
    }


def main() -> None:
    from rnnpb import _xla

    _xla.configure()
    _xla.compilation_cache()
    parser = argparse.ArgumentParser(description=str(__doc__).splitlines()[0])
    parser.add_argument("--model", required=True, help="learning set 1's model (.npz)")
    parser.add_argument("--shape", default="figure-eight", help="a new shape of the demonstrator")
    parser.add_argument(
        "--taught",
        default="101,7320,9100,9101",
        help='user draws to teach the shape from ("": the shape learned from the start only)',
    )
    parser.add_argument(
        "--cycles", default="3,6,6+3", help="whole cycles taught of each performance (A or A+B)"
    )
    parser.add_argument("--draws", default="9000:40", help="FIRST:COUNT development draws")
    parser.add_argument("--out", default="results/follow-after-unstructured")
    args = parser.parse_args()
    first, count = (int(v) for v in args.draws.split(":"))
    draws = range(first, first + count)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    cases = {"start": (learned_from_start(args.shape, out / f"start-{args.shape}.npz"), args.shape)}
    for draw in (int(d) for d in args.taught.split(",") if d):
        for cycles in args.cycles.split(","):
            counts = [int(c) for c in cycles.split("+")]
            name = f"taught-{draw}-{cycles}"
            path = out / f"{name}-{args.shape}.npz"
            pair = (counts[0], counts[-1])
            cases[name] = (taught(args.model, args.shape, draw, pair, path), "new-1")
    results = {}
    print(
        f"| model | within 10 steps of {len(draws)} | sensory error median / p90 | "
        "settled steps above the lock-on level |"
    )
    print("|---|---|---|---|")
    for name, (model, pattern) in cases.items():
        r = results[name] = locks_after_jerky(model, pattern, args.shape, draws)
        print(
            f"| {name} | {r['within_10']} | {r['sensory_error_median']:.4f} / "
            f"{r['sensory_error_p90']:.4f} | {100 * r['settled_above_lock_level']:.1f} % |",
            flush=True,
        )
    (out / "results.json").write_text(
        json.dumps({"args": vars(args), "draws": [first, count], "results": results}, indent=1)
    )


if __name__ == "__main__":
    main()
