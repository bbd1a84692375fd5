"""How many whole cycles teaching's episode must hold to keep what a person shows.

The teach study's scripted user shows a new shape three times between other movements, each
showing a few cycles long (:func:`rnnpb.experiments.scenarios.teaching_scenario.segments`).
This runs that stream for each learning set and shape with the episode cutter's
``[teaching.cutter]`` values of each variant (``episode_cycles=2``, ``episode_cycles=3``, as
a ``--config`` file sets them) and counts, per variant: the runs in which two showings of the
shape were kept, those in which it was learned before the third showing began, the third
showing's recognised share (as the study judges it, from one cycle in), and the patterns
learned from random movement.

    PYTHONPATH=src .venv/bin/python benchmarks/teaching_showings.py \
        --sets 1,full --shapes figure-eight,diagonal,one-arm,asymmetric --draw 600 \
        --variants "episode_cycles=2;episode_cycles=3" --dt 0.4 --json showings.json \
        [--models results/demo/models] [--out results/teaching-showings]

The starting models are learned by the paper's algorithm as the teach study learns them
(weights and demonstrations seed 0) unless ``--models`` holds them; run k (over the shapes,
then the sets) draws the user ``--draw + k``. Development draws only: never an exam's.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

from _settings import processor, variant_tables

SETTLE_STEPS = 12  # the third showing judged from one cycle in, at least 12 steps (teach exam)


def run_variant(variant: str, starts: dict[str, str], args, out: Path) -> dict:
    """Every (set, shape) run of one variant, as the teach study runs them."""
    from rnnpb.experiments.scenarios.teaching_measures import (
        UNSTRUCTURED_MOVEMENTS,
        most_performed,
    )
    from rnnpb.experiments.scenarios.teaching_runs import teach_job
    from rnnpb.experiments.scenarios.teaching_scenario import TeachConfig
    from rnnpb.experiments.scenarios.teaching_targets import learned_in_time, third_showing_share
    from rnnpb.interaction.teaching import TeachingConfig
    from rnnpb.presets import Overrides

    cutter = TeachingConfig().overridden(
        Overrides(variant_tables(variant, "teaching.cutter"), variant)
    )
    config = TeachConfig(
        learning_sets=tuple(args.sets),
        shapes=tuple(args.shapes),
        free_shapes=(),
        step_times=(args.dt,),
        dt=args.dt,
        teaching=cutter,
        paced=None,
    )
    runs = []
    for index, shape in enumerate(args.shapes):
        for name in args.sets:
            draw = args.draw + len(runs)
            folder = out / f"{variant}-set{name}-{shape}"
            run = teach_job(name, shape, index, starts[name], config, str(folder), draw)
            runs.append(
                {
                    "set": name,
                    "shape": shape,
                    "draw": draw,
                    "kept_of_shape": sum(most_performed(e) == shape for e in run.episodes),
                    "learned": bool(run.new_pattern),
                    "learned_before_third": learned_in_time(run),
                    "third_recognised": third_showing_share(run, SETTLE_STEPS),
                    "from_random": sum(
                        m in UNSTRUCTURED_MOVEMENTS for m in run.timeline["taught"].values()
                    ),
                }
            )
            print(f"{variant} set {name} {shape}: {runs[-1]}", flush=True)
    return {
        "runs": runs,
        "learned_before_third": sum(r["learned_before_third"] for r in runs),
        "learned": sum(r["learned"] for r in runs),
        "from_random": sum(r["from_random"] for r in runs),
        "third_recognised_mean": sum(r["third_recognised"] for r in runs) / max(1, len(runs)),
        "count": len(runs),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sets", type=lambda s: s.split(","), default=["1", "full"])
    parser.add_argument(
        "--shapes",
        type=lambda s: s.split(","),
        default=["figure-eight", "diagonal", "one-arm", "asymmetric"],
    )
    parser.add_argument("--draw", type=int, default=600, help="the first user draw (600)")
    parser.add_argument(
        "--variants",
        type=lambda s: s.split(";"),
        default=["episode_cycles=2", "episode_cycles=3"],
        help="[teaching.cutter] variants separated by ';' (default "
        "'episode_cycles=2;episode_cycles=3')",
    )
    parser.add_argument("--dt", type=float, default=0.4)
    parser.add_argument("--models", type=Path, default=None)
    parser.add_argument("--json", type=Path, required=True, help="where the figures go")
    parser.add_argument("--out", type=Path, default=None, help="a folder for the runs")
    args = parser.parse_args()
    from rnnpb import configure_xla

    configure_xla()  # before the first JAX computation: the on-line step's fast setting
    from rnnpb.experiments.scenarios.teaching_scenario import TeachConfig, starting_models

    began = time.perf_counter()
    out = args.out or Path(tempfile.mkdtemp(prefix="teaching-showings-"))
    config = TeachConfig(
        learning_sets=tuple(args.sets),
        models=str(args.models) if args.models else None,
        dt=args.dt,
        step_times=(args.dt,),
    )
    starts = starting_models(config, out / "models")
    figures = {
        "variants": {v: run_variant(v, starts, args, out) for v in args.variants},
        "sets": args.sets,
        "shapes": args.shapes,
        "first_draw": args.draw,
        "dt": args.dt,
        "processor": processor(),
        "seconds": time.perf_counter() - began,
    }
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(figures, indent=1))
    for variant, result in figures["variants"].items():
        print(
            f"{variant}: learned before the third showing in {result['learned_before_third']} "
            f"of {result['count']} runs, third showing recognised "
            f"{result['third_recognised_mean']:.0%} on average, {result['from_random']} from "
            "random movement"
        )


if __name__ == "__main__":
    main()
