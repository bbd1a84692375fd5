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
  --cut whole    each stretch with both hands seen as one sequence (a routine, for
                 `rnnpb train-routines`)
A hand lost for more than a few steps splits the recording; no sequence spans the gap.

SOURCE is one of webcam:INDEX, video:PATH, images:DIR, synthetic:PATTERN, csv:FILE,
scenario:held:P (see `rnnpb interact --help`), or bvh:FILE[,FILE...] (motion capture).

Motion capture (bvh:FILE,FILE...; docs/motion-capture.md): the files are played in order as one
stream, each blending into the next over 0.5 s. The hands are found by the joints' names
(--hands LEFT,RIGHT names them), taken relative to the person's own shoulders and scaled by
their arm length onto the standard user's body, so people of every size reach the same
workspace; units and up axis are read from the skeleton (--units, --up-axis give them). The
stream is resampled to --dt; --time-scale S plays it S times slower. A movement with fewer
than 4 steps per cycle is refused with the --time-scale or --dt that would work. A hand outside
the robot camera's view is not seen; --distance M stands the person further from the robot
(default 1 m), and the command says which distance keeps every step in view.

Every recording also writes DIR/recording.json: the source, the step time, the body's
measures and the scaling; `rnnpb train` learns the model at that step time. A folder holds
data of one step time.

Examples:
  rnnpb record synthetic:3 --steps 120 --pattern three --out data/three
  rnnpb record webcam:0 --steps 150 --colors colors.json --pattern wave --out data/wave
  rnnpb record bvh:wave1.bvh,wave2.bvh --time-scale 3 --pattern wave --out data/wave
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
        choices=("cycles", "length", "whole"),
        default="cycles",
        help="cut into whole cycles, fixed-length sequences or keep each seen stretch whole "
        "(a routine: `rnnpb train-routines`) (default cycles)",
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
    parser.add_argument(
        "--dt",
        type=float,
        default=0.4,
        help="seconds per step the data are recorded (and the model learned) at (default 0.4, "
        "the paper's)",
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of a synthetic source")
    parser.add_argument(
        "--time-scale",
        type=float,
        default=1.0,
        metavar="S",
        help="bvh: play the capture S times slower (0.5: twice as fast; default 1)",
    )
    parser.add_argument(
        "--hands",
        metavar="LEFT,RIGHT",
        help="bvh: the joints of the left and right hand (default: found by their names)",
    )
    parser.add_argument(
        "--units",
        choices=("m", "cm", "mm", "in"),
        help="bvh: the file's length unit (default: the one in which the arms are a person's)",
    )
    parser.add_argument(
        "--distance",
        type=float,
        metavar="M",
        help="bvh: how far from the robot the person's shoulders are, metres (default 1.0, "
        "the standard user's; further keeps raised or wide hands in the robot camera's view)",
    )
    parser.add_argument(
        "--up-axis",
        choices=("x", "y", "z", "-x", "-y", "-z"),
        help="bvh: the file's up axis (default: the one the shoulders are above the root on)",
    )
    add_perception_argument(parser)


def run(args: argparse.Namespace) -> int:
    import datetime
    from pathlib import Path

    import numpy as np

    from rnnpb.commands._checks import finite_seconds
    from rnnpb.commands._recording import check_folder_dt, write_recording
    from rnnpb.demonstrator import MirrorMapping
    from rnnpb.errors import ConfigError, RnnpbError
    from rnnpb.interaction.learning_phase import cut_sequences, demonstration_from_hands
    from rnnpb.safety import check_data
    from rnnpb.sequences import pattern_name_problem, write_sequence

    problem = pattern_name_problem(args.pattern)
    if problem:
        raise ConfigError(f"--pattern {args.pattern!r} {problem}")
    finite_seconds("--dt", args.dt)
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out {out}: exists and is not a directory")
    if out.is_dir():
        check_folder_dt(out, args.dt)
    kind, _, argument = str(args.source).partition(":")
    capture = None
    body = None
    if kind.strip().lower() == "bvh":
        from rnnpb.mocap import capture_stream

        files = [f.strip() for f in argument.split(",")]
        if not argument or not all(files):
            raise ConfigError(f"source {args.source!r}: expected bvh:FILE[,FILE...]")
        if args.perception != "balls":
            raise ConfigError("--perception applies to camera sources, not to bvh:")
        hands = None
        if args.hands is not None:
            names = [n.strip() for n in args.hands.split(",")]
            if len(names) != 2 or not all(names):
                raise ConfigError(f"--hands {args.hands!r}: expected LEFT,RIGHT joint names")
            hands = (names[0], names[1])
        body = _placed_body(args.distance)
        capture = capture_stream(
            files,
            dt=args.dt,
            time_scale=args.time_scale,
            hands=hands,
            units=args.units,
            up_axis=args.up_axis,
            body=body,
        )
        hand_steps = capture.hands if args.steps is None else capture.hands[: args.steps]
        mapping = MirrorMapping(body=body, dt=args.dt)
        demonstration = demonstration_from_hands(hand_steps, mapping=mapping, source=args.source)
    else:
        mapping = MirrorMapping(dt=args.dt)
        for option in ("hands", "units", "up_axis", "distance"):
            if getattr(args, option) is not None:
                raise ConfigError(f"--{option.replace('_', '-')} applies to bvh: sources")
        if args.time_scale != 1.0:
            raise ConfigError("--time-scale applies to bvh: sources")
        demonstration = _record_from_source(args, mapping)
    out_of_view = ""
    if capture is not None and not demonstration.valid.all():
        out_of_view = (
            f"a hand was outside the robot camera's view on {int((~demonstration.valid).sum())} "
            f"of {demonstration.n_steps} steps (not seen: they split the recording); "
            + _distance_in_view(demonstration.hands, body)
        )
    try:
        sequences = cut_sequences(
            demonstration,
            args.pattern,
            mode=args.cut,
            cycles_per_sequence=args.cycles,
            length=args.length,
        )
    except RnnpbError as error:
        if not out_of_view:
            raise
        raise RnnpbError(f"{error}; {out_of_view}") from None
    safety = check_data(sequences, dt=args.dt)
    out.mkdir(parents=True, exist_ok=True)
    names = []
    for i, sequence in enumerate(sequences, 1):
        write_sequence(out / f"{args.pattern}_{i}.csv", sequence)
        names.append(f"{args.pattern}_{i}.csv")
    entry = {
        "source": str(args.source),
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "dt": args.dt,
        "steps": demonstration.n_steps,
        "depth": demonstration.depth,
        "sequences": names,
        "mapping": {
            "user_body": {
                k: getattr(mapping.body, k)
                for k in ("distance", "shoulder_height", "shoulder_half_width", "arm_reach")
            },
            "scale": round(mapping.effective_scale, 6),
        },
        "capture": None if capture is None else capture.to_json(),
        "safety": {
            "steps": safety.steps,
            "collision": safety.collision,
            "speed": safety.speed,
            "limit": safety.limit,
            "adjusted": int(np.sum(demonstration.adjusted)),
        },
    }
    write_recording(out, args.pattern, args.dt, entry)
    valid = demonstration.valid
    reach = demonstration.ik_residual[valid]
    depth_words = {
        "size": "ball size",
        "pose": "the pose model",
        "plane": "a fixed plane",
        "3-d": "motion capture",
    }
    print(
        f"recorded {demonstration.n_steps} steps from {demonstration.source} "
        f"(depth from {depth_words[demonstration.depth]}); "
        f"{int(valid.sum())} with both hands recovered"
    )
    if out_of_view:
        print(out_of_view)
    if capture is not None:
        body = capture.takes[0].body
        print(
            f"body: arm {body.arm_length_m:.3f} m, shoulders {body.shoulder_width_m:.3f} m apart "
            f"(units {body.units}, {body.up_axis} up); hands scaled by {body.scale:.3f}; "
            f"{len(capture.takes)} take(s) at time scale {capture.time_scale:g}, shortest "
            f"cycle {capture.period:.2f} s = {capture.period / args.dt:.1f} steps of {args.dt:g} s"
        )
    if len(reach):
        print(
            f"robot hands within {float(np.max(reach)) * 100:.1f} cm of their targets (median "
            f"{float(np.median(reach)) * 100:.1f} cm); {int(np.sum(demonstration.adjusted))} "
            "steps moved to a safe posture near the one asked for"
        )
    print(f"safety of the written data: {safety.describe()}")
    print(
        f"{len(sequences)} sequences of pattern {args.pattern!r} "
        f"({', '.join(str(s.n_steps) for s in sequences)} steps) -> {out}"
    )
    return 0


def _placed_body(distance: float | None):
    """The standard user, at ``distance`` metres from the robot when given."""
    from rnnpb.demonstrator import UserBody
    from rnnpb.errors import ConfigError

    if distance is None:
        return UserBody()
    if not 0.5 <= distance <= 3.0:
        raise ConfigError(f"--distance must be from 0.5 to 3 m, got {distance}")
    return UserBody(distance=distance, hand_depth=min(UserBody().hand_depth, 0.9 * distance))


def _distance_in_view(hands, body) -> str:
    """Which --distance would keep every hand in the robot camera's view."""
    import numpy as np

    from rnnpb.robot.camera import RobotCamera

    camera = RobotCamera()
    for distance in np.arange(0.5, 3.001, 0.1):
        moved = hands + np.array([distance - body.distance, 0.0, 0.0])
        seen = camera.sensory_from_hands(moved)
        if np.all((seen >= 0) & (seen <= 1)):
            return f"--distance {distance:.1f} keeps every step in view"
    return "no --distance up to 3 m keeps every step in view"


def _record_from_source(args: argparse.Namespace, mapping):
    from rnnpb.interaction import open_source
    from rnnpb.interaction.learning_phase import record_demonstration
    from rnnpb.perception import MOUSE_PLANE_X, DepthConfig

    source = open_source(
        args.source,
        seed=args.seed,
        dt=args.dt,
        colors=args.colors,
        steps=args.steps,
        perception=args.perception,
    )
    with source:
        return record_demonstration(
            source,
            steps=args.steps,
            mapping=mapping,
            depth=DepthConfig(ball_radius_m=args.ball_radius),
            plane_x=MOUSE_PLANE_X if args.plane_x is None else args.plane_x,
        )
