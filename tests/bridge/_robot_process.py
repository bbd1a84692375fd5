"""A robot process on loopback for the bridge tests: `rnnpb robot serve` in a subprocess."""

from __future__ import annotations

import os
import secrets
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


class RobotProcess:
    """``rnnpb robot serve --sim kinematic`` listening on a loopback port of its own."""

    def __init__(self, dt: float = 0.1, robot_map: Path | None = None) -> None:
        self.prefix = f"test/{secrets.token_hex(4)}"
        self.endpoint = f"tcp/127.0.0.1:{free_port()}"
        self.dt = dt
        self.robot_map = robot_map
        self.process: subprocess.Popen[str] | None = None

    def start(self) -> RobotProcess:
        command = [
            sys.executable, "-m", "rnnpb.cli", "robot", "serve", "--sim", "kinematic",
            "--key", self.prefix, "--listen", self.endpoint, "--dt", str(self.dt),
        ]  # fmt: skip
        if self.robot_map is not None:
            command += ["--robot-map", str(self.robot_map)]
        # A child inherits an ignored SIGINT (a suite started in the background by a script
        # runs so), and Ctrl-C would then not stop the robot: give it the default (signals
        # are the main thread's to set).
        main = threading.current_thread() is threading.main_thread()
        previous = signal.signal(signal.SIGINT, signal.default_int_handler) if main else None
        try:
            self.process = subprocess.Popen(
                command,
                stdout=subprocess.PIPE,
                stderr=subprocess.STDOUT,
                text=True,
                env={**os.environ, "RNNPB_XLA_DEFAULTS": "0"},
            )
        finally:
            if main:
                signal.signal(signal.SIGINT, previous)
        assert self.process.stdout is not None
        line = self.process.stdout.readline()
        assert line.startswith("robot serving"), line
        return self

    def kill(self) -> None:
        if self.process is None:
            return
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait(timeout=10)
        if self.process.stdout is not None:
            self.process.stdout.close()

    def stop(self) -> str:
        """Ctrl-C the robot; its last words."""
        assert self.process is not None
        self.process.send_signal(signal.SIGINT)
        output, _ = self.process.communicate(timeout=10)
        return output

    def bus(self):
        from rnnpb.bridge import BusConfig

        return BusConfig(connect=(self.endpoint,))

    def spec(self) -> str:
        return f"zenoh:{self.prefix}@{self.endpoint}"


def wait_until(condition, timeout_s: float = 20.0) -> bool:
    """Whether ``condition()`` comes true within ``timeout_s``: a bound for a busy machine
    (a robot process starved of the cores for seconds), not a measure of speed."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.01)
    return condition()


REST = np.zeros(8)
"""Where the kinematic robot starts."""
