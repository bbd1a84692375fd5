"""A consolidation's policy against its variants, by the incremental study's measures.

For each learning set's model and each draw ``d``, adds the set's left-out pattern by
rehearsal (the paper's consolidation, section 4.1) under the model's preset's
``[consolidation]`` policy and under each variant, and measures the result as
``rnnpb study incremental --seed d`` does (the new pattern's demonstrations drawn with seed
``d``, the user with scenario seed 100 + ``d``;
:func:`rnnpb.experiments.scenarios.incremental_measures.measure`). Prints per variant, over
every set and draw:

- ``followed``: learning sets whose every pattern locks on within 10 steps and is
  recognised, and whose every switch is followed within 15 (the paper's limits);
- ``old_within``: old patterns whose closed-loop cycle stays within RMS 0.05 of the starting
  model's (:data:`rnnpb.analysis.metrics.SIMILAR_CYCLE`), of all, and the worst distance;
- the consolidations' CPU seconds (median).

The evidence of ``[consolidation]`` in both preset files (``[sources.consolidation-noise]``,
``[sources.consolidation-start]``, ``[sources.function-rehearsal]``,
``[sources.rehearsal-cycle]``).

    PYTHONPATH=src .venv/bin/python benchmarks/consolidation_policy.py --out DIR \\
        --sets 1,2,3,4 --draws 0 --variants default input_noise=0 [--json FILE]

A variant is ``default`` or ``key=value[,key=value]`` over ``[consolidation]``
(``iterations=N`` replaces the learning's iterations). ``--models DIR`` takes the models
``rnnpb demo`` wrote (``set1.npz`` ...); without it each set's model is learned as the demo
learns it (the paper's algorithm, weights seed 0, the demonstrator's draw 0) into
``DIR/models`` and taken from there on the next run. A draw of a study's exam is refused.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _settings import processor, variant_tables  # noqa: E402


def one_case(path: str, set_name: str, draw: int, variant: str) -> dict:
    """Set ``set_name``'s model with its left-out pattern added under ``variant``, measured."""
    from rnnpb.analysis import metrics
    from rnnpb.demonstrator import learning_set, novel_pattern
    from rnnpb.experiments.scenarios.incremental_measures import measure
    from rnnpb.experiments.scenarios.incremental_scenario import IncrementalConfig, demonstrations
    from rnnpb.model import TrainedModel, consolidate, consolidation_config
    from rnnpb.presets import Overrides

    start = TrainedModel.load(path)
    tables = variant_tables(variant, "consolidation")
    table = dict(tables.get("consolidation", {}))
    iterations = table.pop("iterations", None)
    policy = consolidation_config(
        start,
        "add",
        iterations=iterations,
        overrides=Overrides({"consolidation": table}, f"variant {variant}") if table else None,
    )
    config = IncrementalConfig(new_data_seed=draw, scenario_seed=100 + draw, workers=1)
    added = novel_pattern(set_name)
    new = demonstrations((added,), config.new_data_seed)
    original = learning_set(set_name, seed=config.data_seed)
    cpu = time.process_time()
    grown = consolidate(start, new, policy, parent=path)
    cpu = time.process_time() - cpu
    measured = measure(grown, variant, config, [*original, *new], before=start)
    old = measured.old_generation()
    return {
        "set": set_name,
        "draw": draw,
        "variant": variant,
        "added": added,
        "followed": measured.followed(),
        "old_within": sum(d <= metrics.SIMILAR_CYCLE for d in old),
        "old": len(old),
        "old_worst": round(max(old), 4) if old else None,
        "locks": {name: m.steps_to_lock for name, m in measured.pattern.items()},
        "switches_beyond": sorted(
            pair
            for pair, steps in measured.switching.items()
            if steps is None or steps > metrics.SWITCH_LIMIT
        ),
        "iterations": policy.train.iterations if policy.train else None,
        "cpu_s": round(cpu, 1),
    }


def summary(rows: list[dict]) -> dict:
    """The counts of the module's list over ``rows``."""
    worst = [r["old_worst"] for r in rows if r["old_worst"] is not None]
    return {
        "sets": len(rows),
        "followed": sum(r["followed"] for r in rows),
        "old": sum(r["old"] for r in rows),
        "old_within": sum(r["old_within"] for r in rows),
        "old_worst": max(worst) if worst else None,
        "cpu_s_median": round(statistics.median(r["cpu_s"] for r in rows), 1),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    parser.add_argument("--models", help="the demo's models folder (default: learn them)")
    parser.add_argument("--sets", default="1,2,3,4", help="learning sets (1-4)")
    parser.add_argument("--draws", default="0", help="draws d, e.g. 0,1")
    parser.add_argument(
        "--variants", nargs="+", default=["default"], help="default, or key=value[,key=value]"
    )
    parser.add_argument("--out", required=True, help="folder for the learned models")
    parser.add_argument("--json", type=Path, help="also write the figures here")
    args = parser.parse_args(argv)
    draws = [int(d) for d in args.draws.split(",") if d.strip()]
    sets = tuple(s.strip() for s in args.sets.split(",") if s.strip())

    from rnnpb import _xla

    _xla.configure()
    from rnnpb.experiments.exams import exam_names, load_exam
    from rnnpb.experiments.scenarios.study_models import paper_training, study_models

    used = {d for d in draws} | {100 + d for d in draws}
    for name in exam_names():
        taken = used & load_exam(name).draws()
        if taken:
            parser.error(f"draws {sorted(taken)} are the {name} exam's: use development draws")
    started = time.perf_counter()
    models = study_models(sets, args.models, Path(args.out) / "models", paper_training, reuse=True)
    rows = []
    for variant in args.variants:
        for set_name in sets:
            for draw in draws:
                rows.append(one_case(models[set_name], set_name, draw, variant))
                print(json.dumps(rows[-1]), flush=True)
    figures = {v: summary([r for r in rows if r["variant"] == v]) for v in args.variants}
    for variant, figure in figures.items():
        print(f"{variant}: {json.dumps(figure)}")
    result = {
        "sets": list(sets),
        "draws": draws,
        "machine": processor(),
        "seconds": round(time.perf_counter() - started, 1),
        "figures": figures,
        "cases": rows,
    }
    if args.json:
        args.json.write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
