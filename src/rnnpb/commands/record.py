"""``rnnpb record``: the paper's learning phase from a source — the person moves, the robot
records the hands and its own joint angles for them, and writes sequence CSVs to train on."""

from __future__ import annotations

import argparse

from rnnpb.commands._perception import add_perception_argument

NAME = "record"
HELP = "record a demonstration from a camera or a stream and write sequence CSVs"
DESCRIPTION = """\
The learning phase of the paper (its Fig. 2a), the same for every source: the person moves,
the robot records the hands it sees and its own joint angles for them, cut into whole cycles,
and writes sequence CSVs for `rnnpb train` (docs/teaching.md, docs/design.md):

  1. the step: the recording played --time-scale times slower, averaged over each --dt;
     a movement with fewer than 4 steps a cycle is played slower by the least factor that
     gives it 4 (said so, with the --dt that would follow it at the person's tempo)
  2. framing: a person whose body the source knows (motion capture, --perception pose) is
     placed where the robot's camera sees the whole movement, as near as it can (--framing M
     gives the distance in metres); a folder holds one framing; a hand outside the view is
     put on its edge and counted
  3. the robot's joints: mirror mapping and safe retargeting (never through its own body);
     where the servos could not follow the person, the movement is made smaller, at the
     person's tempo, and said so
  4. whole cycles: where the movement repeats (4-80 steps a cycle), cut into cycles; rests,
     a raise before a wave, joins between takes are left out, and said so
  5. the one check `rnnpb train` makes, on the values as written: nothing it would refuse
     is ever written

Sources: webcam:INDEX, video:PATH, images:DIR, synthetic:PATTERN, csv:FILE, scenario:...
(see `rnnpb interact --help`), or bvh:FILE[,FILE...] (motion capture: the files played in
order as one stream, each blending into the next over 0.5 s; the hands found by the joints'
names, --hands LEFT,RIGHT names them; units and up axis read from the skeleton).
With --perception pose a camera's hands are bare: a pose model finds the wrists and shoulders
(pip install 'rnnpb[hands]'). Coloured balls give depth from their size; a source without
depth puts the hands on the plane x = --plane-x metres in front of the robot.

Cutting (--cut): cycles (default) takes sequences of --cycles whole cycles (default: as many
as make about 48 steps, at least 2); length takes consecutive --length steps; whole keeps
each stretch seen whole (a routine, for `rnnpb train-routines`). A step on which a hand was not
seen splits the recording; no sequence spans the gap.

Every recording writes DIR/recording.json: the source, the step time, the framing and what
each step changed; `rnnpb train` learns at that step time and framing.

Examples:
  rnnpb record synthetic:3 --steps 120 --pattern three --out data/three
  rnnpb record webcam:0 --steps 150 --colors colors.json --pattern wave --out data/wave
  rnnpb record video:exercise.mp4 --perception pose --dt 0.1 --pattern exercise --out data/ex
  rnnpb record bvh:wave1.bvh,wave2.bvh --dt 0.1 --pattern wave --out data/wave
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
        metavar="N",
        help="whole cycles per sequence with --cut cycles (default: as many as make about 48 "
        "steps, at least 2)",
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
        help="play the recording S times slower (0.5: twice as fast; default 1: the person's "
        "own tempo)",
    )
    parser.add_argument(
        "--framing",
        metavar="reach|fit|M",
        help="where a person's body is placed in the robot camera's view: reach (the whole "
        "reach of the body in view, 1.55 m: the default, or the folder's framing), fit (the "
        "nearest that keeps this recording in view) or metres from the robot",
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
        "--up-axis",
        choices=("x", "y", "z", "-x", "-y", "-z"),
        help="bvh: the file's up axis (default: the one the shoulders are above the root on)",
    )
    add_perception_argument(parser)


def run(args: argparse.Namespace) -> int:
    import datetime
    from pathlib import Path

    from rnnpb.commands._checks import finite_seconds
    from rnnpb.commands._recording import check_folder_dt, folder_framing, write_recording
    from rnnpb.errors import ConfigError
    from rnnpb.learning_phase import PhaseOptions, learning_phase
    from rnnpb.sequences import pattern_name_problem, write_sequence

    problem = pattern_name_problem(args.pattern)
    if problem:
        raise ConfigError(f"--pattern {args.pattern!r} {problem}")
    finite_seconds("--dt", args.dt)
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out {out}: exists and is not a directory")
    framing = _framing(args.framing)
    if out.is_dir():
        check_folder_dt(out, args.dt)
        held = folder_framing(out)
        if args.framing is None and held is not None:
            framing = held
    options = PhaseOptions(
        dt=args.dt,
        time_scale=args.time_scale,
        framing=framing,
        cut=args.cut,
        cycles=args.cycles,
        length=args.length,
    )
    performance = _performance(args)
    recording = learning_phase(performance, args.pattern, options)
    out.mkdir(parents=True, exist_ok=True)
    names = []
    for i, sequence in enumerate(recording.sequences, 1):
        write_sequence(out / f"{args.pattern}_{i}.csv", sequence)
        names.append(f"{args.pattern}_{i}.csv")
    entry = {
        "source": str(args.source),
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "dt": args.dt,
        "sequences": names,
        **recording.to_json(),
        "capture": recording.capture,
    }
    write_recording(out, args.pattern, args.dt, entry, recording.framing.distance)
    seen = int(recording.seen.sum())
    depth_words = {
        "size": "ball size",
        "pose": "the pose model",
        "plane": "a fixed plane",
        "3-d": "motion capture",
    }
    print(
        f"recorded {recording.n_steps} steps of {args.dt:g} s from {recording.source} "
        f"(depth from {depth_words[recording.depth]}); {seen} with both hands seen"
    )
    if recording.capture is not None:
        take = recording.capture["takes"][0]["body"]
        print(
            f"body: arm {take['arm_length_m']:.3f} m, shoulders {take['shoulder_width_m']:.3f} m "
            f"apart (units {take['units']}, {take['up_axis']} up); hands scaled by "
            f"{take['scale']:.3f}; {len(recording.capture['takes'])} take(s)"
        )
    for line in recording.report(args.dt):
        print(line)
    print(
        f"{len(recording.sequences)} sequences of pattern {args.pattern!r} "
        f"({', '.join(str(s.n_steps) for s in recording.sequences)} steps) -> {out}"
    )
    return 0


def _framing(text: str | None) -> float | str:
    """``--framing``: reach (default), fit, or metres."""
    import math

    from rnnpb.errors import ConfigError

    if text is None or text.strip().lower() == "reach":
        return "reach"
    if text.strip().lower() == "fit":
        return "fit"
    try:
        value = float(text)
    except ValueError:
        raise ConfigError(f"--framing must be reach, fit or metres, got {text!r}") from None
    if not math.isfinite(value):
        raise ConfigError(f"--framing must be reach, fit or metres, got {text!r}")
    return value


def _performance(args: argparse.Namespace):
    """The person's movement from the source, as timed samples."""
    from rnnpb.errors import ConfigError
    from rnnpb.learning_phase import from_capture, from_source

    kind, _, argument = str(args.source).partition(":")
    if kind.strip().lower() == "bvh":
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
        performance = from_capture(files, hands=hands, units=args.units, up_axis=args.up_axis)
        if args.steps is not None:
            from dataclasses import replace

            keep = performance.times < args.steps * args.dt / args.time_scale
            performance = replace(
                performance, times=performance.times[keep], hands=performance.hands[keep]
            )
        return performance
    for option in ("hands", "units", "up_axis"):
        if getattr(args, option) is not None:
            raise ConfigError(f"--{option.replace('_', '-')} applies to bvh: sources")
    import math

    from rnnpb.interaction import open_source
    from rnnpb.learning_phase import SUBSTEPS
    from rnnpb.perception import DepthConfig

    frame_time = _frame_time(args)
    samples = args.steps
    stride = None
    if frame_time is not None:
        # Enough frames for a quarter of a step (the fastest cycle is looked for there), no more:
        # the pose model's time goes by frame.
        stride = max(1, math.floor(args.dt / args.time_scale / SUBSTEPS / frame_time))
        if args.steps is not None:
            samples = math.ceil(args.steps * args.dt / args.time_scale / (frame_time * stride)) + 1
        frame_time *= stride
    source = open_source(
        args.source,
        seed=args.seed,
        dt=args.dt,
        colors=args.colors,
        steps=args.steps if frame_time is None else None,
        perception=args.perception,
        frame_step=stride,
    )
    with source:
        return from_source(
            source,
            steps=samples,
            frame_time=frame_time,
            step_time=args.dt,
            plane_x=args.plane_x,
            depth=DepthConfig(ball_radius_m=args.ball_radius),
            live=str(args.source).strip().lower().startswith("webcam:"),
        )


def _frame_time(args: argparse.Namespace) -> float | None:
    """Seconds between a video's frames (read from the file), None for other sources."""

    kind, _, argument = str(args.source).partition(":")
    if kind.strip().lower() != "video":
        return None
    from rnnpb.perception import video_fps

    fps = video_fps(argument)
    return 1.0 / fps if fps else None
