"""rnnpb consolidate: add new patterns to a learned model without forgetting the old ones."""

from __future__ import annotations

import argparse

from rnnpb.commands._config import add_config_argument

NAME = "consolidate"
CONFIG_SECTIONS = ("consolidation",)
SAFE_POINTS = True  # Ctrl-C stops between training chunks (rnnpb._interrupt)
HELP = "add new patterns to a learned model (rehearsal and consolidation)"
DESCRIPTION = """\
Add new movement patterns to a learned model (Ito & Tani 2004, section 4.1, after Tani 1998).

Methods:
  rehearsal  (default) the model regenerates each learned pattern in closed loop from its PB,
             without the original data, and learns the new pattern together with them;
             a rehearsed pattern learns the old network's function on its cycle (what the
             model predicts from noisy inputs near it)
  finetune   learns the new pattern alone (the old ones are overwritten: for comparison)
  replay     learns the new pattern with the original data (--replay-data)
  scratch    learns the original data and the new pattern anew from random weights
             (--replay-data; the model's own full learning: the upper bound)

The new files are sequence CSVs as for `rnnpb train`; their patterns must have names the
model does not hold. A pattern is learned from all its files together (give two or more
performances of it: one short take generalises poorly to the next).

--add-to NAME FILES grows a pattern the model holds instead: every sequence of FILES is more
data for NAME (whatever pattern the files name), learned from NAME's PB with the same
rehearsal of every old pattern, NAME's included.

Learning continues from the model's weights (scratch: from random ones) with the model's own
algorithm (paper or fast preset) and its preset's consolidation policy (iterations, input
noise, how the new PB starts and the old PBs are held); --iterations overrides the policy's
(scratch: the model's first training's). The new model records its
history (see `rnnpb info`). The model given is never changed; the new one is written only when
learning is done, atomically. A checkpoint is written next to it (OUT.checkpoint.npz) every
--checkpoint-every iterations; after an interruption --resume continues from it.

For research, --config FILE overrides any value of the preset's [consolidation] section, e.g.
to measure an alternative the policy did not take:

  [consolidation]
  hold_old_pb = "off"        # or "all"; default "first-half"
  new_pb_start = "centre"    # default "farthest"
  rehearsal_target = "trajectory"

Examples:
  rnnpb consolidate --model set1.npz --add data/patterns/4_*.csv --out set1+4.npz
  rnnpb consolidate --model set1+4.npz --add-to 4 takes/4_again.csv --out set1+4b.npz
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--model", required=True, metavar="MODEL", help="the learned model")
    what = parser.add_mutually_exclusive_group(required=True)
    what.add_argument(
        "--add",
        nargs="+",
        metavar="FILE_OR_DIR",
        help="sequence CSV files (or directories) of the new pattern(s)",
    )
    what.add_argument(
        "--add-to",
        nargs="+",
        metavar=("NAME", "FILE_OR_DIR"),
        help="a pattern the model holds, then sequence CSV files (or directories): more "
        "data for that pattern",
    )
    parser.add_argument(
        "--out", required=True, metavar="MODEL", help="where to write the new model (.npz)"
    )
    parser.add_argument(
        "--method",
        default="rehearsal",
        help="how to add them: one of the methods above (default: rehearsal)",
    )
    parser.add_argument(
        "--replay-data",
        nargs="+",
        metavar="FILE_OR_DIR",
        help="the original training data (replay and scratch)",
    )
    parser.add_argument("--iterations", type=int, help="learning iterations")
    add_config_argument(parser, CONFIG_SECTIONS)
    parser.add_argument("--seed", type=int, help="random seed (default: the model's)")
    parser.add_argument(
        "--checkpoint-every",
        type=int,
        default=1000,
        metavar="N",
        help="write a checkpoint every N iterations (default 1000)",
    )
    parser.add_argument(
        "--resume", action="store_true", help="continue from OUT.checkpoint.npz if it exists"
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")


def run(args: argparse.Namespace) -> int:
    from rnnpb._atomic import check_writable

    check_writable(args.out, "model")

    from dataclasses import replace

    from rnnpb import _interrupt
    from rnnpb.commands._config import read_config
    from rnnpb.commands.train import checkpoint_path_for
    from rnnpb.errors import ConfigError
    from rnnpb.model import TrainedModel
    from rnnpb.model.consolidation import (
        ConsolidationConfig,
        consolidate,
        consolidation_config,
    )
    from rnnpb.sequences import read_sequence_files

    ConsolidationConfig(method=args.method)  # a method it does not know: said before any work
    if args.iterations is not None and args.iterations < 1:
        raise ConfigError(f"--iterations must be >= 1, got {args.iterations}")
    if args.checkpoint_every < 1:
        raise ConfigError(f"--checkpoint-every must be >= 1, got {args.checkpoint_every}")
    overrides = read_config(args.config, CONFIG_SECTIONS, NAME)
    model = TrainedModel.load(args.model)
    grow = args.add_to is not None
    if grow:
        if len(args.add_to) < 2:
            raise ConfigError("--add-to needs a pattern name and at least one file")
        name, *files = args.add_to
        if name not in model.patterns:
            raise ConfigError(
                f"--add-to {name}: the model holds no pattern {name!r} "
                f"(it holds {', '.join(model.patterns)})"
            )
        new = [replace(s, pattern=name) for s in read_sequence_files(files)]
    else:
        new = read_sequence_files(args.add)
    replay = read_sequence_files(args.replay_data) if args.replay_data else None
    if replay is not None and args.method not in ("replay", "scratch"):
        raise ConfigError(
            f"--replay-data is for the methods replay and scratch, not "
            f"{args.method} (rehearsal needs no original data)"
        )
    config = consolidation_config(
        model,
        "add",
        method=args.method,
        iterations=args.iterations,
        seed=args.seed,
        overrides=overrides,
    )
    assert config.train is not None
    learning = replace(config.train, checkpoint_every=args.checkpoint_every)
    config = replace(config, train=learning)
    added = sorted({s.pattern for s in new})
    print(
        f"{'growing' if grow else 'adding'} {len(new)} sequence(s) of pattern(s) "
        f"{', '.join(added)} {'in' if grow else 'to'} {args.model} "
        f"({', '.join(model.patterns)}) by {args.method}: {learning.iterations} iterations "
        f"({learning.optimizer})"
    )
    bar = None
    if not args.no_progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=learning.iterations, unit="it", desc=args.method, dynamic_ncols=True)

    def after_chunk(progress) -> None:
        if bar is not None:
            bar.update(progress.iteration - bar.n)
            bar.set_postfix(mse=f"{progress.mse:.2e}")
        # A safe point: the chunk's error has been read back, so no XLA work is in flight.
        _interrupt.check()

    try:
        grown = consolidate(
            model,
            new,
            config,
            replay_data=replay,
            parent=args.model,
            progress=after_chunk,
            checkpoint_path=checkpoint_path_for(args.out),
            resume=args.resume,
            grow=grow,
        )
    finally:
        if bar is not None:
            bar.close()
    _interrupt.check()  # interrupted during the last chunk: no model file
    grown.save(args.out)
    entry = grown.history[-1]
    print(
        f"wrote {args.out}: patterns {', '.join(grown.patterns)} after {entry.iterations} "
        f"iterations in {entry.seconds:.1f} s; training error (MSE) max "
        f"{grown.meta['training']['mse_max']:.2e}"
    )
    if entry.details.get("replay_data_matches_record") is False:
        print(
            "note: the original data differ from the data the model recorded (CSV files "
            "round values); the new model records that"
        )
    return 0
