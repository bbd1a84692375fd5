"""rnnpb sweep: a grid of learning sets, seeds and settings, on Ray."""

from __future__ import annotations

import argparse

NAME = "sweep"
HELP = "run a grid of learning sets x seeds x settings x user draws on Ray: a Parquet table"
DESCRIPTION = """\
Read the grid from SPEC (TOML: learning sets, training seeds, training and on-line settings,
draws of the user; docs/sweeps.md), train every model (or reuse one already cached in
OUT/models with the same data, config and seed), run the paper's section 3 experiments on it,
and write OUT/results.parquet (one row per run and measure, with the config, seed and version),
OUT/report.md and OUT/results.json (medians and shares within the paper's limits, with 95 %
bootstrap intervals) and OUT/figures/. Runs go to a local Ray instance on this machine's cores
(--workers of them), or to the Ray cluster at --address. Each finished run is kept in
OUT/runs/: rerunning the same command skips them, so an interrupted sweep resumes; a run
whose worker dies is retried; a run that fails is recorded with its error.

Example:
  rnnpb sweep sweeps/larger_set_paper.toml --out results/larger_set_paper
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("spec", metavar="SPEC", help="the sweep's TOML file")
    parser.add_argument("--out", required=True, metavar="DIR", help="output directory")
    parser.add_argument(
        "--address",
        metavar="ADDRESS",
        default=None,
        help="an existing Ray cluster (HOST:PORT, ray://HOST:PORT or auto); "
        "default: a local instance",
    )
    parser.add_argument(
        "--workers",
        type=int,
        default=None,
        metavar="N",
        help="runs at once (default: every CPU of the machine or cluster)",
    )


def run(args: argparse.Namespace) -> int:
    import os

    os.environ.setdefault("MUJOCO_GL", "egl")
    from rnnpb.errors import ConfigError
    from rnnpb.sweeps import load_spec, run_sweep

    if args.workers is not None and args.workers < 1:
        raise ConfigError(f"--workers must be >= 1, got {args.workers}")
    spec = load_spec(args.spec)
    outcome = run_sweep(spec, args.out, address=args.address, workers=args.workers)
    print(
        f"wrote {outcome.table}, {args.out}/report.md and {args.out}/results.json in "
        f"{outcome.runtime_s:.0f} s ({outcome.ran} runs run, "
        f"{len(outcome.records) - outcome.ran} finished before, "
        f"{len(outcome.failed)} failed)"
    )
    return 1 if outcome.failed else 0
