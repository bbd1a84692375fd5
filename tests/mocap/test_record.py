"""`rnnpb record bvh:…`: motion capture through the one learning phase to sequence CSVs and
recording.json."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rnnpb.cli import main
from rnnpb.demonstrator import MirrorMapping
from rnnpb.learning_phase import reach_distance
from rnnpb.learning_phase._framing import projected
from rnnpb.safety import check_data
from rnnpb.sequences import read_sequence_files

from .bvh_files import demonstrator_hands, write_bvh

FPS = 30


def _take(folder, name, period, seconds, pattern="1", **variant):
    times = np.arange(round(seconds * FPS) + 1) / FPS
    return write_bvh(folder / name, demonstrator_hands(pattern, times, period), 1 / FPS, **variant)


def test_a_capture_becomes_sequences_of_what_the_camera_sees_and_the_robot_does(tmp_path, capsys):
    first = _take(tmp_path, "a.bvh", period=2.4, seconds=12)
    second = _take(tmp_path, "b.bvh", period=2.4, seconds=12, naming="lower", unit="m", up="z")
    out = tmp_path / "data"
    code = main(
        ["record", f"bvh:{first},{second}", "--pattern", "swing", "--out", str(out)]
        + ["--cut", "length", "--length", "20", "--framing", "1.0"]
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
    seen = projected(truth, 1.0)
    np.testing.assert_allclose(sequences[0].sensory[1:], seen[1:], atol=0.01)
    np.testing.assert_allclose(
        sequences[0].motor[1:], MirrorMapping().motor_from_hands(truth)[1:], atol=0.05
    )
    recording = json.loads((out / "recording.json").read_text())
    assert recording["dt"] == 0.4 and recording["framing_m"] == 1.0
    entry = recording["recordings"]["swing"]
    assert entry["sequences"] == ["swing_1.csv", "swing_2.csv"]
    takes = entry["capture"]["takes"]
    assert [t["body"]["units"] for t in takes] == ["cm", "m"]
    assert [t["body"]["up_axis"] for t in takes] == ["y", "z"]
    assert entry["time"]["played_time_scale"] == 1.0 and not entry["time"]["retimed"]
    assert takes[0]["body"]["arm_length_m"] == pytest.approx(0.62)


def test_a_capture_too_fast_for_the_step_is_retimed_and_says_so(tmp_path, capsys):
    fast = _take(tmp_path, "fast.bvh", period=1.0, seconds=8)
    out = tmp_path / "data"
    assert main(["record", f"bvh:{fast}", "--pattern", "fast", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "fewer than 4 steps of 0.4 s" in printed and "played 1.6 times slower" in printed
    assert "--dt 0.25 or less" in printed
    entry = json.loads((out / "recording.json").read_text())["recordings"]["fast"]
    assert entry["time"]["retimed"] and entry["time"]["played_time_scale"] == pytest.approx(1.6)
    # played 1.6 times slower, the 1 s cycle is 4 steps of 0.4 s
    assert entry["cycles"]["median_steps"] == pytest.approx(4, abs=0.5)
    # at a step that holds it, the same capture keeps the person's tempo
    assert (
        main(
            ["record", f"bvh:{fast}", "--dt", "0.1", "--pattern", "f", "--out", str(tmp_path / "b")]
        )
        == 0
    )
    entry = json.loads((tmp_path / "b" / "recording.json").read_text())["recordings"]["f"]
    assert not entry["time"]["retimed"]
    assert entry["cycles"]["median_steps"] == pytest.approx(10, abs=1)


def test_a_folder_holds_one_step_time_and_one_framing(tmp_path, capsys):
    take = _take(tmp_path, "a.bvh", period=2.4, seconds=12)
    out = tmp_path / "data"
    args = ["record", f"bvh:{take}", "--cut", "length", "--length", "20", "--out", str(out)]
    assert main([*args, "--pattern", "one", "--framing", "1.2"]) == 0
    # a person recorded into the folder is framed as the folder is
    assert main([*args, "--pattern", "two"]) == 0
    recording = json.loads((out / "recording.json").read_text())
    assert set(recording["recordings"]) == {"one", "two"} and recording["framing_m"] == 1.2
    capsys.readouterr()
    assert main([*args, "--pattern", "three", "--dt", "0.2"]) != 0
    assert "holds data recorded at dt 0.4 s" in capsys.readouterr().err
    assert main([*args, "--pattern", "four", "--framing", "1.5"]) == 2
    assert "framed at 1.2 m, not 1.5 m" in capsys.readouterr().err
    # train learns the folder's framing, and refuses folders framed differently
    other = tmp_path / "other"
    assert main(["record", f"bvh:{take}", "--out", str(other), "--pattern", "x"]) == 0
    capsys.readouterr()
    model = tmp_path / "m.npz"
    assert (
        main(["train", "--data", str(out), str(other), "--out", str(model), "--iterations", "10"])
        == 2
    )
    error = capsys.readouterr().err
    assert "frame the person differently" in error and len(error.strip().splitlines()) == 1


def test_hands_above_the_head_are_framed_by_the_whole_reach(tmp_path, capsys):
    times = np.arange(12 * FPS + 1) / FPS
    raised = demonstrator_hands("2", times, 2.4) + np.array([0.0, 0.0, 0.45])
    take = write_bvh(tmp_path / "raised.bvh", raised, 1 / FPS)
    args = ["record", f"bvh:{take}", "--pattern", "up", "--cut", "length", "--length", "20"]
    assert main([*args, "--out", str(tmp_path / "reach")]) == 0
    printed = capsys.readouterr().out
    assert f"framed at {reach_distance():.2f} m (the whole reach of the body in view)" in printed
    sequences = read_sequence_files([str(tmp_path / "reach")])
    sensory = np.concatenate([s.sensory for s in sequences])
    assert sensory.min() > 0.02 and sensory.max() < 0.98
    # framed nearer than the movement reaches, the hands outside the view are put on its edge
    assert main([*args, "--out", str(tmp_path / "near"), "--framing", "1.0"]) == 0
    assert "a hand outside the view on" in capsys.readouterr().out
    near = np.concatenate([s.sensory for s in read_sequence_files([str(tmp_path / "near")])])
    assert near.max() == 1.0
    # the robot's joint angles do not depend on the framing
    far = np.concatenate([s.motor for s in sequences])
    np.testing.assert_allclose(
        far, np.concatenate([s.motor for s in read_sequence_files([str(tmp_path / "near")])])
    )


def test_real_waving_takes_at_the_persons_tempo(tmp_path, capsys, mocap_dir):
    waves = sorted(mocap_dir.glob("*wave-both-hands*.bvh"))
    spec = "bvh:" + ",".join(str(p) for p in waves)
    for dt in ("0.4", "0.1"):
        out = tmp_path / f"wave{dt}"
        assert main(["record", spec, "--pattern", "wave", "--dt", dt, "--out", str(out)]) == 0
        entry = json.loads((out / "recording.json").read_text())["recordings"]["wave"]
        body = entry["capture"]["takes"][0]["body"]
        assert body["hands"] == ["Hand_L", "Hand_R"] and body["units"] == "cm"
        assert body["up_axis"] == "y" and 0.4 < body["arm_length_m"] < 0.55
        # the raise before each take's waving and the lowering after it are left out
        assert entry["cycles"]["count"] >= 8
        assert entry["cycles"]["steps_in_cycles"] < entry["steps_seen"]
        sequences = read_sequence_files([str(out)])
        assert check_data(sequences, dt=float(dt)).unsafe == 0
    printed = capsys.readouterr().out
    # a wave of about 1.2 s: retimed at the paper's step, at the person's tempo at 0.1 s
    assert "played 1.34 times slower" in printed and "11.5 steps of 0.1 s" in printed


def test_single_raises_per_take_record_with_the_defaults(tmp_path, mocap_dir):
    raises = sorted(mocap_dir.glob("*raise-up-both-hands*.bvh"))
    spec = "bvh:" + ",".join(str(p) for p in raises)
    for dt in ("0.4", "0.1"):
        out = tmp_path / f"raise{dt}"
        assert main(["record", spec, "--pattern", "raise", "--dt", dt, "--out", str(out)]) == 0
        entry = json.loads((out / "recording.json").read_text())["recordings"]["raise"]
        assert entry["cycles"]["count"] == 3  # one raise a take
