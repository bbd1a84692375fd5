"""``rnnpb data``: write the synthetic training data and the paper's Figure 4."""

from __future__ import annotations

import argparse

NAME = "data"
HELP = "write the synthetic demonstrations of the four patterns and Figure 4"
DESCRIPTION = """\
Generate the paper's training data with the synthetic user: each of the four movement patterns
(1 horizontal swing in opposite phase, 2 vertical swing in phase, 3 rotation in opposite phase,
4 rotation in phase), sampled every 0.4 s for 50 steps, two noisy samples per pattern.

Writes:
  DIR/patterns/P_K.csv     sample K of pattern P (step, lhy lhz rhy rhz, lshp ... relp, pattern)
  DIR/learning_sets.json   the files of learning sets 1-4 and the full set
  DIR/figure4.png          hands as seen, robot joints and robot poses per pattern

example:
  rnnpb data --out data/synthetic --seed 0
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--out", required=True, metavar="DIR", help="output directory")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument(
        "--period",
        type=float,
        default=12.0,
        metavar="STEPS",
        help="steps per movement cycle (default 12, i.e. 4.8 s)",
    )
    parser.add_argument("--steps", type=int, default=50, help="steps per sample (default 50)")
    parser.add_argument("--samples", type=int, default=2, help="samples per pattern (default 2)")
    parser.add_argument(
        "--no-render",
        action="store_true",
        help="leave the rendered robot poses out of the figure (no MuJoCo)",
    )


FIGURE_FILE = "figure4.png"


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from rnnpb.analysis.figures import plot_patterns
    from rnnpb.demonstrator import write_dataset

    result = write_dataset(
        args.out,
        seed=args.seed,
        period_steps=args.period,
        n_steps=args.steps,
        samples_per_pattern=args.samples,
    )
    figure = Path(args.out) / FIGURE_FILE
    plot_patterns(result["sequences"], figure, render=not args.no_render)
    print(f"wrote {len(result['files'])} sequences to {result['patterns_dir']}")
    print(f"wrote {result['learning_sets']}")
    print(f"wrote {figure}")
    return 0
