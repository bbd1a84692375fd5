"""Replay in rerun, and the session video an interrupted run leaves."""

import csv
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from rnnpb.cli import main
from rnnpb.interaction.recorder import session_columns
from rnnpb.models import SHIPPED_MODEL


def _write_session(path: Path, n: int = 12) -> None:
    rng = np.random.default_rng(0)
    columns = session_columns(4)
    with open(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(columns)
        for step in range(n):
            row = {name: f"{rng.uniform(0.2, 0.8):.4f}" for name in columns}
            row.update(
                step=step,
                time_s=f"{0.4 * step:.2f}",
                held=0,
                lost_left=0,
                lost_right=int(step == 3),
                truth_pattern="1" if step < 6 else "2",
            )
            row["rhy"] = row["rhz"] = "" if step == 3 else row["rhy"]
            writer.writerow([row[name] for name in columns])


def test_view_saves_a_recording_with_every_part_on_one_timeline(tmp_path, capsys):
    pytest.importorskip("rerun")
    rerun_cli = Path(sys.executable).with_name("rerun")
    if not rerun_cli.exists():
        pytest.skip("the rerun command is not installed next to this Python")
    session = tmp_path / "run"
    session.mkdir()
    _write_session(session / "session.csv")
    rrd = tmp_path / "replay.rrd"
    assert main(["view", str(session), "--save", str(rrd)]) == 0
    assert "12 steps" in capsys.readouterr().out
    verified = subprocess.run(
        [str(rerun_cli), "rrd", "verify", str(rrd)], capture_output=True, text=True, timeout=120
    )
    assert verified.returncode == 0, verified.stderr
    printed = subprocess.run(
        [str(rerun_cli), "rrd", "print", "-vv", str(rrd)],
        capture_output=True,
        text=True,
        timeout=120,
    ).stdout
    for entity in (
        "/hands/observed",
        "/hands/predicted",
        "/robot/arms",
        "/joints/lshp",
        "/pb/pb3",
        "/errors/prediction_error",
        "/status/truth_pattern",
    ):
        assert entity in printed, entity
    assert "index_name: step" in printed and "index_name: time" in printed


def test_view_of_an_empty_recording_is_one_line(tmp_path, capsys):
    path = tmp_path / "session.csv"
    _write_session(path, n=0)
    assert main(["view", str(path), "--save", str(tmp_path / "x.rrd")]) == 2
    assert "has no steps" in capsys.readouterr().err


def test_arm_strips_run_from_the_shoulders_through_the_elbows_to_the_hands():
    from rnnpb.commands.view import arm_strips
    from rnnpb.robot import SHOULDERS, forward_kinematics

    joints = np.array([1.0, 0.7, 0.0, 1.2, 1.0, 0.7, 0.0, 1.2])
    strips = arm_strips(joints)
    hands, elbows = forward_kinematics(joints)
    assert strips.shape == (3, 3, 3)
    np.testing.assert_allclose(strips[:2, 0], SHOULDERS)
    np.testing.assert_allclose(strips[:2, 1], elbows)
    np.testing.assert_allclose(strips[:2, 2], hands)


def test_a_new_video_removes_the_partial_a_killed_run_left(tmp_path):
    from rnnpb.interaction.render import SessionVideo, partial_video_path

    path = tmp_path / "session.mp4"
    partial = partial_video_path(path)
    partial.write_bytes(b"\x00\x00\x00\x18ftypmp42")  # an MP4 cut off before its index
    with SessionVideo(path, fps=5.0):
        assert not partial.exists()
    assert not path.exists()  # no frame: no video


@pytest.mark.slow
def test_sigterm_during_a_rendered_run_leaves_a_playable_video(tmp_path):
    from dataclasses import replace

    from rnnpb.model import TrainedModel

    out = tmp_path / "run"
    # paced at 0.05 s a step: a model learned, as far as its file says, at that step
    shipped = TrainedModel.load(SHIPPED_MODEL)
    fast_model = tmp_path / "fast.npz"
    replace(shipped, meta={**shipped.meta, "dt": 0.05}).save(fast_model)
    env = {
        **os.environ,
        "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl"),
        "PYTHONPATH": os.pathsep.join(sys.path),
    }
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "rnnpb.cli",
            "interact",
            "--model",
            str(fast_model),
            "--source",
            "scenario:held:1",
            "--out",
            str(out),
            "--render",
            "--paced",
            "--dt",
            "0.05",
            "--steps",
            "2000",
            "--no-progress",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=env,
    )
    session = out / "session.csv"
    deadline = time.monotonic() + 240
    while time.monotonic() < deadline and process.poll() is None:
        if session.exists() and session.read_text().count("\n") > 8:
            break
        time.sleep(0.2)
    assert process.poll() is None, process.stderr.read().decode()
    process.send_signal(signal.SIGTERM)
    stdout, stderr = process.communicate(timeout=120)
    assert b"Traceback" not in stderr, stderr.decode()
    assert b"interrupted" in stdout
    video = cv2.VideoCapture(str(out / "session.mp4"))
    frames = int(video.get(cv2.CAP_PROP_FRAME_COUNT))
    ok, _ = video.read()
    video.release()
    assert ok and frames >= 8
    assert not any(p.name.startswith(".") for p in out.iterdir())
    assert (out / "summary.json").exists()
