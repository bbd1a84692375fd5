"""The interaction loop driving a robot process over the bridge: the same session as in
process, and a robot that dies and comes back mid-run."""

from __future__ import annotations

import shutil
import threading

import numpy as np
import pytest

from rnnpb.bridge import ZenohRobot
from rnnpb.cli import main
from rnnpb.demonstrator import ScenarioSource, switch_scenario
from rnnpb.interaction import InteractionLoop, LoopConfig, SessionRecorder, read_session
from rnnpb.model import MirrorSystem
from rnnpb.vectors import MOTOR_NAMES

from ._robot_process import RobotProcess


@pytest.fixture(scope="module")
def model_path(set1_model_dir, tmp_path_factory):
    path = tmp_path_factory.mktemp("model") / "set1.npz"
    shutil.copy(set1_model_dir / "set1.npz", path)
    return path


def _interact(model_path, out, robot: str) -> dict:
    argv = ["interact", "--model", str(model_path), "--source", "scenario:switch:1,2,3"]
    assert main([*argv, "--out", str(out), "--robot", robot, "--no-progress"]) == 0
    return read_session(out / "session.csv")


@pytest.mark.slow  # two runs of `rnnpb interact`, 150 steps each (about 8 s)
def test_switching_gives_the_same_session_over_the_bridge_as_in_process(model_path, tmp_path):
    process = RobotProcess(dt=0.4).start()
    try:
        bridged = _interact(model_path, tmp_path / "bridge", process.spec())
    finally:
        process.kill()
    local = _interact(model_path, tmp_path / "local", "kinematic")
    assert len(bridged["step"]) == len(local["step"]) == 150
    for column in ("recognised", "novelty", *MOTOR_NAMES, "pb0", "pb3"):
        np.testing.assert_array_equal(bridged[column], local[column], err_msg=column)
    assert len(set(local["recognised"][-10:])) == 1  # it did follow the switches


def test_the_loop_waits_for_a_killed_robot_and_loses_no_row(set1_model, tmp_path):
    dt = 0.1
    process = RobotProcess(dt=dt).start()
    restarted = RobotProcess(dt=dt)
    restarted.prefix, restarted.endpoint = process.prefix, process.endpoint
    events: list[tuple[int, str]] = []
    loop_steps = [0]

    def kill_at_step_20(record) -> None:
        loop_steps[0] = record.step + 1
        if record.step == 19:
            process.kill()
            threading.Timer(0.6, restarted.start).start()

    source = ScenarioSource(switch_scenario(("1", "2"), seed=0))
    robot = ZenohRobot(
        process.prefix,
        dt=dt,
        bus=process.bus(),
        on_event=lambda text: events.append((loop_steps[0], text)),
    )
    try:
        with source, robot, SessionRecorder(tmp_path / "s.csv", 4) as recorder:
            loop = InteractionLoop(
                MirrorSystem(set1_model), source, robot, recorder, LoopConfig(dt=dt, max_steps=40)
            )
            loop.run(on_step=kill_at_step_20)
    finally:
        process.kill()
        restarted.kill()
    # Said at the first step after the kill, and again when the robot was back.
    assert [step for step, _ in events] == [20, 20]
    assert "no joint states" in events[0][1] and "back after" in events[1][1]
    session = read_session(tmp_path / "s.csv")
    np.testing.assert_array_equal(session["step"], np.arange(40))
    assert robot.outages == 1
