"""The structure test's periods and level: how unlike its previous cycle a movement's last cycle
is (``rnnpb.structure.cycle_differences``, the on-line detector's measure), for the
demonstrator's new shapes at half, the usual and twice the speed, against random movement
(random walk, jerky targets, a smooth scribble), over development draws.

The detector calls a movement structured when, at some period in ``--lags``, the measure is
below ``structure_level``; the level is chosen between the shapes' values (which must stay below
it at every speed) and the random movements' (which must stay above). The script prints, per
kind and speed, the distribution of the least value over the periods on each judged step, and
the gap between the shapes' highest and the random movements' lowest, with its midpoint: the
value `[recognition]` and `[recognition_untaught]`'s ``structure_level`` take
(`[sources.structure-periods]` in the presets). ``--json FILE`` writes every figure, and the
gap's ends as ``shapes_max`` and ``random_min`` (what ``rnnpb presets evidence --check`` holds
to the presets' expectation).

    .venv/bin/python tools/structure_periods.py --draws 0,1,2,3,4,5 [--lags 5,40] [--steps 300]

Model-free (the measure looks at the observed hands only): seconds. A draw of any study's exam
is refused.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SPEEDS = {"0.5x": 0.5, "1x": 1.0, "2x": 2.0}
MIN_CYCLE_STEPS = 12  # the fewest steps a cycle is compared on (the presets' structure_steps)


def least_differences(
    sensory: np.ndarray, lags: tuple[int, int], steps: int, first: int
) -> np.ndarray:
    """Per step from ``first`` on, once every period can be measured: the least cycle
    difference over the periods ``lags`` (inclusive)."""
    from rnnpb.structure import cycle_differences

    periods = np.arange(lags[0], lags[1] + 1)
    history = lags[1] + max(lags[1], steps)
    out = []
    for t in range(max(first, history), len(sensory) + 1):
        out.append(np.nanmin(cycle_differences(sensory[t - history : t], periods, steps)))
    return np.asarray(out)


def measure(draws: list[int], lags: tuple[int, int], length: int) -> dict[str, np.ndarray]:
    """The least cycle differences of every judged step, by kind: ``shape <speed>`` for the new
    shapes, ``random`` for the unstructured movements."""
    from rnnpb.demonstrator import NEW_SHAPES, UNSTRUCTURED, PatternConfig, make_scenario
    from rnnpb.experiments.scenarios.novelty import PERIOD

    values: dict[str, list[np.ndarray]] = {}
    for draw in draws:
        for name, speed in SPEEDS.items():
            config = PatternConfig(period_steps=PERIOD / speed)
            for shape in NEW_SHAPES:
                steps = round(length * max(1.0, 1.0 / speed))
                scenario = make_scenario([(shape, steps)], seed=draw, config=config)
                # judged from two cycles in: the first cycle has no cycle before it
                first = round(2 * PERIOD / speed)
                values.setdefault(f"shape {name}", []).append(
                    least_differences(scenario.sensory, lags, MIN_CYCLE_STEPS, first)
                )
        for movement in UNSTRUCTURED:
            scenario = make_scenario([(movement, length)], seed=draw)
            values.setdefault("random", []).append(
                least_differences(scenario.sensory, lags, MIN_CYCLE_STEPS, 0)
            )
    return {kind: np.concatenate(v) for kind, v in values.items()}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    parser.add_argument("--draws", default="0,1,2,3,4,5", help="development user draws")
    parser.add_argument("--lags", default="5,40", help="shortest and longest period, steps")
    parser.add_argument("--steps", type=int, default=300, help="steps of each stream")
    parser.add_argument("--json", type=Path, help="also write the figures here")
    args = parser.parse_args(argv)
    sys.path.insert(0, str(ROOT / "src"))
    from rnnpb.experiments.exams import exam_names, load_exam

    draws = [int(d) for d in args.draws.split(",") if d.strip()]
    for name in exam_names():
        taken = set(draws) & load_exam(name).draws()
        if taken:
            parser.error(f"draws {sorted(taken)} are the {name} exam's: use development draws")
    low, high = (int(v) for v in args.lags.split(","))
    values = measure(draws, (low, high), args.steps)
    figures: dict[str, dict[str, float]] = {}
    for kind, v in values.items():
        figures[kind] = {
            "steps": int(v.size),
            "min": float(v.min()),
            "median": float(np.median(v)),
            "p99": float(np.percentile(v, 99)),
            "max": float(v.max()),
        }
        print(
            f"{kind:10s} {v.size:6d} steps: min {v.min():.3f}  median {np.median(v):.3f}  "
            f"p99 {np.percentile(v, 99):.3f}  max {v.max():.3f}"
        )
    shapes = max(f["max"] for k, f in figures.items() if k.startswith("shape"))
    random = figures["random"]["min"]
    print(
        f"shapes at most {shapes:.3f}, random movement at least {random:.3f}: "
        + (
            f"a level between them, midpoint {(shapes + random) / 2:.3f}"
            if shapes < random
            else "they overlap: no level separates them"
        )
    )
    if args.json:
        gap = {"shapes_max": round(shapes, 4), "random_min": round(random, 4)}
        args.json.write_text(
            json.dumps({"lags": [low, high], "draws": draws, **gap, **figures}, indent=1)
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
