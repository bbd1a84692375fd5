"""rnnpb study: the studies beyond the paper's section 3."""

from __future__ import annotations

import argparse

NAME = "study"
HELP = "run a study beyond the paper: report.md, results.json, figures"
DESCRIPTION = """\
Run one study and write OUT/report.md (figures embedded from OUT/figures/) and
OUT/results.json (every measure, with the config, seeds and versions). --quick is the short
form, the one the test suite runs; the full form is the one whose figures docs/ quote.

Example:
  rnnpb study novelty --quick --out results/novelty
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    # Names only: a study's module (and JAX with it) is imported when it runs, so that
    # `rnnpb --help` stays fast. docs/experiments.md describes each study.
    from rnnpb.experiments.studies import study_names

    parser.add_argument(
        "name", metavar="NAME", choices=study_names(), help="the study: " + ", ".join(study_names())
    )
    parser.add_argument("--out", required=True, metavar="DIR", help="output directory")
    parser.add_argument("--quick", action="store_true", help="the short form")
    parser.add_argument(
        "--workers", type=int, default=2, help="parallel worker processes (default 2)"
    )
    parser.add_argument("--seed", type=int, default=0, help="the first seed (default 0)")
    parser.add_argument(
        "--models",
        metavar="DIR",
        help="learned models to start from, for the studies that take them (incremental: "
        "set1.npz ... set4.npz; teach: those and full.npz or full_seed0.npz; default "
        "results/demo/models)",
    )


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from rnnpb.experiments.studies import StudyOptions, load_study

    study = load_study(args.name)
    options = StudyOptions(
        quick=args.quick, workers=args.workers, seed=args.seed, models=args.models
    )
    outcome = study.run(Path(args.out), options)
    print(f"wrote {args.out}/report.md and {args.out}/results.json in {outcome.runtime_s:.0f} s")
    for key, target in outcome.targets.items():
        print(f"  {key}: {'met' if target.met else 'NOT met'} ({target.detail})")
    return 0
