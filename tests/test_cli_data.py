"""The `rnnpb data` command writes the datasets, the learning-set index and Figure 4."""

import json

import numpy as np

from rnnpb.cli import main
from rnnpb.demonstrator import learning_set
from rnnpb.sequences import read_sequence_files


def test_data_command_writes_files_that_read_back(tmp_path, capsys):
    out = tmp_path / "data"
    assert main(["data", "--out", str(out), "--seed", "3", "--period", "10", "--no-render"]) == 0
    assert "wrote 8 sequences" in capsys.readouterr().out
    index = json.loads((out / "learning_sets.json").read_text())
    assert index["generator"]["seed"] == 3 and index["generator"]["period_steps"] == 10
    assert index["learning_sets"]["1"]["patterns"] == ["1", "2", "3"]
    files = index["learning_sets"]["2"]["files"]
    assert files == [
        "patterns/2_1.csv",
        "patterns/2_2.csv",
        "patterns/3_1.csv",
        "patterns/3_2.csv",
        "patterns/4_1.csv",
        "patterns/4_2.csv",
    ]
    read = read_sequence_files([out / f for f in files])
    from rnnpb.demonstrator import PatternConfig

    expected = learning_set("2", seed=3, config=PatternConfig(period_steps=10))
    assert [s.pattern for s in read] == [s.pattern for s in expected]
    for got, want in zip(read, expected, strict=True):
        np.testing.assert_allclose(got.sensory, want.sensory, atol=5e-7)
        np.testing.assert_allclose(got.motor, want.motor, atol=5e-7)
    png = (out / "figure4.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000


def test_data_command_with_rendering(tmp_path):
    out = tmp_path / "rendered"
    assert main(["data", "--out", str(out), "--steps", "24"]) == 0
    assert (out / "figure4.png").stat().st_size > 100_000  # includes four robot renders


def test_data_command_user_error(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["data", "--out", str(blocker)]) == 2
    assert "not a directory" in capsys.readouterr().err
