"""``rnnpb view``: scrub through a recorded session in the rerun viewer."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # numpy is imported when a command runs: `rnnpb --help` stays fast
    import numpy as np

NAME = "view"
HELP = "scrub through a recorded session in the rerun viewer (hands, PB, joints, 3-D robot)"
DESCRIPTION = """\
Open a session recording (the session.csv of `rnnpb interact`, or one downloaded from the
dashboard) in rerun (https://rerun.io), the viewer robotics and machine-learning people use
for recorded time series: every step on one timeline you can scrub, with

  hands/      the observed hands and the network's prediction for them, in the camera's
              view plane (left ball red, right blue; predictions as rings)
  robot/      the humanoid's arms in 3-D (forward kinematics of the recorded joints)
  joints/     the eight joint angles, radians
  pb/         the parametric bias
  errors/     the prediction error and the window error
  status/     the ground-truth pattern, and recognition and novelty when recorded (and the
              routine level's routine and anticipated movement, `interact --routines`)

SESSION is a session CSV, or a folder holding session.csv. Without --save the viewer opens
(it needs a display); --save FILE.rrd writes a recording file instead, to open later with
`rerun FILE.rrd` or in the browser at https://app.rerun.io.

Needs the optional viewer: pip install 'rnnpb[view]' (rerun-sdk).

Examples:
  rnnpb view run/
  rnnpb view run/session.csv --save run/session.rrd
"""

LEFT_RGB = (220, 40, 40)  # the red ball on the user's left hand
RIGHT_RGB = (30, 90, 220)  # the blue ball on the right
#: Text columns shown on the status timeline when a recording has them.
STATUS_COLUMNS = (
    "truth_pattern",
    "recognised",
    "confidence",
    "novelty",
    "unsafe",
    "filtered",
    "routine",
    "anticipated",
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("session", metavar="SESSION", help="session.csv or a folder holding it")
    parser.add_argument(
        "--save",
        metavar="FILE.rrd",
        help="write a rerun recording file instead of opening the viewer",
    )


def _import_rerun():
    from rnnpb.errors import ConfigError

    try:
        import rerun
    except ImportError:
        raise ConfigError(
            "rnnpb view needs the rerun viewer: pip install 'rnnpb[view]' "
            "(or pip install rerun-sdk)"
        ) from None
    return rerun


def session_path(session: str | Path) -> Path:
    """The session CSV that ``session`` names (the file, or ``session.csv`` in a folder)."""
    from rnnpb.errors import ConfigError

    path = Path(session)
    if path.is_dir():
        path = path / "session.csv"
    if not path.is_file():
        raise ConfigError(f"{path}: no such session recording")
    return path


def arm_strips(joints: np.ndarray) -> np.ndarray:
    """The robot's arms as line strips from the joints: shoulder, elbow, hand per arm.

    Parameters
    ----------
    joints : array, shape (8,)
        Joint angles, radians, MOTOR_NAMES order.

    Returns
    -------
    array, shape (3, 3, 3)
        Three strips of three points, metres in the robot frame: the left arm, the right
        arm, and the torso (left shoulder, the point between the shoulders at hip height,
        right shoulder).
    """
    import numpy as np

    from rnnpb.robot import SHOULDERS, forward_kinematics

    hands, elbows = forward_kinematics(joints)
    hip = np.array([0.0, 0.0, 0.0])
    return np.stack(
        [
            np.stack([SHOULDERS[0], elbows[0], hands[0]]),
            np.stack([SHOULDERS[1], elbows[1], hands[1]]),
            np.stack([SHOULDERS[0], hip, SHOULDERS[1]]),
        ]
    )


def log_session(session: dict[str, np.ndarray], recording: Any, rr: Any) -> int:
    """Log every step of a session (as :func:`rnnpb.interaction.read_session` returns it) to
    a rerun ``recording``; return the number of steps logged."""
    import numpy as np

    from rnnpb.vectors import MOTOR_NAMES, PREDICTED_PREFIX, SENSORY_NAMES

    steps = np.asarray(session["step"], dtype=np.int64)
    n = len(steps)
    times = session.get("time_s")
    index = [rr.TimeColumn("step", sequence=steps)]
    if times is not None and np.all(np.isfinite(times)):
        index.append(rr.TimeColumn("time", duration=np.asarray(times, dtype=np.float64)))

    def series(path: str, values: np.ndarray) -> None:
        rr.send_columns(
            path,
            indexes=index,
            columns=rr.Scalars.columns(scalars=np.asarray(values, np.float64)),
            recording=recording,
        )

    for name in MOTOR_NAMES:
        series(f"joints/{name}", session[name])
    pb_names = sorted(
        (c for c in session if c.startswith("pb") and c[2:].isdigit()), key=lambda c: int(c[2:])
    )
    for name in pb_names:
        series(f"pb/{name}", session[name])
    for name in ("prediction_error", "window_error"):
        if name in session:
            series(f"errors/{name}", session[name])
    # The view plane as the camera sees it: y to the right, z up (rerun's 2-D y points down).
    rr.log(
        "hands/frame",
        rr.Boxes2D(mins=[0, 0], sizes=[1, 1], colors=[(160, 160, 160)]),
        static=True,
        recording=recording,
    )
    observed = np.stack([session[name] for name in SENSORY_NAMES], axis=1)
    predicted = (
        np.stack([session[PREDICTED_PREFIX + name] for name in SENSORY_NAMES], axis=1)
        if all(PREDICTED_PREFIX + name in session for name in SENSORY_NAMES)
        else np.full_like(observed, np.nan)
    )
    motor = np.stack([session[name] for name in MOTOR_NAMES], axis=1)
    status = [c for c in STATUS_COLUMNS if c in session]
    for i in range(n):
        rr.set_time("step", sequence=int(steps[i]), recording=recording)
        if len(index) > 1:
            rr.set_time("time", duration=float(times[i]), recording=recording)
        for what, values, radius in (
            ("observed", observed[i], 0.025),
            ("predicted", predicted[i], 0.04),
        ):
            points = values.reshape(2, 2)
            seen = np.all(np.isfinite(points), axis=1)
            colours = np.array([LEFT_RGB, RIGHT_RGB])[seen]
            xy = np.column_stack([points[seen, 0], 1.0 - points[seen, 1]])
            rr.log(
                f"hands/{what}", rr.Points2D(xy, radii=radius, colors=colours), recording=recording
            )
        if np.all(np.isfinite(motor[i])):
            rr.log(
                "robot/arms",
                rr.LineStrips3D(
                    arm_strips(motor[i]), radii=0.012, colors=[LEFT_RGB, RIGHT_RGB, (90, 90, 90)]
                ),
                recording=recording,
            )
        for name in status:
            value = session[name][i]
            text = (
                ""
                if value is None or (isinstance(value, float) and np.isnan(value))
                else str(value)
            )
            rr.log(f"status/{name}", rr.TextLog(f"{name}: {text or '—'}"), recording=recording)
    return n


def run(args: argparse.Namespace) -> int:
    from rnnpb.errors import ConfigError
    from rnnpb.interaction import read_session

    path = session_path(args.session)
    session = read_session(path)
    if not len(session["step"]):
        raise ConfigError(f"{path}: the recording has no steps")
    rr = _import_rerun()
    recording = rr.RecordingStream("rnnpb", recording_id=str(path.resolve()))
    if args.save:
        save = Path(args.save)
        if save.is_dir():
            raise ConfigError(f"--save {save}: is a folder; give a file name (.rrd)")
        save.parent.mkdir(parents=True, exist_ok=True)
        recording.save(save)
    else:
        recording.spawn()
    n = log_session(session, recording, rr)
    recording.flush()
    if args.save:
        recording.disconnect()
        print(f"wrote {args.save}: {n} steps of {path} (open with `rerun {args.save}`)")
    else:
        print(f"{n} steps of {path} sent to the rerun viewer")
    return 0
