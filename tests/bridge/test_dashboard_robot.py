"""`rnnpb serve --robot`: the dashboard's loop drives a robot process on the bus too."""

from __future__ import annotations

import json
import queue
import time

import numpy as np

from rnnpb.bridge import ZenohRobot
from rnnpb.cli import main
from rnnpb.web import find_models
from rnnpb.web._session import Session

from ._robot_process import RobotProcess

DT = 0.05


def test_the_dashboards_steps_reach_the_robot_on_the_bus(set1_model_dir, tmp_path):
    process = RobotProcess(dt=DT).start()
    robot = ZenohRobot(process.prefix, dt=DT, bus=process.bus())
    session = Session(find_models(set1_model_dir), dt=DT, workdir=tmp_path / "sessions")
    steps: queue.Queue[dict] = queue.Queue()
    try:
        robot.connect()
        session.robot = robot
        session.subscribe(
            lambda text: steps.put(m) if (m := json.loads(text))["type"] == "step" else None
        )
        session.start()
        deadline = time.monotonic() + 90
        while session.mirror is None or session.loading:
            assert time.monotonic() < deadline, "the model did not load within 90 s"
            time.sleep(0.05)
        session.submit({"type": "control", "action": "start"})
        last = steps.get(timeout=30)
        while last["step"] < 10:
            last = steps.get(timeout=5)
        session.submit({"type": "control", "action": "stop"})
        time.sleep(0.2)
        assert robot.commands_sent >= 11 and robot.outages == 0 and robot.unanswered == 0
        while not steps.empty():
            last = steps.get()
        # What the page shows is what the robot on the bus was sent, and where it is.
        np.testing.assert_allclose(robot.observe(), last["motor"], atol=1e-3)
    finally:
        session.close()
        robot.disconnect()
        process.kill()


def test_serve_drives_only_a_robot_on_a_bus(capsys):
    assert main(["serve", "--port", "0", "--robot", "mujoco"]) == 2
    err = capsys.readouterr().err
    assert "the page shows the simulated humanoid itself; name a robot on a bus" in err
    assert main(["serve", "--port", "0", "--robot-map", "arm.toml"]) == 2
    assert "--robot-map maps the joints of a --robot" in capsys.readouterr().err
