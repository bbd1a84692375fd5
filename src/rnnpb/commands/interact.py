"""rnnpb interact: the interaction loop — a user source drives the robot through the RNNPB."""

from __future__ import annotations

import argparse
import contextlib

from rnnpb.commands._config import RUN_SECTIONS, TEACHING_SECTIONS, add_config_argument
from rnnpb.commands._perception import add_perception_argument
from rnnpb.commands._signals import terminate_as_interrupt

NAME = "interact"
CONFIG_SECTIONS = RUN_SECTIONS
SAFE_POINTS = True  # Ctrl-C stops between steps (rnnpb._interrupt)
HELP = "run the on-line interaction: a user source drives the robot"
DESCRIPTION = """\
Run the interaction phase: every step the robot observes the user's hands, the mirror
system regresses the parametric bias over the last L steps (weights frozen) and generates
the motor command, which the robot executes.

Sources (--source):
  scenario:held:P | scenario:pause:P | scenario:switch:A,B,C | scenario:novel:SET
  scenario:steps:M*N,...   movements (any demonstrator movement or pause), N steps each
  csv:FILE        a sensory stream (step,lhy,lhz,rhy,rhz; empty cell = hand not seen)
  video:FILE | images:DIR | webcam:INDEX | synthetic:P   (through the colour-ball tracker)
  zenoh:KEY[@ENDPOINT]     hands published on a Zenoh bus by a camera node (docs/bridge.md)
  bvh:FILE[,FILE...]       motion capture, read as `rnnpb record` reads it (docs/motion-capture.md)

Writes DIR/session.csv (one row per step), DIR/session.png (the paper's Figure 5 layout)
and DIR/summary.json (timings per section, missed deadlines, config, versions, the
recognition timeline); with
--render also DIR/session.mp4: the camera frame with the tracked balls | the robot.

While it runs, a step counter shows what the robot recognises (the learned pattern and
its confidence, "new movement", "hands still", ...); at the end it prints the recognition
timeline: which answer held from which step to which.

Steps where a hand is lost are run on the network's own prediction and marked in the
recording (lost_left, lost_right).

Without --model: the first model (by name) in ./models/, else in ./results/demo/models/
(what `make demo` writes), else the small model shipped with rnnpb (learning set 1 — patterns
1, 2, 3 — learned with the fast preset).

The on-line regression (--online) defaults to the one that suits how the model was learned
(`auto`): `ungated` for a model learned with the fast preset (Adam), `default` for one
learned by the paper's algorithm; the choice is printed. --config FILE overrides any of the
learning preset's [online], [recognition] or [recognition_untaught] values for research
([online] changes the regression in use, whichever --online chose; docs/model.md), and with
--learn its [teaching.cutter], [teaching] and [consolidation] values.

With --learn the robot learns new movements on-line (docs/teaching.md): when the novelty
detector has called a structured movement `novel` for a few cycles, two whole cycles of it
(a performance of three or four cycles: all of it, when it ends) are kept in the model's
short-term memory (MODEL.memory.sqlite) as pattern new-1, new-2, ....
A later performance of the same shape is merged with it (never a second pattern); once a
movement has been seen twice ("new-1 seen twice") it is consolidated, from both performances,
into a new model version (MODEL.v2.npz, ...; the old file stays) in a background process, and
the new version is swapped in between two steps (--learn-from-one: from its first
performance). A performance of a pattern learned this way that is kept again is more data for
it: the pattern grows with use. When a file or scenario source ends, a performance still
going is kept as if the person had stopped. Run as fast as possible (a file or scenario
source, no --paced) the loop waits for each consolidation, so a scripted run repeats; paced
it never waits. A failed consolidation keeps the running model
and says why. One line is printed for each episode kept and each consolidation's start and
end; summary.json lists the episodes and the versions written.

A progress bar on stderr shows the steps (only on a terminal; --no-progress turns it off).

Safety (docs/safety.md): every command passes the command filter before it is sent (it
slows a command faster than the servos and holds or shortens one that would collide; the
recording's unsafe and filtered columns say so); with a safety map beside the model
(MODEL.safety.npz, from `rnnpb safety learn`) the regression also keeps the PB out of the
learned unsafe region. Without a map the filter alone guards (said once). --no-safety turns
both off.

Example:
  rnnpb interact --model results/demo/models/set1.npz --source scenario:switch:1,2,3 --out run/
  rnnpb interact --model m.npz --source scenario:steps:1*40,figure-eight*100 --learn --out run/
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--model",
        help="trained model (.npz) or a folder of them (default: "
        "./models/, ./results/demo/models/, else the shipped model)",
    )
    parser.add_argument("--source", required=True, help="what drives the robot (see above)")
    parser.add_argument("--out", required=True, metavar="DIR", help="output directory")
    parser.add_argument(
        "--robot",
        default="kinematic",
        metavar="ROBOT",
        help="kinematic (default: simulated, instant, no physics), mujoco (simulated with "
        "physics), zenoh[:PREFIX][@ENDPOINT] (a robot process on a Zenoh bus, e.g. "
        "`rnnpb robot serve`), ros2dds[:CONTROLLER][@ENDPOINT] (a ROS 2 robot through "
        "zenoh-bridge-ros2dds) or rclpy[:CONTROLLER] (ROS 2 installed); docs/bridge.md",
    )
    parser.add_argument(
        "--robot-map",
        metavar="FILE",
        help="with a robot on a bus: its joint names, signs, offsets and limits (TOML; "
        "default: the simulated humanoid's)",
    )
    parser.add_argument(
        "--online",
        choices=("auto", "default", "paper", "ungated"),
        default="auto",
        help="on-line regression settings (auto, the default: the one that "
        "suits how the model was learned; default: the one chosen for the "
        "paper's algorithm; ungated: without the surprise gate, for models "
        "learned with --preset fast; paper: the paper's)",
    )
    parser.add_argument(
        "--paced", action="store_true", help="run in real time, one step every --dt seconds"
    )
    parser.add_argument(
        "--dt",
        type=float,
        help="seconds per step (default: the model's, the step it was learned at; another "
        "is refused)",
    )
    parser.add_argument("--steps", type=int, help="stop after this many steps")
    parser.add_argument("--colors", help="colour config JSON for camera sources")
    add_perception_argument(parser)
    parser.add_argument(
        "--frame-step", type=int, help="use every N-th camera frame (default: video fps x dt)"
    )
    parser.add_argument("--seed", type=int, default=0, help="seed for scenario sources")
    parser.add_argument(
        "--time-scale",
        type=float,
        default=1.0,
        metavar="S",
        help="bvh: play the motion capture S times slower (default 1: the person's tempo)",
    )
    parser.add_argument(
        "--render",
        action="store_true",
        help="also write session.mp4: camera frame | simulated robot",
    )
    parser.add_argument(
        "--learn",
        action="store_true",
        help="learn new movements on-line: keep them in the short-term memory, "
        "consolidate them into a new model version, swap it in (see above)",
    )
    parser.add_argument(
        "--consolidation-iterations",
        type=int,
        metavar="N",
        help="with --learn: learning iterations of each consolidation "
        "(default: 30,000 for the paper's learning, 1,000 for the fast preset's; "
        "docs/teaching.md)",
    )
    parser.add_argument(
        "--learn-from-one",
        action="store_true",
        help="with --learn: learn a new movement from its first performance instead of "
        "waiting for a second one (a pattern learned from one generalises less)",
    )
    parser.add_argument(
        "--no-safety",
        action="store_true",
        help="no command filter and no PB guard (docs/safety.md)",
    )
    parser.add_argument(
        "--routines",
        metavar="FILE",
        help="a routine file learned over this model (`rnnpb train-routines`): the robot "
        "also follows routines and anticipates their switches; the recording gains the "
        "columns routine and anticipated (docs/routines.md)",
    )
    add_config_argument(parser, CONFIG_SECTIONS)
    parser.add_argument(
        "--no-progress",
        action="store_true",
        help="no progress bar (there is none when stderr is not a terminal)",
    )


def run(args: argparse.Namespace) -> int:
    import json
    from pathlib import Path
    from typing import cast

    from rnnpb import __version__, _interrupt
    from rnnpb._atomic import atomic_write
    from rnnpb.analysis.figures import plot_session
    from rnnpb.commands._checks import finite_seconds, played_dt, step_count
    from rnnpb.commands._config import read_config
    from rnnpb.commands.progress import progress_bar
    from rnnpb.interaction import (
        InteractionLoop,
        LoopConfig,
        SessionRecorder,
        open_source,
        read_session,
    )
    from rnnpb.model import MirrorSystem, OnlineConfig, TrainedModel
    from rnnpb.model.recognition import describe_answer, recognition_timeline
    from rnnpb.models import default_model, first_model_file
    from rnnpb.robot import JOINT_LIMITS

    if args.dt is not None:
        finite_seconds("--dt", args.dt)
    step_count("--steps", args.steps, low=0)
    step_count("--frame-step", args.frame_step)
    step_count("--consolidation-iterations", args.consolidation_iterations)
    if args.consolidation_iterations is not None and not args.learn:
        from rnnpb.errors import ConfigError

        raise ConfigError("--consolidation-iterations needs --learn")
    if args.learn_from_one and not args.learn:
        from rnnpb.errors import ConfigError

        raise ConfigError("--learn-from-one needs --learn")
    overrides = read_config(args.config, CONFIG_SECTIONS, NAME)
    if overrides is not None and set(overrides.names) & set(TEACHING_SECTIONS) and not args.learn:
        from rnnpb.errors import ConfigError

        raise ConfigError(
            f"{overrides.origin}: [teaching], [teaching.cutter] and [consolidation] apply with "
            "--learn"
        )
    model_path = first_model_file(Path(args.model) if args.model else default_model())
    model = TrainedModel.load(model_path, joint_limits=JOINT_LIMITS)
    args.dt = played_dt(model_path, model.dt, args.dt)
    # The regression and the recognition that suit the model, the --config file's values over
    # both (read where the preset's are).
    choice = OnlineConfig.for_model(model, overrides)
    if args.online == "auto":
        online_name, online = choice.name, choice.config
        why = f", chosen as {choice.reason}; --online overrides"
    else:
        # the named preset's regression, its effort per second kept at the model's step
        online_name = args.online
        online = OnlineConfig.preset(args.online).at_step(model.dt).overridden(overrides)
        why = ""
    if overrides is not None:
        why += f"; values from {overrides.origin}"

    loop_config = LoopConfig(dt=args.dt, paced=args.paced, max_steps=args.steps)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    source = open_source(
        args.source,
        seed=args.seed,
        dt=args.dt,
        frame_step=args.frame_step,
        colors=args.colors,
        steps=args.steps,
        perception=args.perception,
        framing=model.framing,
        time_scale=args.time_scale,
    )
    from rnnpb.commands.robot import open_robot

    robot = open_robot(args.robot, args.dt, args.robot_map, waiting=_interrupt.check)
    from rnnpb.safety import online_safety

    safety = online_safety(model_path, model, online, enabled=not args.no_safety)
    online = safety.config
    extra_columns: tuple[str, ...] = ()
    if args.routines is not None:
        from rnnpb.interaction.routines import ROUTINE_COLUMNS, RoutineMirror
        from rnnpb.model.routines import RoutineModel

        if args.learn:
            from rnnpb.errors import ConfigError

            raise ConfigError("--routines and --learn exclude each other")
        routines = RoutineModel.load(args.routines, model)
        mirror = RoutineMirror(
            model,
            routines,
            online,
            recognition=choice.recognition,
            **safety.mirror_options,
        )
        extra_columns = ROUTINE_COLUMNS
    else:
        mirror = MirrorSystem(
            model, online, recognition=choice.recognition, **safety.mirror_options
        )
    with contextlib.ExitStack() as stack:
        # SIGTERM (`kill`, a service manager) ends the run as Ctrl-C does: at the next step,
        # with the recording, the summary and a playable video.
        stack.enter_context(terminate_as_interrupt())
        stack.enter_context(source)
        stack.enter_context(robot)
        if safety.command_filter is not None:
            safety.command_filter.reset(robot.read())  # the pose the first command leaves
        recorder = stack.enter_context(
            SessionRecorder(
                out / "session.csv",
                model.network.pb_size,
                extra_columns,
                getattr(mirror, "columns", None),
            )
        )
        # A RoutineMirror steps where the mirror system does (its `model`, `step`).
        loop = InteractionLoop(
            cast("MirrorSystem", mirror),
            source,
            robot,
            recorder,
            loop_config,
            command_filter=safety.command_filter,
        )
        if args.render:
            from rnnpb.interaction.render import SessionVideo

            video = stack.enter_context(SessionVideo(out / "session.mp4", fps=1.0 / args.dt))
            loop.subscribe(video.add)
        teacher = None
        if args.learn:
            teacher = _start_teaching(
                stack, loop, model_path, source, args, online, overrides, model.framing
            )
        # One line, printed just before the first compilation starts.
        print(
            f"interacting: {args.source} -> {model_path} ({online_name} on-line regression"
            f"{why}; {args.robot} robot{', paced' if args.paced else ''}); Ctrl-C stops",
            flush=True,
        )
        print(safety.note, flush=True)
        bar = stack.enter_context(
            progress_bar(
                total=args.steps or _source_length(source),
                unit="step",
                desc="interacting",
                disable=args.no_progress,
            )
        )
        answers: list[tuple[str | None, str]] = []
        said = [0]  # teaching events printed so far

        def say_teaching() -> None:
            for event in teacher.events[said[0] :]:
                if event.kind not in _TEACHING_LINES:
                    continue
                text = event.text
                if event.kind == "consolidating":
                    text += f" (pattern {event.pattern})"
                line = f"step {event.step + 1}: {text}"
                if bar.disable:
                    print(line, flush=True)
                else:
                    bar.write(line)
            said[0] = len(teacher.events)

        def between_steps(wait_s: float) -> None:
            if teacher.wait and teacher.job is not None:
                # Waiting for the consolidation in slices keeps Ctrl-C working meanwhile.
                while teacher.job.wait(timeout_s=0.2).state == "running":
                    _interrupt.check()
            teacher.between_steps(wait_s)
            say_teaching()

        def after_step(record) -> None:
            if teacher is not None:
                say_teaching()
            answers.append((record.recognised, record.novelty))
            text = describe_answer(record.recognised, record.confidence, record.novelty)
            if not bar.disable:  # a terminal: the live counter is the bar, the answer beside it
                bar.set_postfix_str(text, refresh=False)
                bar.update(1)
            elif len(answers) == 1 or answers[-1] != answers[-2]:
                print(f"step {record.step + 1}: {text}", flush=True)
            # Between steps is the safe point: the step's results are read back from XLA.
            _interrupt.check()

        try:
            summary = loop.run(
                on_step=after_step, between_steps=between_steps if teacher is not None else None
            )
            if teacher is not None:
                # The source has ended: a performance still going is kept as if the person
                # had stopped (a recording that ends mid-movement keeps its last one).
                teacher.finish()
                say_teaching()
            if teacher is not None and teacher.job is not None:
                # An episode kept near the end: its consolidation finishes, so that the run
                # leaves the version it started (paced too: the interaction is over).
                print("waiting for the consolidation to finish", flush=True)
                teacher.wait = True
                between_steps(0.0)
        except KeyboardInterrupt:
            summary = loop.summary()
            bar.close()
            if teacher is not None and teacher.job is not None:
                teacher.job.cancel()
                print(
                    "interrupted: the running consolidation is cancelled, the kept "
                    "episodes stay in the memory"
                )
            print("interrupted: the recording keeps every step so far")
        teaching = None if teacher is None else _teaching_summary(teacher)
    timeline = recognition_timeline(answers)
    print("recognition timeline:")
    for part in timeline:
        text = describe_answer(part["recognised"], 1.0, part["novelty"]).split(" (")[0]
        print(f"  steps {part['first'] + 1:>4}-{part['last'] + 1:<4} {text}")
    session = read_session(out / "session.csv")
    if len(session["step"]):
        plot_session(
            session,
            out / "session.png",
            title=f"{args.source} — {model_path}",
            joint_limits=JOINT_LIMITS,
            dt=args.dt,
        )
    document = {
        "rnnpb_version": __version__,
        "model": str(model_path),
        "source": args.source,
        "online": online_name,
        "online_config": online.to_dict(),
        "loop": summary.to_dict(),
        "dt": args.dt,
        "paced": args.paced,
        "robot": args.robot,
        "recognition_config": mirror.recognition.to_dict(),
        "recognition_timeline": timeline,
        "safety": {
            **safety.to_dict(),
            "unsafe_commands": loop.unsafe_commands,
            "prevented_commands": loop.prevented_commands,
            "inhibited_commands": loop.inhibited_commands,
        },
    }
    if teaching is not None:
        document["teaching"] = teaching
    with atomic_write(out / "summary.json", "w", encoding="utf-8") as handle:
        json.dump(document, handle, indent=2)
    print(summary.describe())
    if safety.command_filter is not None:
        print(
            f"safety: {loop.unsafe_commands} unsafe commands generated, "
            f"{loop.prevented_commands} held, shortened or slowed by the filter, "
            f"{loop.inhibited_commands} inhibited by the meta-level"
        )
    if teaching is not None:
        versions = [Path(v).name for v in teaching["versions_written"]]
        print(
            f"learned: {len(teaching['episodes'])} episode(s) kept, model versions written: "
            + (", ".join(versions) or "none")
            + f"; memory {teaching['memory']}"
        )
    print(
        f"wrote {out / 'session.csv'}, {out / 'session.png'}, {out / 'summary.json'}"
        + (f", {out / 'session.mp4'}" if args.render else "")
    )
    return 0


# The teaching events worth a line of their own (`recording` changes every cycle: the bar's
# or the step lines' business would be too chatty).
_TEACHING_LINES = ("kept", "extended", "waiting", "refused", "consolidating", "learned", "failed")


def _start_teaching(stack, loop, model_path, source, args, online, overrides, framing):
    """Open the model's short-term memory and subscribe a Teacher to the loop (with the
    --config file, ``overrides``); a person's 3-D hands stand at ``framing`` metres."""
    from pathlib import Path

    import rnnpb.models
    from rnnpb.interaction.teaching import PERFORMANCES, Teacher, tracked_hands
    from rnnpb.memory import MemoryStore, memory_path_for
    from rnnpb.model import MirrorSystem, OnlineConfig

    model_path = Path(model_path)
    shipped = Path(rnnpb.models.__file__).resolve().parent
    if model_path.resolve().parent == shipped:
        # New versions and the memory are written beside the model: never into the installed
        # package. Learning starts from a copy of the shipped model in the run's folder.
        import shutil

        copy = Path(args.out) / model_path.name
        if not copy.exists():
            shutil.copyfile(model_path, copy)
        print(f"learning from a copy of the shipped model: {copy}", flush=True)
        model_path = copy
    memory = stack.enter_context(MemoryStore(memory_path_for(model_path)))
    # On cancel/exit a consolidation still running must not outlive the command.
    teacher = Teacher(
        loop,
        model_path,
        memory,
        make_mirror=lambda model: MirrorSystem(
            model, online, recognition=OnlineConfig.for_model(model, overrides).recognition
        ),
        source=args.source,
        hands_of=tracked_hands(source),
        framing=framing,
        iterations=args.consolidation_iterations,
        overrides=overrides,
        performances=1 if args.learn_from_one else PERFORMANCES,
    )
    stack.callback(lambda: teacher.job.cancel() if teacher.job is not None else None)
    print(
        f"learning new movements: short-term memory {memory.path}"
        + (
            ", waiting for each consolidation"
            if teacher.wait
            else ", consolidating in the background"
        ),
        flush=True,
    )
    return teacher


def _teaching_summary(teacher) -> dict:
    """summary.json's ``teaching``: the episodes this run kept and the versions it wrote."""
    kept = set(teacher.keeper.kept)
    episodes = [
        {
            "id": e.id,
            "pattern": e.pattern,
            "status": e.status,
            "n_cycles": e.n_cycles,
            "n_steps": e.n_steps,
            "note": e.note,
        }
        for e in teacher.memory.episodes()
        if e.id in kept
    ]
    return {
        "memory": str(teacher.memory.path),
        "episodes": episodes,
        "versions_written": [str(v) for v in teacher.versions[1:]],
        "running_model": teacher.model_path,
        "events": [
            {"step": e.step, "kind": e.kind, "text": e.text}
            for e in teacher.events
            if e.kind in _TEACHING_LINES
        ],
    }


def _source_length(source) -> int | None:
    """How many steps a source will deliver, when it knows (a scenario, a CSV stream)."""
    sensory = getattr(source, "sensory", None)  # an in-memory or CSV stream
    if sensory is None:
        scenario = getattr(source, "scenario", None)
        sensory = getattr(scenario, "sensory", None)
        if getattr(source, "loop", False):
            return None
    return None if sensory is None else len(sensory)
