"""rnnpb interact: the interaction loop — a user source drives the robot through the RNNPB."""

from __future__ import annotations

import argparse

NAME = "interact"
SAFE_POINTS = True  # Ctrl-C stops between steps (rnnpb._interrupt)
HELP = "run the on-line interaction: a user source drives the robot"
DESCRIPTION = """\
Run the interaction phase: every step the robot observes the user's hands, the mirror
system regresses the parametric bias over the last L steps (weights frozen) and generates
the motor command, which the robot executes.

Sources (--source):
  scenario:held:P | scenario:pause:P | scenario:switch:A,B,C | scenario:novel:SET
  csv:FILE        a sensory stream (step,lhy,lhz,rhy,rhz; empty cell = hand not seen)
  video:FILE | images:DIR | webcam:INDEX | synthetic:P   (through the colour-ball tracker)

Writes DIR/session.csv (one row per step), DIR/session.png (the paper's Figure 5 layout)
and DIR/summary.json (timings per section, missed deadlines, config, versions); with
--render also DIR/session.mp4: the camera frame with the tracked balls | the robot.

Steps where a hand is lost are run on the network's own prediction and marked in the
recording (lost_left, lost_right).

Safety (docs/safety.md): every command passes the command filter before it is sent (it
slows a command faster than the servos and holds or shortens one that would collide; the
recording's unsafe and filtered columns say so); with a safety map beside the model
(MODEL.safety.npz, from `rnnpb safety learn`) the regression also keeps the PB out of the
learned unsafe region. Without a map the filter alone guards (said once). --no-safety turns
both off.

Example:
  rnnpb interact --model results/models/set1.npz --source scenario:switch:1,2,3 --out run/
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--model", required=True, help="trained model (.npz)")
    parser.add_argument("--source", required=True, help="what drives the robot (see above)")
    parser.add_argument("--out", required=True, metavar="DIR", help="output directory")
    parser.add_argument("--robot", choices=("kinematic", "mujoco"), default="kinematic",
                        help="simulated robot (default kinematic: instant, no physics)")
    parser.add_argument("--online", choices=("default", "paper", "ungated"), default="default",
                        help="on-line regression settings (default: the best measured; "
                        "ungated: without the surprise gate, for models learned with "
                        "--preset fast; paper: the paper's)")
    parser.add_argument("--paced", action="store_true",
                        help="run in real time, one step every --dt seconds")
    parser.add_argument("--dt", type=float, default=0.4, help="seconds per step (default 0.4)")
    parser.add_argument("--steps", type=int, help="stop after this many steps")
    parser.add_argument("--colors", help="colour config JSON for camera sources")
    parser.add_argument("--frame-step", type=int,
                        help="use every N-th camera frame (default: video fps x dt)")
    parser.add_argument("--seed", type=int, default=0, help="seed for scenario sources")
    parser.add_argument("--render", action="store_true",
                        help="also write session.mp4: camera frame | simulated robot")
    parser.add_argument("--no-safety", action="store_true",
                        help="no command filter and no PB guard (docs/safety.md)")


def run(args: argparse.Namespace) -> int:
    import contextlib
    import json
    import os
    from pathlib import Path

    from rnnpb import __version__, _interrupt
    from rnnpb._atomic import atomic_write
    from rnnpb.analysis.figures import plot_session
    from rnnpb.interaction import (
        InteractionLoop,
        LoopConfig,
        SessionRecorder,
        open_source,
        read_session,
    )
    from rnnpb.model import MirrorSystem, OnlineConfig, TrainedModel
    from rnnpb.robot import JOINT_LIMITS, KinematicRobot

    model = TrainedModel.load(args.model, joint_limits=JOINT_LIMITS)
    online = {"paper": OnlineConfig.paper, "ungated": OnlineConfig.ungated}.get(
        args.online, OnlineConfig)()
    loop_config = LoopConfig(dt=args.dt, paced=args.paced, max_steps=args.steps)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    source = open_source(args.source, seed=args.seed, dt=args.dt, frame_step=args.frame_step,
                         colors=args.colors, steps=args.steps)
    if args.robot == "mujoco":
        os.environ.setdefault("MUJOCO_GL", "egl")
        from rnnpb.robot import MujocoRobot

        robot = MujocoRobot(dt=args.dt)
    else:
        robot = KinematicRobot(dt=args.dt)
    from rnnpb.safety import online_safety

    safety = online_safety(args.model, model, online, enabled=not args.no_safety)
    online = safety.config
    mirror = MirrorSystem(model, online, meta=safety.meta)
    with contextlib.ExitStack() as stack:
        stack.enter_context(source)
        stack.enter_context(robot)
        if safety.command_filter is not None:
            safety.command_filter.reset(robot.read())  # the pose the first command leaves
        recorder = stack.enter_context(SessionRecorder(out / "session.csv",
                                                       model.network.pb_size))
        loop = InteractionLoop(mirror, source, robot, recorder, loop_config,
                               command_filter=safety.command_filter)
        if args.render:
            from rnnpb.interaction.render import SessionVideo

            video = stack.enter_context(SessionVideo(out / "session.mp4", fps=1.0 / args.dt))
            loop.subscribe(video.add)
        print(f"interacting: {args.source} -> {args.model} ({args.online} regression, "
              f"{args.robot} robot{', paced' if args.paced else ''}); Ctrl-C stops")
        print(safety.note)
        try:
            # Between steps is the safe point: the step's results are read back from XLA.
            summary = loop.run(on_step=lambda record: _interrupt.check())
        except KeyboardInterrupt:
            summary = loop.summary()
            print("interrupted: the recording keeps every step so far")
    session = read_session(out / "session.csv")
    if len(session["step"]):
        plot_session(session, out / "session.png", title=f"{args.source} — {args.model}",
                     joint_limits=JOINT_LIMITS)
    document = {"rnnpb_version": __version__, "model": str(args.model), "source": args.source,
                "online_config": online.to_dict(), "loop": summary.to_dict(),
                "dt": args.dt, "paced": args.paced, "robot": args.robot,
                "safety": {**safety.to_dict(), "unsafe_commands": loop.unsafe_commands,
                           "prevented_commands": loop.prevented_commands}}
    with atomic_write(out / "summary.json", "w", encoding="utf-8") as handle:
        json.dump(document, handle, indent=2)
    print(summary.describe())
    if safety.command_filter is not None:
        print(f"safety: {loop.unsafe_commands} unsafe commands generated, "
              f"{loop.prevented_commands} held, shortened or slowed by the filter")
    print(f"wrote {out / 'session.csv'}, {out / 'session.png'}, {out / 'summary.json'}"
          + (f", {out / 'session.mp4'}" if args.render else ""))
    return 0
