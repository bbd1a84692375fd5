"""`rnnpb record bvh:…`: motion capture to sequence CSVs and recording.json."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rnnpb.cli import main
from rnnpb.demonstrator import MirrorMapping
from rnnpb.robot.camera import RobotCamera
from rnnpb.sequences import read_sequence_files

from .bvh_files import demonstrator_hands, write_bvh

FPS = 30


def _take(folder, name, period, seconds, **variant):
    times = np.arange(round(seconds * FPS) + 1) / FPS
    return write_bvh(folder / name, demonstrator_hands("1", times, period), 1 / FPS, **variant)


def test_a_capture_becomes_sequences_of_what_the_camera_sees_and_the_robot_does(tmp_path, capsys):
    first = _take(tmp_path, "a.bvh", period=2.4, seconds=12)
    second = _take(tmp_path, "b.bvh", period=2.4, seconds=12, naming="lower", unit="m", up="z")
    out = tmp_path / "data"
    code = main(
        ["record", f"bvh:{first},{second}", "--pattern", "swing", "--out", str(out)]
        + ["--cut", "length", "--length", "20"]
    )
    assert code == 0
    printed = capsys.readouterr().out
    assert "arm 0.620 m" in printed and "cm, y up" in printed
    sequences = read_sequence_files([str(out)])
    assert [s.pattern for s in sequences] == ["swing"] * 2
    steps = np.arange(20) * 0.4
    truth = demonstrator_hands("1", steps, 2.4)
    # a 0.4 s average of a 2.4 s swing keeps 95 % of it: the camera sees the same swing (the
    # first step is averaged with the held first frame)
    seen = RobotCamera().sensory_from_hands(truth)
    np.testing.assert_allclose(sequences[0].sensory[1:], seen[1:], atol=0.01)
    np.testing.assert_allclose(
        sequences[0].motor[1:], MirrorMapping().motor_from_hands(truth)[1:], atol=0.05
    )
    recording = json.loads((out / "recording.json").read_text())
    assert recording["dt"] == 0.4
    entry = recording["recordings"]["swing"]
    assert entry["sequences"] == ["swing_1.csv", "swing_2.csv"]
    takes = entry["capture"]["takes"]
    assert [t["body"]["units"] for t in takes] == ["cm", "m"]
    assert [t["body"]["up_axis"] for t in takes] == ["y", "z"]
    assert entry["capture"]["time_scale"] == 1.0
    assert takes[0]["body"]["arm_length_m"] == pytest.approx(0.62)


def test_a_capture_too_fast_for_dt_is_one_line_saying_what_works(tmp_path, capsys):
    fast = _take(tmp_path, "fast.bvh", period=1.0, seconds=6)
    out = tmp_path / "data"
    code = main(["record", f"bvh:{fast}", "--pattern", "fast", "--out", str(out)])
    assert code != 0
    error = capsys.readouterr().err.strip()
    assert len(error.splitlines()) == 1
    assert "it would alias" in error and "use --time-scale" in error and "--dt" in error
    assert not out.exists()


def test_a_folder_holds_one_step_time(tmp_path, capsys):
    take = _take(tmp_path, "a.bvh", period=2.4, seconds=12)
    out = tmp_path / "data"
    args = ["record", f"bvh:{take}", "--cut", "length", "--length", "20", "--out", str(out)]
    assert main([*args, "--pattern", "one"]) == 0
    assert main([*args, "--pattern", "two"]) == 0
    assert set(json.loads((out / "recording.json").read_text())["recordings"]) == {"one", "two"}
    capsys.readouterr()
    assert main([*args, "--pattern", "three", "--dt", "0.2"]) != 0
    assert "holds data recorded at dt 0.4 s" in capsys.readouterr().err


def test_hands_out_of_the_cameras_view_are_not_seen_and_a_distance_is_proposed(tmp_path, capsys):
    times = np.arange(12 * FPS + 1) / FPS
    raised = demonstrator_hands("2", times, 2.4) + np.array([0.0, 0.0, 0.45])
    take = write_bvh(tmp_path / "raised.bvh", raised, 1 / FPS)
    args = ["record", f"bvh:{take}", "--pattern", "up", "--cut", "length", "--length", "20"]
    assert main([*args, "--out", str(tmp_path / "near")]) == 2
    error = capsys.readouterr().err.strip()
    assert "outside the robot camera's view on" in error and "--distance" in error
    distance = error.split("--distance ")[1].split()[0]
    assert main([*args, "--out", str(tmp_path / "far"), "--distance", distance]) == 0
    recording = json.loads((tmp_path / "far" / "recording.json").read_text())
    assert recording["recordings"]["up"]["mapping"]["user_body"]["distance"] == float(distance)
    # the robot's joint angles do not depend on where the person stands
    near = MirrorMapping().motor_from_hands(raised[::12])
    sequences = read_sequence_files([str(tmp_path / "far")])
    np.testing.assert_allclose(sequences[0].motor[1:], near[1:20], atol=0.05)


def test_real_waving_takes_slowed_to_the_papers_step(tmp_path, capsys, mocap_dir):
    waves = sorted(mocap_dir.glob("*wave-both-hands*.bvh"))
    spec = "bvh:" + ",".join(str(p) for p in waves)
    out = tmp_path / "wave"
    assert main(["record", spec, "--pattern", "wave", "--out", str(out)]) != 0
    assert "use --time-scale 1.48 or more" in capsys.readouterr().err
    args = ["--pattern", "wave", "--out", str(out), "--cut", "length", "--length", "40"]
    assert main(["record", spec, "--time-scale", "3", *args]) == 2
    # waving overhead at 1 m leaves the robot camera's view
    assert "--distance 1.5 keeps every step in view" in capsys.readouterr().err
    assert main(["record", spec, "--time-scale", "3", "--distance", "1.5", *args]) == 0
    entry = json.loads((out / "recording.json").read_text())["recordings"]["wave"]
    body = entry["capture"]["takes"][0]["body"]
    assert body["hands"] == ["Hand_L", "Hand_R"] and body["units"] == "cm"
    assert body["up_axis"] == "y" and 0.4 < body["arm_length_m"] < 0.55
    assert entry["steps"] == pytest.approx(3 * 3 * 6.2 / 0.4, rel=0.1)
    sequences = read_sequence_files([str(out)])
    assert len(sequences) >= 3
    assert np.isfinite(np.concatenate([s.motor for s in sequences])).all()
