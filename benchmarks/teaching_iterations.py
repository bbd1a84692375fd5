"""How many learning iterations a teaching consolidation needs: the teach study at each count.

Runs `rnnpb study teach`'s full form (every learning set and new shape, the scripted user of
the development draw 100 + seed) once per iteration count, from the same paper-learned
models, without the paced run, and prints each target of the teach exam's definitions beside
each other, with the consolidations' CPU seconds (median and longest).

    .venv/bin/python benchmarks/teaching_iterations.py --models results/demo/models \
        --iterations 10000,20000 --seed 1 --out results/teaching-iterations [--workers 2]

Each count's study is written to OUT/iterations-N-seed-S (report.md, results.json); a folder
that already holds a finished results.json is read, not run again.
"""

from __future__ import annotations

import argparse
import json
import statistics
from dataclasses import replace
from pathlib import Path


def run_one(models: str, iterations: int, seed: int, workers: int, out: Path) -> dict:
    """The results of the teach study's full form with ``iterations`` per consolidation."""
    done = out / "results.json"
    if done.exists():
        data = json.loads(done.read_text())
        if data["jobs_done"] == data["jobs"]:
            return data
    from rnnpb.experiments.scenarios.teaching_scenario import TeachConfig
    from rnnpb.experiments.studies.teach import run_study

    config = TeachConfig(models=models, scenario_seed=100 + seed, workers=workers, paced=None)
    run_study(out, replace(config, consolidation_iterations=iterations))
    return json.loads(done.read_text())


def cpu_seconds(data: dict) -> list[float]:
    """Every consolidation's CPU seconds in a study's runs."""
    return [c["cpu_s"] for run in data["runs"] for c in run.get("consolidations", [])]


def main() -> None:
    from rnnpb import _xla

    _xla.configure()
    _xla.compilation_cache()  # as the rnnpb command: each consolidation need not compile anew
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--models", required=True, help="demo's models directory")
    parser.add_argument("--iterations", default="10000,20000", help="comma-separated counts")
    parser.add_argument("--seed", type=int, default=1, help="development draw 100 + seed")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    counts = [int(n) for n in args.iterations.split(",")]
    studies = {
        n: run_one(
            args.models,
            n,
            args.seed,
            args.workers,
            Path(args.out) / f"iterations-{n}-seed-{args.seed}",
        )
        for n in counts
    }
    names = list(next(iter(studies.values()))["targets"])
    print("| target | " + " | ".join(f"{n} iterations" for n in counts) + " |")
    print("|---|" + "---|" * len(counts))
    for name in names:
        cells = []
        for n in counts:
            t = studies[n]["targets"].get(name, {})
            cells.append(f"{t.get('detail')} ({'met' if t.get('met') else 'not met'})")
        print(f"| {name} | " + " | ".join(cells) + " |")
    cpu = {n: cpu_seconds(d) for n, d in studies.items()}
    print(
        "| consolidation CPU s, median / longest | "
        + " | ".join(
            f"{statistics.median(c):.1f} / {max(c):.1f}" if c else "–" for c in cpu.values()
        )
        + " |"
    )


if __name__ == "__main__":
    main()
