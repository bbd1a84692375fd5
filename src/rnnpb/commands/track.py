"""``rnnpb track``: track the hands (coloured balls, or bare hands with ``--perception pose``)
in a camera, video, image folder or synthetic render, and write the sensory stream
``lhy lhz rhy rhz`` as CSV."""

from __future__ import annotations

import argparse

from rnnpb.commands._perception import add_perception_argument

NAME = "track"
HELP = "track the balls on the user's hands and write the sensory stream (CSV)"
DESCRIPTION = """\
Track the two coloured balls on the user's hands (red on the left hand, blue on the right by
default) frame by frame and write the sensory stream: one row per frame with columns
step, lhy, lhz, rhy, rhz (normalized image coordinates; an empty cell where a ball was lost).

SOURCE is one of:
  webcam:INDEX       a camera device (e.g. webcam:0)
  video:PATH         a video file
  images:DIR         a folder of images, in natural order of their names
  synthetic:PATTERN  the synthetic user performing PATTERN (1-4) rendered by the robot camera

Examples:
  rnnpb track video:me.mp4 --out me.csv --colors colors.json --render me_tracked.mp4
  rnnpb track synthetic:3 --steps 100 --out pattern3.csv
  rnnpb track webcam:0 --perception pose --out bare.csv   (bare hands: pip install 'rnnpb[hands]')
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "source", metavar="SOURCE", help="webcam:INDEX, video:PATH, images:DIR or synthetic:PATTERN"
    )
    parser.add_argument(
        "--out", required=True, metavar="FILE.csv", help="where to write the sensory stream"
    )
    parser.add_argument(
        "--colors",
        metavar="FILE.json",
        help="ball colour ranges (from `rnnpb calibrate`); default red/blue",
    )
    parser.add_argument(
        "--steps",
        type=int,
        metavar="N",
        help="track at most N frames (synthetic: render N frames, default 200)",
    )
    parser.add_argument(
        "--render",
        metavar="OUT.mp4",
        help="also write a video (.mp4 or .avi) with the tracked balls marked",
    )
    parser.add_argument(
        "--fps", type=float, default=10.0, help="frame rate of the --render video (default 10)"
    )
    parser.add_argument(
        "--smoothing",
        type=float,
        default=0.0,
        help="exponential smoothing of the ball centres in [0, 1) (default 0)",
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the synthetic source")
    add_perception_argument(parser)
    parser.add_argument(
        "--no-progress",
        action="store_true",
        help="no progress bar (there is none when stderr is not a terminal)",
    )


def run(args: argparse.Namespace) -> int:
    import math
    from dataclasses import replace

    import numpy as np

    from rnnpb.commands._checks import step_count
    from rnnpb.commands.progress import progress_bar
    from rnnpb.errors import ConfigError
    from rnnpb.interaction import CAMERA_KINDS, parse_source_spec
    from rnnpb.perception import (
        TrackerConfig,
        VideoWriter,
        draw_tracking,
        load_ball_colors,
        open_camera_source,
    )
    from rnnpb.sequences import write_sensory_stream

    step_count("--steps", args.steps)
    if not (math.isfinite(args.fps) and 0 < args.fps <= 1000):
        raise ConfigError(f"--fps must be in (0, 1000] frames per second, got {args.fps}")
    if not (math.isfinite(args.smoothing) and 0 <= args.smoothing < 1):
        raise ConfigError(f"--smoothing must be in [0, 1), got {args.smoothing}")
    spec = parse_source_spec(args.source, kinds=CAMERA_KINDS)
    config = TrackerConfig(smoothing=args.smoothing)
    if args.colors:
        config = replace(config, colors=load_ball_colors(args.colors))
    source = open_camera_source(
        spec.kind,
        spec.argument,
        tracker_config=config,
        steps=args.steps,
        seed=args.seed,
        perception=args.perception,
    )
    rows = []
    writer = VideoWriter(args.render, args.fps) if args.render else None
    ok = False
    try:
        with (
            source,
            progress_bar(
                total=args.steps, unit="frame", desc="tracking", disable=args.no_progress
            ) as bar,
        ):
            while (observation := source.read()) is not None:
                rows.append(observation.sensory)
                bar.update(1)
                if writer is not None and source.last_result is not None:
                    writer.write(
                        draw_tracking(observation.frame, source.last_result, config.colors)
                    )
        ok = True
    finally:
        if writer is not None:
            writer.close(keep=ok)
    if not rows:
        from rnnpb.errors import RnnpbError

        raise RnnpbError(f"{args.source}: delivered no frames")
    write_sensory_stream(args.out, np.asarray(rows))
    n = len(rows)
    left, right = (int(v) for v in source.lost_frames)
    print(f"tracked {n} frames from {source.description} -> {args.out}")
    if args.perception == "pose":
        print(f"left hand lost in {left} of {n} frames, right hand lost in {right} of {n} frames")
    else:
        print(
            f"left ball ({config.colors.left.name}) lost in {left} of {n} frames, "
            f"right ball ({config.colors.right.name}) lost in {right} of {n} frames"
        )
    if writer is not None:
        print(f"marked video -> {args.render}")
    return 0
