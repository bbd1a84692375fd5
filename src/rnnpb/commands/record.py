"""``rnnpb record``: the paper's learning phase from a source — the person moves, the robot
records the hands and its own joint angles for them, and writes sequence CSVs to train on."""

from __future__ import annotations

import argparse

from rnnpb.commands._perception import add_perception_argument

NAME = "record"
HELP = "record a demonstration from a camera or a stream and write sequence CSVs"
DESCRIPTION = """\
The learning phase of the paper (its Fig. 2a) from a camera: the two coloured balls give the
user's hands in the image and, from their apparent size, their depth; the 3-D hand positions
are mirrored onto the robot's hand targets and, by inverse kinematics, its joint angles.
Sources without depth (a sensory CSV, a scenario) put the hands on the plane x = --plane-x
metres in front of the robot (default 0.68 m, where the synthetic user's hands move).
With --perception pose the hands are bare: a pose model finds the wrists and shoulders, the
hands are scaled by the shoulder span to a standard body, and their depth is the model's wrist
depth scaled the same way (pip install 'rnnpb[hands]').

The recording is cut into training sequences, written as DIR/PATTERN_1.csv, PATTERN_2.csv …
(columns step, lhy lhz rhy rhz, lshp … relp, pattern) for `rnnpb train`:
  --cut cycles   (default) --cycles N whole cycles per sequence; a cycle runs from one upward
                 crossing of the movement's main component through its mean to the next
  --cut length   consecutive sequences of --length steps
A hand lost for more than a few steps splits the recording; no sequence spans the gap.

SOURCE is one of webcam:INDEX, video:PATH, images:DIR, synthetic:PATTERN, csv:FILE,
scenario:held:P (see `rnnpb interact --help`).

Examples:
  rnnpb record synthetic:3 --steps 120 --pattern three --out data/three
  rnnpb record webcam:0 --steps 150 --colors colors.json --pattern wave --out data/wave
  rnnpb record webcam:0 --steps 150 --perception pose --pattern wave --out data/wave
  rnnpb train --data data/three data/wave --out model.npz --preset fast
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("source", metavar="SOURCE", help="where the movement comes from")
    parser.add_argument(
        "--out", required=True, metavar="DIR", help="directory to write the sequence CSVs into"
    )
    parser.add_argument(
        "--pattern", default="new", help="name of the movement pattern (default: new)"
    )
    parser.add_argument(
        "--steps",
        type=int,
        metavar="N",
        help="record at most N steps (synthetic: render N frames, default 200)",
    )
    parser.add_argument(
        "--cut",
        choices=("cycles", "length"),
        default="cycles",
        help="cut into whole cycles or fixed-length sequences (default cycles)",
    )
    parser.add_argument(
        "--cycles",
        type=int,
        default=4,
        metavar="N",
        help="whole cycles per sequence with --cut cycles (default 4)",
    )
    parser.add_argument(
        "--length",
        type=int,
        default=50,
        metavar="STEPS",
        help="steps per sequence with --cut length (default 50)",
    )
    parser.add_argument(
        "--colors",
        metavar="FILE.json",
        help="ball colour ranges (from `rnnpb calibrate`); default red/blue",
    )
    parser.add_argument(
        "--ball-radius",
        type=float,
        default=0.04,
        metavar="M",
        help="the balls' real radius in metres (default 0.04)",
    )
    parser.add_argument(
        "--plane-x",
        type=float,
        metavar="M",
        help="x of the hands' plane for sources without depth (default 0.68)",
    )
    parser.add_argument("--dt", type=float, default=0.4, help="seconds per step (default 0.4)")
    parser.add_argument("--seed", type=int, default=0, help="seed of a synthetic source")
    add_perception_argument(parser)


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    import numpy as np

    from rnnpb.errors import ConfigError
    from rnnpb.interaction import open_source
    from rnnpb.interaction.learning_phase import cut_sequences, record_demonstration
    from rnnpb.perception import MOUSE_PLANE_X, DepthConfig
    from rnnpb.sequences import pattern_name_problem, write_sequence

    depth_words = {"size": "ball size", "pose": "the pose model", "plane": "a fixed plane"}
    problem = pattern_name_problem(args.pattern)
    if problem:
        raise ConfigError(f"--pattern {args.pattern!r} {problem}")
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out {out}: exists and is not a directory")
    source = open_source(
        args.source,
        seed=args.seed,
        dt=args.dt,
        colors=args.colors,
        steps=args.steps,
        perception=args.perception,
    )
    with source:
        demonstration = record_demonstration(
            source,
            steps=args.steps,
            depth=DepthConfig(ball_radius_m=args.ball_radius),
            plane_x=MOUSE_PLANE_X if args.plane_x is None else args.plane_x,
        )
    sequences = cut_sequences(
        demonstration,
        args.pattern,
        mode=args.cut,
        cycles_per_sequence=args.cycles,
        length=args.length,
    )
    out.mkdir(parents=True, exist_ok=True)
    for i, sequence in enumerate(sequences, 1):
        write_sequence(out / f"{args.pattern}_{i}.csv", sequence)
    valid = demonstration.valid
    reach = demonstration.ik_residual[valid]
    print(
        f"recorded {demonstration.n_steps} steps from {demonstration.source} "
        f"(depth from {depth_words[demonstration.depth]}); "
        f"{int(valid.sum())} with both hands recovered"
    )
    if len(reach):
        print(f"robot hands within {float(np.max(reach)) * 100:.1f} cm of their targets")
    print(
        f"{len(sequences)} sequences of pattern {args.pattern!r} "
        f"({', '.join(str(s.n_steps) for s in sequences)} steps) -> {out}"
    )
    return 0
