"""Every writer replaces its file atomically (a failure leaves the old file and no debris), and
the command line reports bad input on one line."""

import json
import os

import numpy as np
import pytest

from rnnpb.cli import main
from rnnpb.perception import BallColors, load_ball_colors, save_ball_colors
from rnnpb.sequences import Sequence, write_sensory_stream, write_sequence


def _failing_fsync(fd):
    raise OSError(28, "No space left on device")


def _writers(model):
    rng = np.random.default_rng(0)
    sequence = Sequence(rng.uniform(0, 1, (4, 4)), rng.uniform(-1, 1, (4, 8)), "wave")
    colors = BallColors()
    return {
        "sequence.csv": lambda p: write_sequence(p, sequence),
        "stream.csv": lambda p: write_sensory_stream(p, sequence.sensory),
        "model.npz": lambda p: model.save(p),
        "colours.json": lambda p: save_ball_colors(p, colors),
    }


@pytest.mark.parametrize("name", ["sequence.csv", "stream.csv", "model.npz", "colours.json"])
def test_failed_write_leaves_the_old_file(model, tmp_path, monkeypatch, name):
    path = tmp_path / name
    path.write_bytes(b"the previous version")
    write = _writers(model)[name]
    monkeypatch.setattr(os, "fsync", _failing_fsync)
    with pytest.raises(OSError, match="No space left"):
        write(path)
    assert path.read_bytes() == b"the previous version"
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]
    monkeypatch.undo()
    write(path)
    assert path.read_bytes() != b"the previous version"


def test_saved_colours_round_trip(tmp_path):
    save_ball_colors(tmp_path / "c.json", BallColors())
    assert load_ball_colors(tmp_path / "c.json") == BallColors()


@pytest.mark.parametrize(
    "content, message",
    [
        (b"\x00\x01garbage", "not a readable rnnpb model file"),
        (b"", "not a readable rnnpb model file"),
    ],
)
def test_cli_bad_model_is_one_line(tmp_path, capsys, content, message):
    model = tmp_path / "m.npz"
    model.write_bytes(content)
    code = main(
        [
            "interact",
            "--model",
            str(model),
            "--source",
            "scenario:held:1",
            "--out",
            str(tmp_path / "out"),
        ]
    )
    err = capsys.readouterr().err
    assert code == 2 and err.startswith(f"rnnpb: error: {model}: ") and message in err
    assert len(err.strip().splitlines()) == 1


def test_cli_bad_stream_is_one_line(model_file, tmp_path, capsys):
    stream = tmp_path / "s.csv"
    stream.write_text("step,lhy,lhz,rhy,rhz\n0,0.1,oops,0.3,0.4\n")
    code = main(
        [
            "interact",
            "--model",
            str(model_file),
            "--source",
            f"csv:{stream}",
            "--out",
            str(tmp_path / "out"),
        ]
    )
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert err.strip() == (f"rnnpb: error: {stream}: line 2, column 'lhz': 'oops' is not a number")


def test_cli_system_errors_are_one_line_unless_debug(model_file, tmp_path, capsys):
    blocked = tmp_path / "file"
    blocked.write_text("not a directory")
    args = [
        "interact",
        "--model",
        str(model_file),
        "--source",
        "scenario:held:1",
        "--out",
        str(blocked / "out"),
        "--steps",
        "2",
    ]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.startswith("rnnpb: error: ") and "Not a directory" in err
    assert len(err.strip().splitlines()) == 1
    with pytest.raises(OSError):
        main(["--debug", *args])


def test_summary_json_is_written_whole(model_file, tmp_path, capsys):
    out = tmp_path / "run"
    assert (
        main(
            [
                "interact",
                "--model",
                str(model_file),
                "--source",
                "scenario:held:1",
                "--out",
                str(out),
                "--steps",
                "3",
            ]
        )
        == 0
    )
    assert json.loads((out / "summary.json").read_text())["loop"]["steps"] == 3
    assert sorted(p.name for p in out.iterdir()) == ["session.csv", "session.png", "summary.json"]
