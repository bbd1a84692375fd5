"""rnnpb generate: closed-loop generation from a learned pattern or a PB vector."""

from __future__ import annotations

import argparse

NAME = "generate"
HELP = "generate a movement from a learned pattern or a PB vector (closed loop)"
DESCRIPTION = """\
Run the trained network in closed loop — all outputs fed back as inputs, no external
input — with a constant parametric bias, and write the generated user hands and robot
joints as a sequence CSV (the same columns as training data; joints in radians).

Example:
  rnnpb generate --model model.npz --pattern 1 --steps 100 --out gen.csv
  rnnpb generate --model model.npz --pb 0.2,0.8,0.5,0.1 --steps 100 --out gen.csv
  rnnpb generate --model model.npz --routines routines.npz --routine dance --steps 200 \
      --out dance.csv

With --routines and --routine the robot performs a learned routine alone: the routine level
in closed loop gives each movement's PB and how long it lasts, top-down (docs/routines.md).
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--model", required=True, help="trained model (.npz)")
    which = parser.add_mutually_exclusive_group(required=True)
    which.add_argument("--pattern", help="name of a learned pattern")
    which.add_argument("--pb", help="PB values, comma-separated, each in [0, 1]")
    which.add_argument("--routine", help="name of a routine in --routines")
    parser.add_argument("--routines", help="routine file (`rnnpb train-routines`)")
    parser.add_argument("--steps", type=int, default=100, help="steps to write (default 100)")
    parser.add_argument(
        "--transient",
        type=int,
        default=0,
        metavar="K",
        help="generate K steps first and drop them (default 0)",
    )
    parser.add_argument("--out", required=True, help="output sequence CSV")


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from rnnpb.commands._checks import MAX_STEPS, step_count
    from rnnpb.errors import ConfigError
    from rnnpb.model import TrainedModel, generate
    from rnnpb.sequences import Sequence, write_sequence

    # Before the model is read: a mistyped count is one line, not an allocation that fails.
    step_count("--steps", args.steps, low=2)
    step_count("--transient", args.transient, low=0)
    if args.steps + args.transient > MAX_STEPS:
        raise ConfigError(
            f"--steps plus --transient must be at most {MAX_STEPS:,}, got "
            f"{args.steps + args.transient:,}"
        )
    model = TrainedModel.load(args.model)
    if (args.routine is None) != (args.routines is None):
        raise ConfigError("--routine and --routines go together")
    if args.routine is not None:
        from rnnpb.model.routines import RoutineModel, generate_routine

        routines = RoutineModel.load(args.routines, model)
        _, sensory, motor = generate_routine(
            model, routines, args.routine, args.steps + args.transient
        )
        k = args.transient
        write_sequence(args.out, Sequence(sensory[k:], motor[k:], args.routine, args.out))
        print(f"wrote {args.steps} steps of routine {args.routine} to {args.out}")
        return 0
    if args.pattern is not None:
        if args.pattern not in model.pattern_pb:
            raise ConfigError(
                f"pattern {args.pattern!r} is not in {args.model} (it has "
                f"{', '.join(model.patterns)})"
            )
        pb = model.pattern_pb[args.pattern]
        context = model.pattern_initial_context(args.pattern)
        label = args.pattern
    else:
        try:
            pb = np.array([float(v) for v in args.pb.split(",")])
        except ValueError:
            raise ConfigError(f"--pb {args.pb!r}: expected comma-separated numbers") from None
        context = None
        label = "pb"
    generated = generate(model, pb, args.steps + args.transient, initial_context=context)
    k = args.transient
    write_sequence(args.out, Sequence(generated.sensory[k:], generated.motor[k:], label, args.out))
    print(
        f"wrote {args.steps} steps generated from PB {np.array2string(pb, precision=3)} "
        f"to {args.out}"
    )
    return 0
