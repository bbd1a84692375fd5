"""rnnpb demo: reproduce the paper's experiments with numbers and figures."""

from __future__ import annotations

import argparse

NAME = "demo"
HELP = "reproduce the paper's experiments: report.md, results.json, figures"
DESCRIPTION = """\
Learn learning sets 1-4 and the 4-pattern set, run every experiment of the paper's
section 3 (synchronization and pause, switching, novel patterns and attractors, the larger
set) and write OUT/report.md (measure | paper | ours, figures embedded), OUT/results.json
(every measure, the config and versions), OUT/figures/, OUT/models/ and OUT/data/.

Every measure is also reported over all networks and draws of the user, with 95 % bootstrap
intervals: three networks per learning set by default (--quick: two), --training-seeds N
for N; the figures show the first seed's. The jobs run on a local Ray instance with
--workers workers. The full run learns with the paper's algorithm and also runs the
paper's own on-line regression on the first seed's models for comparison. --quick
learns with the fast preset, keeps the lock-on and switching experiments whole and
shortens the rest; its models go with the ungated on-line regression, which
`rnnpb interact` picks for them by itself.

Example:
  rnnpb demo --out results/demo
  rnnpb interact --model results/demo/models/set1.npz --source scenario:switch:1,2,3 --out run/
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--out",
        default="results/demo",
        metavar="DIR",
        help="output directory (default results/demo)",
    )
    parser.add_argument("--quick", action="store_true", help="the short run")
    parser.add_argument(
        "--workers", type=int, default=2, help="runs at once, on a local Ray instance (default 2)"
    )
    parser.add_argument(
        "--samples-per-pattern",
        type=int,
        default=2,
        metavar="N",
        help="demonstrations of each pattern in every learning set (default 2, as in the paper)",
    )
    parser.add_argument(
        "--training-seeds",
        type=int,
        metavar="N",
        help="networks learned per learning set, seeds 0..N-1 (default 3; --quick: 2)",
    )


#: Minutes the run takes on 2 cores with 2 workers (the measured runs: notes/2026-12-03-history.md,
#: notes/2026-12-06-native-learning.md).
MEASURED_MINUTES = {"full": 3.5, "quick": 1.0}


def _estimate(config) -> str:
    """What to expect: the measured time, scaled by the workers (the work is the same)."""
    from rnnpb.experiments import ExperimentConfig

    base = MEASURED_MINUTES["quick" if config.quick else "full"]
    minutes = base * 2 / min(config.workers, 2)
    more = (
        f", longer with {config.samples_per_pattern} demonstrations per pattern"
        if config.samples_per_pattern > 2
        else ""
    )
    default = (ExperimentConfig.quick_run() if config.quick else ExperimentConfig()).training_seeds
    seeds = (
        f", measured with {len(default)} networks per learning set (you asked for "
        f"{len(config.training_seeds)})"
        if len(config.training_seeds) != len(default)
        else ""
    )
    return (
        f"about {minutes:.0f} minute{'' if round(minutes) == 1 else 's'} on 2 cores with "
        f"{config.workers} worker(s)"
        f"{more}{seeds} (longer while other programs use the cores)"
    )


def run(args: argparse.Namespace) -> int:
    import os
    import time
    from dataclasses import replace

    os.environ.setdefault("MUJOCO_GL", "egl")
    from rnnpb.errors import ConfigError
    from rnnpb.experiments import ExperimentConfig, run_demo
    from rnnpb.sweeps import ray_runner

    if args.workers < 1:
        raise ConfigError(f"--workers must be >= 1, got {args.workers}")
    config = ExperimentConfig.quick_run() if args.quick else ExperimentConfig()
    config = replace(config, workers=args.workers, samples_per_pattern=args.samples_per_pattern)
    if args.training_seeds is not None:
        if args.training_seeds < 1:
            raise ConfigError(f"--training-seeds must be >= 1, got {args.training_seeds}")
        config = replace(config, training_seeds=tuple(range(args.training_seeds)))
    print(f"rnnpb demo ({'quick' if args.quick else 'full'} run): {_estimate(config)}", flush=True)
    started = time.monotonic()

    def log(message: str) -> None:
        # Elapsed time on every line, so a reader can set the progress against the estimate.
        minutes, seconds = divmod(int(time.monotonic() - started), 60)
        print(f"[{minutes:2d}:{seconds:02d}] {message}", flush=True)

    results = run_demo(args.out, config, log=log, runner=ray_runner(workers=args.workers))
    print(f"wrote {args.out}/report.md and {args.out}/results.json in {results.runtime_s:.0f} s")
    for key, target in results.targets.items():
        print(f"  {key}: {'met' if target.met else 'NOT met'} ({target.detail})")
    return 0
