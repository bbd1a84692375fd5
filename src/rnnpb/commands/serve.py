"""``rnnpb serve``: the live dashboard in the browser."""

from __future__ import annotations

import argparse

from rnnpb.commands._config import RUN_SECTIONS, add_config_argument
from rnnpb.commands._perception import add_perception_argument
from rnnpb.commands._signals import terminate_as_interrupt

NAME = "serve"
HELP = "open the live dashboard: watch the robot imitate the demonstrator, your mouse or webcam"
DESCRIPTION = """\
Start a local web page that shows the simulated humanoid in 3-D, driven live by the synthetic
demonstrator (patterns 1-4, switch, pause), by you dragging two hand markers with the mouse or
a touch screen, or by the webcam (coloured balls on the hands, or bare hands with
--perception pose; the webcam tab can switch). Live plots show the perceived
and predicted hands, the joint angles and the parametric bias moving towards the learned
pattern it recognises. The session can be downloaded as CSV.

Serves on 127.0.0.1 (this computer only) unless --host says otherwise. All tabs share one
session. Stop with Ctrl-C.

The server answers only requests addressed to 127.0.0.1, localhost, [::1] or the --host
address, and its WebSocket only accepts its own page, so that other web sites open in your
browser can neither drive the robot nor see the camera. To reach it from other machines
under a name, list the name with --allow-host (the page served under it is then its own);
a page at another origin (a proxy) needs --allow-origin.

--config FILE overrides the learning preset's [online], [recognition],
[recognition_untaught], [teaching.cutter], [teaching] and [consolidation] values for
research, for every model the page chooses (docs/model.md, "Settings").

Without --model: the models in ./models/, else in ./results/demo/models/ (what `make demo`
writes), else the small model shipped with rnnpb (learning set 1 — patterns 1, 2, 3 —
learned with the fast preset).

Examples:
  rnnpb serve
  rnnpb serve --model models/set1.npz
  rnnpb serve --model models/ --port 9000
  rnnpb serve --perception pose          # bare hands on the webcam: pip install 'rnnpb[hands]'
  rnnpb serve --model models/ --host 192.168.1.20   # reachable as http://192.168.1.20:8765
  rnnpb serve --model models/ --host 0.0.0.0 --allow-host robot.lab
  rnnpb serve --model models/ --host 0.0.0.0 --allow-host robot.lab \\
      --allow-origin https://robot.lab                # behind an HTTPS proxy
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--model",
        metavar="MODEL_OR_DIR",
        help="a trained model (.npz) or a folder searched for *.npz "
        "(default: ./models/, ./results/demo/models/, else the model "
        "shipped with rnnpb)",
    )
    parser.add_argument(
        "--host",
        default="127.0.0.1",
        help="address to listen on (default 127.0.0.1: this computer only)",
    )
    parser.add_argument("--port", type=int, default=8765, help="port (default 8765; 0: any free)")
    parser.add_argument(
        "--dt",
        type=float,
        help="seconds per network step (default: the models', the step they were learned at; "
        "another is refused)",
    )
    parser.add_argument(
        "--allow-host",
        action="append",
        default=[],
        metavar="NAME",
        help="also answer requests addressed to this host name or IP address "
        "(repeatable; 127.0.0.1, localhost, [::1] and --host always are)",
    )
    parser.add_argument(
        "--allow-origin",
        action="append",
        default=[],
        metavar="ORIGIN",
        help="also accept the WebSocket of pages from this origin, "
        "scheme://host[:port] (repeatable; the server's own page "
        "always is)",
    )
    parser.add_argument(
        "--no-safety",
        action="store_true",
        help="no command filter and no PB guard (docs/safety.md; by default "
        "the filter checks every command, and a model's safety map beside it "
        "guards its PB)",
    )
    parser.add_argument(
        "--teach",
        choices=("confirm", "auto", "off"),
        default="confirm",
        help="teaching by showing (docs/dashboard.md): keep new movements and learn them "
        "when you press Confirm (default), automatically, or keep nothing; the page can "
        "change it",
    )
    parser.add_argument(
        "--consolidation-iterations",
        type=int,
        metavar="N",
        help="learning iterations of each consolidation (default: 30,000 for the paper's "
        "learning, 1,000 for the fast preset's)",
    )
    parser.add_argument(
        "--teach-dir",
        metavar="DIR",
        help="where a shipped model is copied to learn from, with its memory and new "
        "versions (default: a temporary folder deleted when the server stops)",
    )
    parser.add_argument(
        "--robot",
        metavar="ROBOT",
        help="also drive a robot on a bus: zenoh[:PREFIX][@ENDPOINT], "
        "ros2dds[:CONTROLLER][@ENDPOINT] or rclpy[:CONTROLLER] (docs/bridge.md; default: the "
        "page's simulated humanoid only)",
    )
    parser.add_argument(
        "--robot-map",
        metavar="FILE",
        help="with --robot: the robot's joint names, signs, offsets and limits (TOML)",
    )
    parser.add_argument(
        "--routines",
        action="append",
        default=[],
        metavar="FILE",
        help="a routine file (`rnnpb train-routines`; repeatable): over the model it was "
        "learned for, the page says the routine it recognises and the movement it expects "
        "next (docs/routines.md)",
    )
    add_config_argument(parser, RUN_SECTIONS)
    add_perception_argument(parser)
    parser.add_argument(
        "--log-level",
        default="warning",
        choices=("debug", "info", "warning", "error"),
        help="server log detail (default warning)",
    )


def run(args: argparse.Namespace) -> int:
    import logging

    from rnnpb.errors import ConfigError

    if not 0 <= args.port <= 65535:
        raise ConfigError(f"--port must be in [0, 65535], got {args.port}")
    # Before the dashboard's imports and the first model's compilation (seconds): a port in
    # use is one line, at once.
    _check_port_free(args.host, args.port)
    from rnnpb.web import MAX_DT, MIN_DT, AccessPolicy, find_models

    if args.dt is not None and not MIN_DT <= args.dt <= MAX_DT:
        raise ConfigError(f"--dt must be in [{MIN_DT}, {MAX_DT}] seconds, got {args.dt}")
    # Checked before anything starts, so a mistyped name is one clear error line.
    access = AccessPolicy.for_address(args.host, args.allow_host, args.allow_origin)
    logging.basicConfig(level=args.log_level.upper(), format="%(levelname)s %(name)s: %(message)s")
    from pathlib import Path

    from rnnpb.commands._checks import step_count
    from rnnpb.commands._config import read_config
    from rnnpb.models import default_model
    from rnnpb.web import TeachingSettings

    step_count("--consolidation-iterations", args.consolidation_iterations)
    if args.perception == "pose":  # one error line now, not when the webcam tab opens
        from rnnpb.perception import load_pose_model

        load_pose_model().close()
    overrides = read_config(args.config, RUN_SECTIONS, NAME)
    teaching = TeachingSettings(
        mode=args.teach,
        iterations=args.consolidation_iterations,
        folder=Path(args.teach_dir) if args.teach_dir else None,
    )
    models = find_models(args.model if args.model is not None else default_model())
    args.dt = _models_dt(models, args.dt)
    _check_routines(args.routines, models)
    # SIGTERM ends the serve as Ctrl-C does from here on, even while the banner prints, so the
    # robot is let go and the working folder removed.
    with terminate_as_interrupt():
        return _serve(args, models, access, teaching, overrides)


def _check_routines(paths: list[str], models: dict) -> None:
    """Each ``--routines`` file read, and learned over one of the offered models: one error
    line now rather than a routine level that never shows."""
    if not paths:
        return
    from rnnpb.errors import ConfigError
    from rnnpb.model import TrainedModel
    from rnnpb.model.routines import RoutineModel

    fingerprints = {TrainedModel.load(path).fingerprint for path in models.values()}
    for path in paths:
        routines = RoutineModel.load(path)
        if routines.lower_fingerprint not in fingerprints:
            raise ConfigError(
                f"{path}: these routines were learned over none of the models offered "
                f"({', '.join(models)}); give --model the model they were learned over"
            )


def _serve(args: argparse.Namespace, models: dict, access, teaching, overrides) -> int:
    """Connect the robot, start the dashboard and wait; let both go however it ends."""
    from pathlib import Path

    from rnnpb.web import DashboardServer

    robot = _connect_robot(args)
    server = None
    try:
        server = DashboardServer(
            models,
            host=args.host,
            port=args.port,
            dt=args.dt,
            log_level=args.log_level,
            allow_hosts=access.hosts,
            allow_origins=access.origins,
            teaching=teaching,
        )
        server.session.safety_enabled = not args.no_safety  # read when a model loads
        server.session.perception = args.perception  # read when the webcam tab opens
        if overrides is not None:  # read when a model loads, and by teaching
            server.session.overrides = overrides
        server.session.robot = robot  # read when a run starts
        # Read when a step is published (the routine level of the running model version).
        server.session.routine_files = [Path(p) for p in args.routines]
        server.start()
        print(
            f"rnnpb dashboard: {server.url}  (models: {', '.join(models)}; Ctrl-C to stop)",
            flush=True,
        )
        print(
            f"answering for: {', '.join(access.allowed_hosts)}"
            + (f"; pages from: {', '.join(access.origins)}" if access.origins else ""),
            flush=True,
        )
        _print_safety(models, args.no_safety)
        if overrides is not None:
            print(f"values from {overrides.origin} over the learning preset's", flush=True)
        server.wait()
    finally:
        if robot is not None:
            robot.disconnect()  # first: a loop waiting for a lost robot stops waiting
        if server is not None:
            server.stop()
    return 0


def _models_dt(models: dict, given: float | None) -> float:
    """The step time the models were learned at (all must agree); ``given`` must be it."""
    from rnnpb.commands._checks import played_dt
    from rnnpb.errors import ConfigError
    from rnnpb.model import TrainedModel

    steps = {name: TrainedModel.load(path).dt for name, path in models.items()}
    if not steps:
        from rnnpb.model.io import DEFAULT_DT

        return DEFAULT_DT if given is None else given
    if len(set(steps.values())) > 1:
        shown = ", ".join(f"{name} {dt:g} s" for name, dt in steps.items())
        raise ConfigError(
            f"the models were learned at different step times ({shown}); a page plays at one: "
            "serve the models of one step time (--model FILE or a folder of them)"
        )
    name, learned = next(iter(steps.items()))
    return played_dt(models[name], learned, given)


def _connect_robot(args: argparse.Namespace):
    """The robot ``--robot`` names, connected; None without --robot."""
    if args.robot is None:
        if args.robot_map is not None:
            from rnnpb.errors import ConfigError

            raise ConfigError("--robot-map maps the joints of a --robot")
        return None
    from rnnpb.commands.robot import open_robot
    from rnnpb.errors import ConfigError

    if args.robot.partition(":")[0].strip().lower() not in ("zenoh", "ros2dds", "rclpy"):
        raise ConfigError(
            f"--robot {args.robot!r}: the page shows the simulated humanoid itself; name a robot "
            "on a bus: zenoh[:PREFIX][@ENDPOINT], ros2dds[:CONTROLLER][@ENDPOINT] or rclpy"
        )
    robot = open_robot(args.robot, args.dt, args.robot_map)
    robot.connect()
    print(f"driving the robot on {args.robot} too (docs/bridge.md)", flush=True)
    return robot


def _check_port_free(host: str, port: int) -> None:
    """Raise ConfigError if nothing can listen on ``host:port`` (in use, or not this
    machine's address). Binds as uvicorn will (SO_REUSEADDR), then lets go at once."""
    import errno
    import socket

    from rnnpb.errors import ConfigError

    if port == 0:
        return
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)
    except socket.gaierror as error:
        raise ConfigError(f"--host {host}: {error.strerror}") from None
    family, kind, proto, _, address = infos[0]
    with socket.socket(family, kind, proto) as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            probe.bind(address)
        except OSError as error:
            reason = error.strerror or str(error)
            if error.errno == errno.EADDRINUSE:
                reason = (
                    "the port is in use (another `rnnpb serve`?); choose another with "
                    "--port, or --port 0 for any free one"
                )
            raise ConfigError(f"cannot serve on {host}:{port}: {reason}") from None


def _print_safety(models: dict, off: bool) -> None:
    """Say once what guards the robot (docs/safety.md)."""
    from rnnpb.safety import safety_map_path

    if off:
        print("safety: off (--no-safety): no command filter, no PB guard", flush=True)
        return
    mapped = [name for name, path in models.items() if safety_map_path(path).exists()]
    print(
        "safety: the command filter checks every command; "
        + (
            f"safety maps guard the PB of {', '.join(mapped)}"
            if mapped
            else "no model has a safety map (`rnnpb safety learn`), so the filter alone guards"
        ),
        flush=True,
    )
