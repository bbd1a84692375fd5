"""rnnpb train-routines: learn routines (sequences of learned patterns) over a model."""

from __future__ import annotations

import argparse

NAME = "train-routines"
HELP = "learn routines of movements: a higher level over a trained model"
DESCRIPTION = """\
Learn routines — sequences of the model's learned patterns, each for a number of cycles —
as a higher-level RNNPB over the model (docs/routines.md). Each routine is given as
recordings of it performed whole (`rnnpb record --cut whole --pattern NAME`): the routine's
name is each sequence's pattern. The recordings are run through the model on-line, its PB is
cut into segments where it moves from one learned pattern to another, and the higher level
learns the order and duration of the segments, with its own PB for each routine. The file
written holds the model's fingerprint and is refused for any other model.

Example:
  rnnpb record --source scenario:routine:1*3,3*2,2*4 --cut whole --pattern dance --out data/dance
  rnnpb train-routines --model model.npz --data data/dance data/wave --out routines.npz
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--model", required=True, help="the trained model (.npz) below")
    parser.add_argument(
        "--data",
        required=True,
        nargs="+",
        metavar="PATH",
        help="recordings of whole routines: sequence CSVs or folders of them",
    )
    parser.add_argument("--out", required=True, help="routine file to write (.npz)")
    parser.add_argument(
        "--iterations", type=int, default=1500, help="learning iterations (default 1500)"
    )
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")


def run(args: argparse.Namespace) -> int:
    from rnnpb.commands._checks import step_count
    from rnnpb.errors import DataFileError
    from rnnpb.model import TrainedModel
    from rnnpb.model.routines import RoutineLearning, learn_routines
    from rnnpb.sequences import read_sequence_files

    step_count("--iterations", args.iterations, low=1)
    model = TrainedModel.load(args.model)
    sequences = read_sequence_files(args.data)
    recordings: dict[str, list] = {}
    for sequence in sequences:
        if sequence.sensory.shape[1] != model.network.sensory_size:
            raise DataFileError(f"{sequence.source}: hands do not match the model's")
        recordings.setdefault(sequence.pattern, []).append(sequence.sensory)
    routines = learn_routines(
        model, recordings, RoutineLearning(iterations=args.iterations, seed=args.seed)
    )
    routines.save(args.out)
    print(
        f"wrote {args.out}: routines {', '.join(routines.routines)} over {args.model} "
        f"(from {len(sequences)} recordings)"
    )
    return 0
