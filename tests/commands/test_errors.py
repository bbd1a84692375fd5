"""Each bad number on the command line is one error line, exit status 2, before the work."""

import socket

import pytest

from rnnpb.cli import main
from rnnpb.models import SHIPPED_MODEL

MODEL = str(SHIPPED_MODEL)


@pytest.mark.parametrize(
    "argv, message",
    [
        (["bench", "--steps", "0"], "--steps must be in [1,"),
        (["bench", "--reference-steps", "0"], "--reference-steps must be in [1,"),
        (
            ["train", "--data", "none", "--out", "m.npz", "--iterations", "0"],
            "--iterations must be in [1,",
        ),
        (
            ["train", "--data", "none", "--out", "m.npz", "--checkpoint-every", "0"],
            "--checkpoint-every must be in [1,",
        ),
        (
            ["interact", "--source", "scenario:held:1", "--out", "o", "--dt", "inf"],
            "--dt must be a number of seconds",
        ),
        (
            ["interact", "--source", "scenario:held:1", "--out", "o", "--dt", "nan"],
            "--dt must be a number of seconds",
        ),
        (
            ["interact", "--source", "scenario:held:1", "--out", "o", "--frame-step", "0"],
            "--frame-step must be in [1,",
        ),
        (
            ["interact", "--source", "scenario:held:1", "--out", "o", "--steps", "-1"],
            "--steps must be in [0,",
        ),
        (
            [
                "generate",
                "--model",
                MODEL,
                "--pattern",
                "1",
                "--out",
                "g.csv",
                "--transient",
                "1000000000",
            ],
            "--transient must be in [0,",
        ),
        (
            ["generate", "--model", MODEL, "--pattern", "1", "--out", "g.csv", "--steps", "1"],
            "--steps must be in [2,",
        ),
        (["track", "synthetic:1", "--out", "t.csv", "--fps", "inf"], "--fps must be in"),
        (["track", "synthetic:1", "--out", "t.csv", "--steps", "0"], "--steps must be in [1,"),
        (["track", "synthetic:1", "--out", "t.csv", "--smoothing", "nan"], "--smoothing"),
        (["calibrate", "synthetic:1", "--out", "c.json", "--frame", "-1"], "--frame must be in"),
        (["view", "no-such-session"], "no such session recording"),
    ],
)
def test_bad_numbers_are_one_line(argv, message, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("rnnpb: error: ") and err.count("\n") == 1, err
    assert message in err
    assert list(tmp_path.iterdir()) == []  # nothing was written


def test_a_port_in_use_is_one_line_before_the_model_loads(tmp_path, capsys):
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        # A model that cannot load: the port is checked first.
        assert main(["serve", "--model", str(tmp_path / "missing.npz"), "--port", str(port)]) == 2
    err = capsys.readouterr().err
    assert err == (
        f"rnnpb: error: cannot serve on 127.0.0.1:{port}: the port is in use "
        "(another `rnnpb serve`?); choose another with --port, or --port 0 for any "
        "free one\n"
    )


@pytest.mark.slow
def test_calibrate_names_the_side_of_a_pixel_outside_the_frame(tmp_path, capsys):
    assert (
        main(
            [
                "calibrate",
                "synthetic:1",
                "--out",
                str(tmp_path / "c.json"),
                "--left-pixel",
                "5000,5000",
            ]
        )
        == 2
    )
    err = capsys.readouterr().err
    assert "--left-pixel 5000,5000 is outside the" in err and "None" not in err
