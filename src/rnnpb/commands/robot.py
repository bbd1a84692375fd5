"""``rnnpb robot serve``: the simulated robot as a process of its own on a Zenoh bus."""

from __future__ import annotations

import argparse

NAME = "robot"
HELP = "run the simulated robot as a process of its own on a Zenoh bus"
DESCRIPTION = """\
rnnpb robot serve --bus zenoh [--key PREFIX]

Serve the simulated humanoid on a Zenoh bus (docs/bridge.md): it publishes its joint states on
PREFIX/joint_states and takes joint commands from PREFIX/joint_commands (JSON: joint names,
radians, a time stamp and a sequence number). `rnnpb interact --robot zenoh[:PREFIX]` drives it
from another process or another computer; a real robot's node speaks the same messages.

On the robot's side every command is checked before it is applied: malformed messages are
refused, commands older than one step dropped, joint limits and the servo's speed enforced,
and when commands stop for more than two steps the robot holds its pose. Each is counted in
the joint states it publishes.

Peers find each other by Zenoh's discovery on the local network; --listen ENDPOINT makes this
process listen at a fixed address (e.g. tcp/127.0.0.1:7447), and the loop then connects with
--robot zenoh:PREFIX@tcp/127.0.0.1:7447. Stop with Ctrl-C.

Examples:
  rnnpb robot serve --bus zenoh
  rnnpb robot serve --bus zenoh --key lab/arm --sim mujoco --listen tcp/0.0.0.0:7447
  rnnpb interact --source scenario:switch:1,2,3 --robot zenoh:lab/arm@tcp/127.0.0.1:7447 --out run/
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    sub = parser.add_subparsers(dest="action", metavar="ACTION", required=True)
    serve = sub.add_parser(
        "serve",
        help="serve the simulated robot on the bus",
        description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    serve.add_argument(
        "--bus", choices=("zenoh",), default="zenoh", help="the bus (default zenoh, the only one)"
    )
    serve.add_argument(
        "--key", default=None, metavar="PREFIX", help="key prefix (default rnnpb/robot)"
    )
    serve.add_argument(
        "--listen",
        action="append",
        default=[],
        metavar="ENDPOINT",
        help="also listen at this Zenoh endpoint, e.g. tcp/127.0.0.1:7447 (repeatable)",
    )
    serve.add_argument(
        "--connect",
        action="append",
        default=[],
        metavar="ENDPOINT",
        help="connect to this Zenoh endpoint (repeatable)",
    )
    serve.add_argument(
        "--sim",
        choices=("kinematic", "mujoco"),
        default="mujoco",
        help="the simulated robot (default mujoco: the humanoid with its physics)",
    )
    serve.add_argument(
        "--dt", type=float, default=0.4, help="seconds per network step (default 0.4)"
    )
    serve.add_argument(
        "--robot-map",
        metavar="FILE",
        help="speak for the simulated robot in this map's joint names and angles "
        "(default: the humanoid's own)",
    )


def run(args: argparse.Namespace) -> int:
    import os

    from rnnpb.bridge import DEFAULT_PREFIX, BusConfig, RobotServer
    from rnnpb.commands._checks import finite_seconds
    from rnnpb.commands._signals import terminate_as_interrupt

    finite_seconds("--dt", args.dt)
    robot_map = load_robot_map(args.robot_map)
    prefix = (args.key or DEFAULT_PREFIX).strip("/")
    if args.sim == "mujoco":
        os.environ.setdefault("MUJOCO_GL", "egl")
        from rnnpb.robot import MujocoRobot

        robot = MujocoRobot(dt=args.dt)
    else:
        from rnnpb.robot import KinematicRobot

        robot = KinematicRobot(dt=args.dt)
    bus = BusConfig(connect=tuple(args.connect), listen=tuple(args.listen))
    server = RobotServer(robot, prefix, dt=args.dt, robot_map=robot_map, bus=bus)
    where = ", ".join(bus.listen + bus.connect) or "Zenoh discovery"
    print(
        f"robot serving: {args.sim} humanoid on zenoh {prefix}/joint_states (states), "
        f"{prefix}/joint_commands (commands); {where}; dt {args.dt:g} s; Ctrl-C stops",
        flush=True,
    )
    if args.robot_map:
        print(robot_map.describe(), flush=True)
    try:
        with terminate_as_interrupt():  # `kill` stops it as Ctrl-C does: the counts print
            server.run()
    except KeyboardInterrupt:
        pass
    print(
        f"robot stopped: {server.applied} commands applied; refused "
        + ", ".join(f"{n} {why}" for why, n in server.refused.items())
        + f"; {server.safeguard.clipped} clipped, {server.safeguard.slowed} slowed",
        flush=True,
    )
    return 0


def load_robot_map(path: str | None):
    """The robot map a ``--robot-map`` names, or the simulated humanoid's."""
    from rnnpb.robot import RobotMap

    return RobotMap.humanoid() if path is None else RobotMap.load(path)


def open_robot(spec: str, dt: float, robot_map: str | None = None, waiting=None):
    """The robot ``--robot`` names: ``kinematic``, ``mujoco``, ``zenoh[:PREFIX][@ENDPOINT]``
    (a robot process speaking rnnpb's messages), ``ros2dds[:CONTROLLER][@ENDPOINT]`` (a ROS 2
    robot through zenoh-bridge-ros2dds) or ``rclpy[:CONTROLLER]`` (through ROS 2's rclpy);
    ``--robot-map FILE`` maps the joints of the last three."""
    from rnnpb.errors import ConfigError

    kind = spec.partition(":")[0].strip().lower()
    if kind == "zenoh":
        from rnnpb.bridge import DEFAULT_PREFIX, ZenohRobot, parse_bus_spec

        prefix, bus = parse_bus_spec(spec, DEFAULT_PREFIX, "--robot")
        return ZenohRobot(
            prefix, dt=dt, robot_map=load_robot_map(robot_map), bus=bus, waiting=waiting
        )
    if kind in ("ros2dds", "rclpy"):
        from rnnpb.bridge import DEFAULT_CONTROLLER, RclpyRobot, Ros2BridgeRobot

        controller, at, endpoint = spec.partition(":")[2].partition("@")
        controller = controller.strip().strip("/") or DEFAULT_CONTROLLER
        mapped = load_robot_map(robot_map)
        if kind == "rclpy":
            if at:
                raise ConfigError("--robot rclpy: ROS 2 finds its peers itself (no @ENDPOINT)")
            return RclpyRobot(controller, dt=dt, robot_map=mapped)
        from rnnpb.bridge import BusConfig

        bus = BusConfig(connect=(endpoint.strip(),) if endpoint.strip() else ())
        return Ros2BridgeRobot(controller, dt=dt, robot_map=mapped, bus=bus, waiting=waiting)
    if robot_map is not None:
        raise ConfigError(
            "--robot-map maps the joints of a robot on a bus (--robot zenoh, ros2dds or rclpy)"
        )
    if spec == "mujoco":
        import os

        os.environ.setdefault("MUJOCO_GL", "egl")
        from rnnpb.robot import MujocoRobot

        return MujocoRobot(dt=dt)
    if spec == "kinematic":
        from rnnpb.robot import KinematicRobot

        return KinematicRobot(dt=dt)
    raise ConfigError(
        f"--robot {spec!r}: expected kinematic, mujoco, zenoh[:PREFIX][@ENDPOINT], "
        "ros2dds[:CONTROLLER][@ENDPOINT] or rclpy[:CONTROLLER]"
    )
