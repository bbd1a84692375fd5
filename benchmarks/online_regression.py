"""The on-line regression's values by the paper's measures, the preset's against variants.

For each learning set's model and each draw of the user (scenario seeds), runs the demo's
experiments 3.1 and 3.2 (:func:`rnnpb.experiments.paper.draws`: the user performs each
learned pattern, pauses and goes on; switches between every ordered pair) with the model's
own on-line regression (``OnlineConfig.for_model``: the paper preset's gated regression for
the paper's models, the fast preset's ungated one for the fast preset's) and with each
variant, and prints per variant, over every set, pattern and draw:

- ``lock``: runs locked on within 10 steps (the paper's "about 10"), of all, and the range
  of the steps it took;
- ``settled``: runs whose PB settled within 20 steps;
- ``relock``: runs that locked on again within 5 steps after the pause;
- ``switch``: switches followed within 15 steps, of all, the range of the steps it took and
  the switches never followed.

The limits are :mod:`rnnpb.analysis.metrics`'. The evidence of ``[online]`` and
``[online.pb]`` in both preset files (``[sources.onset]``, ``[sources.online-pb]``,
``[sources.surprise-gate]``, ``[sources.phase-restarts]``, ``[sources.ungated]``).

    PYTHONPATH=src .venv/bin/python benchmarks/online_regression.py --preset paper \\
        --sets 1 --draws 100 --out DIR \\
        --variants default optimize_onset=false motor_input=recorded [--json FILE]

A variant is ``default`` or ``key=value[,key=value]`` over ``[online]`` (``pb.KEY`` for
``[online.pb]``). ``--models DIR`` takes the models ``rnnpb demo`` wrote (``set1.npz`` ...);
without it each set's model is learned as the demo learns it (the paper preset: the paper's
algorithm, 50,000 iterations; the fast preset: its own 3,000) with weights ``--seed`` on the
demonstrator's draw 0, into ``DIR/models`` (``DIR/fast-models`` for the fast preset), and
taken from there on the next run. Draws are development draws: a draw of a study's exam is
refused.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _settings import apply_variant, processor  # noqa: E402


def models_of(args: argparse.Namespace) -> dict[str, str]:
    """Each learning set's model file: ``--models``', else learned into the output folder."""
    from dataclasses import replace

    from rnnpb.experiments.scenarios.study_models import paper_training, study_models
    from rnnpb.model import TrainConfig

    sets = tuple(s.strip() for s in args.sets.split(",") if s.strip())
    folder = Path(args.out) / ("models" if args.preset == "paper" else "fast-models")

    def learning(name: str) -> TrainConfig:
        if args.preset == "paper":
            return paper_training(name, args.seed)
        return replace(TrainConfig.fast(), seed=args.seed)

    return study_models(sets, args.models, folder, learning, reuse=True)


def measured(model, online, draws: list[int]) -> list[dict]:
    """Every run's measures: one row per (draw, pattern) and per (draw, switch)."""
    from rnnpb.experiments.paper import draws as run_draws
    from rnnpb.model.consolidation import model_joint_limits

    rows = []
    for draw, result in run_draws(model, online, model_joint_limits(model), draws).items():
        for sync in result.synchronization:
            rows.append(
                {
                    "draw": draw,
                    "pattern": sync.pattern,
                    "lock": sync.steps_to_lock,
                    "settle": sync.pb_settle_steps,
                    "relock": sync.pause_steps_to_relock,
                }
            )
        for pair, steps in result.switching.pairs.items():
            rows.append({"draw": draw, "switch": pair, "steps": steps})
    return rows


def summary(rows: list[dict]) -> dict:
    """The counts and ranges of the module's list, over ``rows``."""
    from rnnpb.analysis import metrics

    def within(values: list, limit: int) -> int:
        return sum(v is not None and v <= limit for v in values)

    def span(values: list) -> list[int] | None:
        taken = [v for v in values if v is not None]
        return [min(taken), max(taken)] if taken else None

    locks = [r["lock"] for r in rows if "pattern" in r]
    settles = [r["settle"] for r in rows if "pattern" in r]
    relocks = [r["relock"] for r in rows if "pattern" in r]
    switches = [r["steps"] for r in rows if "switch" in r]
    return {
        "runs": len(locks),
        "lock_within": within(locks, metrics.LOCK_LIMIT),
        "lock_steps": span(locks),
        "settled_within": within(settles, metrics.SETTLE_LIMIT),
        "relock_within": within(relocks, metrics.RELOCK_LIMIT),
        "switches": len(switches),
        "switch_within": within(switches, metrics.SWITCH_LIMIT),
        "switch_steps": span(switches),
        "switch_never": sum(v is None for v in switches),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    parser.add_argument("--preset", choices=("paper", "fast"), default="paper")
    parser.add_argument("--models", help="the demo's models folder (default: learn them)")
    parser.add_argument("--sets", default="1,2,3,4", help="learning sets, e.g. 1,2,3,4")
    parser.add_argument("--draws", default="100", help="user draws (scenario seeds), e.g. 100,200")
    parser.add_argument("--seed", type=int, default=0, help="the learned models' weights")
    parser.add_argument(
        "--variants", nargs="+", default=["default"], help="default, or key=value[,key=value]"
    )
    parser.add_argument("--out", required=True, help="folder for the learned models")
    parser.add_argument("--json", type=Path, help="also write the figures here")
    args = parser.parse_args(argv)
    draws = [int(d) for d in args.draws.split(",") if d.strip()]

    from rnnpb import _xla

    _xla.configure()
    from rnnpb.experiments.exams import exam_names, load_exam
    from rnnpb.model import OnlineConfig, TrainedModel

    for name in exam_names():
        taken = set(draws) & load_exam(name).draws()
        if taken:
            parser.error(f"draws {sorted(taken)} are the {name} exam's: use development draws")
    started = time.perf_counter()
    models = {name: TrainedModel.load(path) for name, path in models_of(args).items()}
    figures, by_set = {}, {}
    for variant in args.variants:
        rows = []
        for name, model in models.items():
            online = apply_variant(OnlineConfig.for_model(model).config, variant, "online")
            these = measured(model, online, draws)
            by_set.setdefault(variant, {})[name] = summary(these)
            rows += [{"set": name, **row} for row in these]
        figures[variant] = summary(rows)
        print(f"{variant}: {json.dumps(figures[variant])}", flush=True)
    result = {
        "preset": args.preset,
        "sets": list(models),
        "draws": draws,
        "seed": args.seed,
        "machine": processor(),
        "seconds": round(time.perf_counter() - started, 1),
        "figures": figures,
        "by_set": by_set,
    }
    if args.json:
        args.json.write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
