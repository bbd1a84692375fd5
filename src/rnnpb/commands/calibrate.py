"""``rnnpb calibrate``: fit the balls' colour ranges to a frame of the user's own camera."""

from __future__ import annotations

import argparse

NAME = "calibrate"
HELP = "fit the ball colour ranges to a frame of your camera (writes colors.json)"
DESCRIPTION = """\
Take one frame from SOURCE and fit the HSV colour range of each ball to it, then write the
colour file for `rnnpb track --colors` and a preview PNG: the frame with the found balls
circled, next to the mask each fitted range gives (only the ball should light up).

Give where the balls are with --left-pixel/--right-pixel X,Y (column,row of a pixel in the
middle of the ball on the user's LEFT and RIGHT hand), or leave them out to take the red and
the blue blob that move like hands over the frames up to --frame (use --frame 30 or so while
moving your hands, so that a still red or blue object in the room is not taken for a ball).

SOURCE is webcam:INDEX, video:PATH, images:DIR or synthetic:PATTERN.

Examples:
  rnnpb calibrate webcam:0 --out colors.json
  rnnpb calibrate video:me.mp4 --frame 30 --left-pixel 412,220 --right-pixel 190,231 \\
      --out colors.json --preview colors.png
"""


def _pixel(text: str) -> tuple[int, int]:
    try:
        x, y = (int(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected X,Y (two integers), got {text!r}") from None
    return x, y


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "source", metavar="SOURCE", help="webcam:INDEX, video:PATH, images:DIR or synthetic:PATTERN"
    )
    parser.add_argument(
        "--out", required=True, metavar="FILE.json", help="where to write the colour file"
    )
    parser.add_argument(
        "--preview",
        metavar="FILE.png",
        help="where to write the preview (default: next to --out, .png)",
    )
    parser.add_argument(
        "--frame",
        type=int,
        default=0,
        metavar="N",
        help="use frame N of the source (default 0; for a webcam, frames "
        "before N let its exposure settle)",
    )
    parser.add_argument(
        "--left-pixel",
        type=_pixel,
        metavar="X,Y",
        help="a pixel in the middle of the ball on the user's left hand",
    )
    parser.add_argument(
        "--right-pixel",
        type=_pixel,
        metavar="X,Y",
        help="a pixel in the middle of the ball on the user's right hand",
    )
    parser.add_argument("--left-name", default=None, help="name of the left ball's colour")
    parser.add_argument("--right-name", default=None, help="name of the right ball's colour")


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    import cv2

    from rnnpb._atomic import atomic_write
    from rnnpb.errors import RnnpbError
    from rnnpb.interaction import CAMERA_KINDS, parse_source_spec
    from rnnpb.perception import (
        BROAD_BLUE,
        BROAD_RED,
        BallColor,
        BallColors,
        calibrate_automatically,
        calibrate_from_pixel,
        calibration_preview,
        locate_ball,
        open_frame_source,
        save_ball_colors,
    )

    if not 0 <= args.frame <= 1_000_000:
        raise RnnpbError(f"--frame must be in [0, 1,000,000], got {args.frame}")
    spec = parse_source_spec(args.source, kinds=CAMERA_KINDS)
    frame = None
    recent = []  # the last frames up to --frame: motion tells the balls from look-alikes
    with open_frame_source(spec.kind, spec.argument, steps=args.frame + 1) as source:
        for image in source:
            frame = image
            recent = [*recent[-29:], image]
        if frame is None or source.frame_index < args.frame:
            raise RnnpbError(f"{args.source}: has no frame {args.frame}")

    calibrations = []
    for side, pixel, broad, name in (
        ("left", args.left_pixel, BROAD_RED, args.left_name),
        ("right", args.right_pixel, BROAD_BLUE, args.right_name),
    ):
        if pixel is not None:
            height, width = frame.shape[:2]
            if not (0 <= pixel[0] < width and 0 <= pixel[1] < height):
                raise RnnpbError(
                    f"--{side}-pixel {pixel[0]},{pixel[1]} is outside the {width}x{height} frame"
                )
            cal = calibrate_from_pixel(frame, pixel, name)
        else:
            cal = calibrate_automatically(recent, broad)
        if name and cal.color.name != name:
            c = cal.color
            cal = type(cal)(
                BallColor(name, c.hue, c.saturation, c.value),
                cal.center_px,
                cal.radius_px,
                cal.n_pixels,
            )
        calibrations.append(cal)
    colors = BallColors(calibrations[0].color, calibrations[1].color)

    # Check the fitted ranges the way `rnnpb track` will use them.
    for i, (side, cal) in enumerate(zip(("left", "right"), calibrations, strict=True)):
        found = locate_ball(recent, colors.balls[i])
        if found is None:
            raise RnnpbError(f"calibration: the fitted {side} range finds no ball in the frame")
        off = float(((found[0] - cal.center_px) ** 2).sum() ** 0.5)
        if off > max(3.0, cal.radius_px):
            raise RnnpbError(
                f"calibration: with the fitted {side} range the tracker picks a "
                f"blob {off:.0f} px away from the calibrated ball; another object "
                "has the same colour — move it away or give --"
                f"{side}-pixel"
            )
    save_ball_colors(args.out, colors)
    preview = Path(args.preview) if args.preview else Path(args.out).with_suffix(".png")
    ok, png = cv2.imencode(
        ".png", calibration_preview(frame, colors, (calibrations[0], calibrations[1]))
    )
    if not ok:
        raise RnnpbError(f"{preview}: cannot encode the preview")
    with atomic_write(preview, "wb") as handle:
        handle.write(png.tobytes())
    for side, cal in zip(("left", "right"), calibrations, strict=True):
        c = cal.color
        print(
            f"{side} ball ({c.name}): hue {c.hue[0]}..{c.hue[1]}, saturation "
            f"{c.saturation[0]}..{c.saturation[1]}, value {c.value[0]}..{c.value[1]}; "
            f"found at {cal.center_px[0]:.1f},{cal.center_px[1]:.1f}, radius "
            f"{cal.radius_px:.1f} px"
        )
    print(f"colour file -> {args.out}")
    print(f"preview -> {preview}")
    return 0
