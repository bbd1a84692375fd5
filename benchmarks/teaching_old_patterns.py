"""What a teaching consolidation does to the old patterns, for the policy and its variants.

The teach study judges the old patterns by the paper's measures after each teaching: lock-on
from rest (≤ 10 steps) and switching for every ordered pair (≤ 15). This runs one
consolidation at a time, outside the interaction loop, so that its variants can be set side
by side on the same data:

- the new shape taught from a user draw's two performances in the teach study's scenario,
  6 whole cycles of the first and 3 of the second (what teaching learns when the second
  performance is kept while the first has grown), beginning 21 steps into each;
- consolidated by teaching's policy (``policy``), by it with another iteration count
  (``iterations:N``), with Adam at a learning rate for N iterations (``adam:RATExN``), or
  with other values of the preset's ``[teaching]`` table, as a ``--config`` file sets them
  (``teaching:input_noise=0.02``, ``teaching:hold_old_pb=first-half+new_pb_start=farthest``);
- measured as the study measures: the old patterns' lock-ons and switches beyond the
  paper's limits, the new pattern's lock-on from rest, the new shape followed within 10
  steps after 60 steps of jerky movement (20 development draws of the user, 9000-9019),
  and the consolidation's CPU seconds in this process (compiled programs warm after the
  first).

    PYTHONPATH=src .venv/bin/python benchmarks/teaching_old_patterns.py \
        --models results/demo/models --sets full,1 --shapes figure-eight,diagonal \
        --draws 101,7320,9100,9101 --variants policy,iterations:40000 \
        [--out results/teaching-old-patterns]

Each case's figures are written to OUT/results.jsonl as they come (a case already there is
read, not run again), and a table per variant is printed at the end.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
import tomllib
from dataclasses import replace
from pathlib import Path

CYCLES = (6, 3)  # whole cycles of the first and the second performance


def model_path(models: Path, set_name: str) -> Path:
    """The demo's layout: set1.npz ... set4.npz, full.npz (or full_seed0.npz)."""
    if set_name == "full":
        for name in ("full.npz", "full_seed0.npz"):
            if (models / name).exists():
                return models / name
        raise SystemExit(f"{models}: no full.npz or full_seed0.npz")
    return models / f"set{set_name}.npz"


def consolidation(model, variant: str):
    """Teaching's consolidation of ``model``, or the variant named."""
    from rnnpb.interaction.background import teaching_consolidation
    from rnnpb.presets import Overrides

    config = teaching_consolidation(model)
    assert config.train is not None
    kind, _, value = variant.partition(":")
    if kind == "policy":
        return config
    if kind == "iterations":
        return replace(config, train=replace(config.train, iterations=int(value)))
    if kind == "adam":
        rate, iterations = value.split("x")
        learning = config.train.with_tuning(optimizer="adam", learning_rate=float(rate))
        return replace(config, train=replace(learning, iterations=int(iterations)))
    if kind == "teaching":
        # another of the preset's [teaching] values, as a --config file would set it
        table = {}
        for pair in value.split("+"):
            key, _, text = pair.partition("=")
            try:
                table[key] = tomllib.loads(f"v = {text}")["v"]
            except tomllib.TOMLDecodeError:
                table[key] = text
        return teaching_consolidation(model, overrides=Overrides({"teaching": table}, variant))
    raise SystemExit(
        f"unknown variant {variant!r}: policy, iterations:N, adam:RATExN or "
        "teaching:KEY=VALUE[+KEY=VALUE]"
    )


def one_case(models: Path, set_name: str, shape: str, draw: int, variant: str) -> dict:
    """One consolidation and its measures."""
    import follow_after_unstructured as follow

    from rnnpb.experiments.scenarios.teaching_measures import paper_measures
    from rnnpb.experiments.scenarios.teaching_scenario import TeachConfig
    from rnnpb.model import TrainedModel, consolidate

    model = TrainedModel.load(model_path(models, set_name))
    config = consolidation(model, variant)
    start = time.process_time()
    taught = follow.performances(set_name, shape, draw, CYCLES)
    learned = consolidate(model, taught, config, grow=True)
    cpu = time.process_time() - start
    learned = replace(learned, meta={**learned.meta, "taught": {"new-1": shape}})
    measures = paper_measures(learned, TeachConfig(), "new-1")
    old = tuple(p for p in learned.patterns if p != "new-1")
    locks = {p: measures.lock[p] for p in old}
    switches = measures.switching_among(old)
    misses = [f"lock {p} {v}" for p, v in locks.items() if v is None or v > 10] + [
        f"switch {k} {v}" for k, v in switches.items() if v is None or v > 15
    ]
    after_jerky = follow.locks_after_jerky(learned, "new-1", shape, range(9000, 9020))
    return {
        "set": set_name,
        "shape": shape,
        "draw": draw,
        "variant": variant,
        "cpu_s": round(cpu, 2),
        "old_measures": len(locks) + len(switches),
        "old_misses": misses,
        "new_lock_from_rest": measures.lock["new-1"],
        "followed_after_jerky": after_jerky["within_10"],
        "after_jerky_runs": after_jerky["runs"],
    }


def main() -> None:
    import sys

    from rnnpb import _xla

    _xla.configure()
    _xla.compilation_cache()
    sys.path.insert(0, str(Path(__file__).parent))  # follow_after_unstructured
    parser = argparse.ArgumentParser(description=str(__doc__).splitlines()[0])
    parser.add_argument("--models", required=True, help="demo's models directory")
    parser.add_argument("--sets", default="full,1", help="learning sets (1-4, full)")
    parser.add_argument("--shapes", default="figure-eight,diagonal", help="new shapes")
    parser.add_argument("--draws", default="101,7320,9100,9101", help="user draws to teach from")
    parser.add_argument("--variants", default="policy,iterations:40000")
    parser.add_argument("--out", default="results/teaching-old-patterns")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    table = out / "results.jsonl"
    done = [json.loads(line) for line in table.read_text().splitlines()] if table.exists() else []
    key = ("set", "shape", "draw", "variant")
    seen = {tuple(r[k] for k in key) for r in done}
    for variant in args.variants.split(","):
        for set_name in args.sets.split(","):
            for shape in args.shapes.split(","):
                for draw in (int(d) for d in args.draws.split(",")):
                    if (set_name, shape, draw, variant) in seen:
                        continue
                    row = one_case(Path(args.models), set_name, shape, draw, variant)
                    done.append(row)
                    with table.open("a") as f:
                        f.write(json.dumps(row) + "\n")
                    print(json.dumps(row), flush=True)
    print("| variant | old misses | of | followed after jerky | CPU s, median / longest |")
    print("|---|---|---|---|---|")
    for variant in args.variants.split(","):
        rows = [r for r in done if r["variant"] == variant]
        if rows:
            cpu = [r["cpu_s"] for r in rows]
            print(
                f"| {variant} | {sum(len(r['old_misses']) for r in rows)} | "
                f"{sum(r['old_measures'] for r in rows)} | "
                f"{sum(r['followed_after_jerky'] for r in rows)} of "
                f"{sum(r['after_jerky_runs'] for r in rows)} | "
                f"{statistics.median(cpu):.1f} / {max(cpu):.1f} |"
            )


if __name__ == "__main__":
    main()
