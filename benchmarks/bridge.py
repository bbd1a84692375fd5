"""The robot bridge over loopback: what it adds to a step, whether a paced loop keeps its
deadlines, and the faults (docs/bridge.md).

``latency``  the interaction loop (the shipped model, the switching demonstrator) driving a
             robot process (``rnnpb robot serve``) over Zenoh on loopback and, in alternate
             blocks, the same robot in process: the median act section of each and the
             difference, the latency the bridge adds per step.
``paced``    the loop paced at ``--dt`` over the bridge for ``--steps`` steps: missed deadlines
             and the act section's median and p99.
``faults``   (1) the robot process killed mid-run and started again: after how many steps the
             loop says so, whether a recording row is lost, whether it resumes; (2) the loop
             (``rnnpb interact``) killed: how long until the robot holds its pose; (3) a flood
             of stale and malformed commands: how many applied, how many counted.

Run: ``.venv/bin/python benchmarks/bridge.py latency|paced|faults [--steps N] [--dt S]
[--sim kinematic|mujoco]``.
"""

from __future__ import annotations

import argparse
import json
import os
import secrets
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import replace
from pathlib import Path

import numpy as np


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


class RobotProcess:
    def __init__(self, dt: float, sim: str, prefix: str | None = None, endpoint: str | None = None):
        self.dt, self.sim = dt, sim
        self.prefix = prefix or f"bench/{secrets.token_hex(4)}"
        self.endpoint = endpoint or f"tcp/127.0.0.1:{free_port()}"
        self.process: subprocess.Popen | None = None

    def start(self) -> RobotProcess:
        command = [sys.executable, "-m", "rnnpb.cli", "robot", "serve", "--sim", self.sim,
                   "--key", self.prefix, "--listen", self.endpoint,
                   "--dt", str(self.dt)]  # fmt: skip
        self.process = subprocess.Popen(
            command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True
        )
        assert self.process.stdout is not None
        line = self.process.stdout.readline()
        assert line.startswith("robot serving"), line
        return self

    def kill(self) -> None:
        if self.process is not None and self.process.poll() is None:
            self.process.kill()
            self.process.wait()

    def robot(self, **kwargs):
        from rnnpb.bridge import BusConfig, ZenohRobot

        return ZenohRobot(
            self.prefix, dt=self.dt, bus=BusConfig(connect=(self.endpoint,)), **kwargs
        )


def _mirror():
    from rnnpb.model import MirrorSystem, OnlineConfig, TrainedModel
    from rnnpb.models import SHIPPED_MODEL

    model = TrainedModel.load(SHIPPED_MODEL)
    return MirrorSystem(model, OnlineConfig.for_model(model).config)


def _source():
    from rnnpb.demonstrator import ScenarioSource, switch_scenario

    return ScenarioSource(switch_scenario(("1", "2", "3"), seed=0), loop=True)


def latency(args: argparse.Namespace) -> None:
    from rnnpb.interaction import InteractionLoop, LoopConfig
    from rnnpb.robot import KinematicRobot, MujocoRobot

    process = RobotProcess(0.4, args.sim).start()
    local_robot = KinematicRobot(dt=0.4) if args.sim == "kinematic" else MujocoRobot(dt=0.4)
    acts: dict[str, list[float]] = {"bridge": [], "in process": []}
    try:
        with _source() as s1, _source() as s2, process.robot() as bridged, local_robot as local:
            loops = {
                "bridge": InteractionLoop(_mirror(), s1, bridged, config=LoopConfig(0.4)),
                "in process": InteractionLoop(_mirror(), s2, local, config=LoopConfig(0.4)),
            }
            for loop in loops.values():  # compile
                loop.config = replace(loop.config, max_steps=5)
                loop.run()
            block = 100
            for _ in range(max(1, args.steps // block)):
                for name, loop in loops.items():
                    loop.config = replace(loop.config, max_steps=loop.steps + block)
                    loop.run(on_step=lambda r, name=name: acts[name].append(r.timings["act"]))
    finally:
        process.kill()
    medians = {name: float(np.median(v)) * 1e3 for name, v in acts.items()}
    for name, values in acts.items():
        v = np.asarray(values) * 1e3
        print(
            f"act section, {name} ({args.sim} robot): median {np.median(v):.3f} ms, "
            f"p99 {np.percentile(v, 99):.3f} ms over {len(v)} steps"
        )
    added = medians["bridge"] - medians["in process"]
    print(f"added latency per step over loopback: median {added:.3f} ms (target <= 2 ms)")


def paced(args: argparse.Namespace) -> None:
    from rnnpb.interaction import InteractionLoop, LoopConfig

    process = RobotProcess(args.dt, args.sim).start()
    events: list[str] = []
    try:
        with _source() as source, process.robot(on_event=events.append) as robot:
            loop = InteractionLoop(_mirror(), source, robot, config=LoopConfig(args.dt, paced=True))
            loop.config = replace(loop.config, max_steps=5, paced=False)
            loop.run()  # compile, unpaced
            loop.missed_deadlines = 0
            loop.config = replace(loop.config, max_steps=5 + args.steps, paced=True)
            started = time.monotonic()
            summary = loop.run()
    finally:
        process.kill()
    act = summary.section_ms["act"]
    print(
        f"paced at dt {args.dt:g} s over the bridge ({args.sim} robot): {summary.steps - 5} steps "
        f"in {time.monotonic() - started:.0f} s, missed deadlines {summary.missed_deadlines}; "
        f"act median {act['median']:.3f} ms, p99 {act['p99']:.3f} ms, max {act['max']:.3f} ms; "
        f"robot silent {robot.outages} times, {robot.unanswered} commands refused"
    )
    for text in events[:5]:
        print(f"  {text}")


def faults(args: argparse.Namespace) -> None:
    _robot_killed(args.dt, args.sim)
    _loop_killed(args.dt, args.sim)
    _flood(args.dt, args.sim)


def _robot_killed(dt: float, sim: str) -> None:
    from rnnpb.interaction import InteractionLoop, LoopConfig, SessionRecorder, read_session

    process = RobotProcess(dt, sim).start()
    again = RobotProcess(dt, sim, process.prefix, process.endpoint)
    marks: dict[str, float] = {}
    events: list[tuple[float, int, str]] = []
    steps = [0]

    def on_step(record) -> None:
        steps[0] = record.step + 1
        if record.step == 9:
            process.kill()
            marks["killed"] = time.monotonic()
            threading.Timer(3.0, again.start).start()

    with tempfile.TemporaryDirectory() as folder:
        csv = Path(folder) / "s.csv"
        robot = process.robot(on_event=lambda t: events.append((time.monotonic(), steps[0], t)))
        try:
            with _source() as source, robot, SessionRecorder(csv, 4) as recorder:
                loop = InteractionLoop(
                    _mirror(), source, robot, recorder, LoopConfig(dt, paced=True, max_steps=30)
                )
                loop.run(on_step=on_step)
        finally:
            process.kill()
            again.kill()
        rows = read_session(csv)["step"]
    said = (events[0][0] - marks["killed"]) / dt
    print(
        f"robot killed at step 10 (dt {dt:g} s): the loop said so {said:.2f} steps later "
        f"({events[0][2]!r}); back: {events[1][2]!r}; recording rows {len(rows)} of 30, "
        f"contiguous {bool(np.array_equal(rows, np.arange(30)))}"
    )


def _loop_killed(dt: float, sim: str) -> None:
    from rnnpb.bridge import decode_state

    process = RobotProcess(dt, sim).start()
    states: list[tuple[float, object]] = []
    from rnnpb.bridge import BusConfig

    session = BusConfig(connect=(process.endpoint,)).open()
    session.declare_subscriber(
        f"{process.prefix}/joint_states",
        lambda s: states.append((time.monotonic(), decode_state(bytes(s.payload.to_bytes())))),
    )
    with tempfile.TemporaryDirectory() as folder:
        loop = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "rnnpb.cli",
                "interact",
                "--source",
                "scenario:switch:1,2,3",
                "--robot",
                f"zenoh:{process.prefix}@{process.endpoint}",
                "--paced",
                "--dt",
                str(dt),
                "--no-progress",
                "--out",
                folder,
            ],  # fmt: skip
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            env={**os.environ, "MUJOCO_GL": "egl"},
        )
        try:
            while not any(s.ack and s.ack >= 10 for _, s in states):
                time.sleep(0.01)
            loop.send_signal(signal.SIGKILL)
            killed = time.monotonic()
            loop.wait()
            final = max(s.ack for _, s in states if s.ack is not None)
            last_ack = min(t for t, s in states if s.ack == final)
            while not any(s.holding for _, s in states):
                time.sleep(0.01)
            held = min(t for t, s in states if s.holding)
        finally:
            session.close()
            process.kill()
    print(
        f"loop killed (dt {dt:g} s): the robot held its pose {(held - killed) / dt:.2f} steps "
        f"after the kill, {(held - last_ack) / dt:.2f} steps after the last command"
    )


def _flood(dt: float, sim: str) -> None:
    from rnnpb.bridge import BusConfig, JointCommand, decode_state, encode_command
    from rnnpb.vectors import MOTOR_NAMES

    process = RobotProcess(dt, sim).start()
    states = []
    session = BusConfig(connect=(process.endpoint,)).open()
    try:
        session.declare_subscriber(
            f"{process.prefix}/joint_states",
            lambda s: states.append(decode_state(bytes(s.payload.to_bytes()))),
        )
        publisher = session.declare_publisher(f"{process.prefix}/joint_commands")
        while not states:
            time.sleep(0.01)
        position = np.full(8, 0.2)
        publisher.put(encode_command(JointCommand(1, time.time(), MOTOR_NAMES, position, "b")))
        while states[-1].ack != 1:
            time.sleep(0.01)
        before = states[-1].position.copy()
        n = 5000
        good = {"seq": 2, "stamp": 0.0, "names": list(MOTOR_NAMES), "position": [0.9] * 8}
        for i in range(n):
            publisher.put(
                encode_command(
                    JointCommand(2 + i, time.time() - 10 * dt, MOTOR_NAMES, np.full(8, 0.9), "b")
                )  # fmt: skip
            )
            publisher.put(json.dumps({**good, "position": [0.9] * 7}).encode())
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            refused = states[-1].refused
            if sum(refused.values()) >= 2 * n:
                break
            time.sleep(0.05)
        last = states[-1]
    finally:
        session.close()
        process.kill()
    print(
        f"flood of {n} stale and {n} malformed commands: applied "
        f"{0 if last.ack == 1 else 'some'}, pose unchanged "
        f"{bool(np.array_equal(last.position, before))}, counted {last.refused}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", choices=("latency", "paced", "faults"))
    parser.add_argument("--steps", type=int, default=1000, help="steps measured (default 1000)")
    parser.add_argument("--dt", type=float, default=0.4, help="seconds per step (default 0.4)")
    parser.add_argument("--sim", choices=("kinematic", "mujoco"), default="kinematic")
    args = parser.parse_args()
    import platform

    import rnnpb

    rnnpb.configure_xla()  # as the command line does, before the first JAX computation

    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores")
    {"latency": latency, "paced": paced, "faults": faults}[args.what](args)


if __name__ == "__main__":
    main()
