"""rnnpb study: the studies beyond the paper's section 3."""

from __future__ import annotations

import argparse

NAME = "study"
HELP = "run a study beyond the paper: report.md, results.json, figures"
DESCRIPTION = """\
Run one study and write OUT/report.md (figures embedded from OUT/figures/) and
OUT/results.json (every measure, with the config, seeds and versions). --quick is the short
form, the one the test suite runs; the full form is the one whose figures docs/ quote.
--exam runs the full form on the study's exam: the draws named in its exam file, never used
to choose a setting, every target judged by the file's definitions. The run is written in the
exam ledger (the checkout's src/rnnpb/experiments/exams/ledger.jsonl, or --ledger FILE, which
an installed rnnpb needs), and a version with a judged run is refused: a version is judged
once. A study learns the models it needs unless --models names a directory that holds them.

Examples:
  rnnpb study novelty --quick --out results/novelty
  rnnpb study dyad --exam --out results/dyad-exam
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
    parser.add_argument(
        "--seed", type=int, default=None, help="the first seed (default 0; not with --exam)"
    )
    parser.add_argument(
        "--exam",
        action="store_true",
        help="run the full form on the study's exam draws and judge every target by its exam",
    )
    parser.add_argument(
        "--ledger",
        metavar="FILE",
        help="with --exam: the exam ledger to write the run in (default: the checkout's "
        "src/rnnpb/experiments/exams/ledger.jsonl; an installed rnnpb needs this)",
    )
    parser.add_argument(
        "--rerun-unjudged",
        action="store_true",
        help="with --exam: run a version again whose earlier runs all stopped before their "
        "verdicts (never one with a judged run)",
    )
    parser.add_argument(
        "--models",
        metavar="DIR",
        help="learned models to start from (set1.npz ... set4.npz, and full.npz or "
        "full_seed0.npz for the larger set: the layout of `rnnpb demo`'s models); without "
        "it a study learns those it needs",
    )
    parser.add_argument(
        "--data",
        metavar="DIR",
        help="recordings a study reads (the people study: a folder of motion-capture takes)",
    )


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from rnnpb.errors import ConfigError
    from rnnpb.experiments.exams import load_exam
    from rnnpb.experiments.studies import StudyOptions, load_study, takes_exam

    study = load_study(args.name)
    exam = None
    if args.exam:
        if args.seed is not None:
            raise ConfigError("an exam names its own seeds: --exam takes no --seed")
        if not takes_exam(study):
            raise ConfigError(f"the {args.name} study does not run its exam yet")
        exam = load_exam(args.name)
    elif args.ledger is not None or args.rerun_unjudged:
        raise ConfigError("--ledger and --rerun-unjudged go with --exam")
    options = StudyOptions(
        quick=args.quick,
        workers=args.workers,
        seed=args.seed or 0,
        models=args.models,
        exam=exam,
        data=args.data,
    )
    record = None
    if exam is None:
        outcome = study.run(Path(args.out), options)
    else:
        from rnnpb.experiments.exams.ledger import exam_run

        # The ledger is checked and the run's start written before the study starts; its end
        # (the verdicts, or the error that stopped it) after.
        with exam_run(exam, args.out, args.ledger, args.rerun_unjudged) as record:
            outcome = study.run(Path(args.out), options)
            record.judged(outcome.targets)
    print(f"wrote {args.out}/report.md and {args.out}/results.json in {outcome.runtime_s:.0f} s")
    if exam is not None:
        print(f"exam {exam.study} version {exam.version}:")
    for key, target in outcome.targets.items():
        print(f"  {key}: {'met' if target.met else 'NOT met'} ({target.detail})")
    if record is not None:
        print(f"written in the exam ledger {record.path} as run {record.entry.run}")
    return 0
