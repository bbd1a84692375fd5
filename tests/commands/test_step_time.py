"""A model's step time: learned at the dt its data were recorded at, shown, and the only one
it plays at."""

from __future__ import annotations

import json
from dataclasses import replace

import pytest

from rnnpb.cli import main
from rnnpb.errors import ModelFileError
from rnnpb.model import TrainedModel
from rnnpb.models import SHIPPED_MODEL


def _one_line_error(capsys) -> str:
    error = capsys.readouterr().err.strip()
    assert len(error.splitlines()) == 1, error
    return error


def _record(folder, dt, pattern="one", steps=40):
    args = ["record", "scenario:held:1", "--steps", str(steps), "--pattern", pattern]
    args += ["--cut", "length", "--length", "20", "--dt", str(dt), "--out", str(folder)]
    assert main(args) == 0


def test_a_model_is_learned_at_its_datas_step_and_plays_only_at_it(tmp_path, capsys, monkeypatch):
    # What is learned does not matter here, only what the command records: the learning
    # itself is the shipped model's, so the test learns nothing.
    learned = TrainedModel.load(SHIPPED_MODEL)
    monkeypatch.setattr("rnnpb.model.train", lambda sequences, *args, **kwargs: learned)
    data = tmp_path / "data"
    _record(data, 0.2)
    assert json.loads((data / "recording.json").read_text())["dt"] == 0.2
    model = tmp_path / "model.npz"
    train = ["train", "--data", str(data), "--out", str(model), "--preset", "fast"]
    assert main([*train, "--iterations", "5", "--no-progress"]) == 0
    assert "learned at dt 0.2 s (from " in capsys.readouterr().out
    assert TrainedModel.load(model).dt == 0.2
    assert main(["info", str(model)]) == 0
    shown = capsys.readouterr().out
    assert "step time: dt 0.2 s" in shown
    # the demonstrator stands where the camera frames it: the standard user's place
    assert "framing: a person's body placed 1 m from the robot's camera" in shown
    out = str(tmp_path / "run")
    assert (
        main(
            [
                "interact",
                "--model",
                str(model),
                "--source",
                "scenario:held:1",
                "--out",
                out,
                "--dt",
                "0.4",
            ]
        )
        == 2
    )
    error = _one_line_error(capsys)
    assert "was learned at dt 0.2 s" in error and "rnnpb record --dt 0.4" in error


def test_data_of_different_step_times_are_refused_before_learning(tmp_path, capsys):
    _record(tmp_path / "slow", 0.4)
    _record(tmp_path / "fast", 0.1, pattern="two", steps=60)
    capsys.readouterr()
    model = tmp_path / "model.npz"
    train = ["train", "--out", str(model), "--preset", "fast", "--iterations", "5"]
    assert main([*train, "--data", str(tmp_path / "slow"), str(tmp_path / "fast")]) == 2
    error = _one_line_error(capsys)
    assert "recorded at different step times" in error and "dt 0.1 s" in error
    assert main([*train, "--data", str(tmp_path / "slow"), "--dt", "0.1"]) == 2
    assert "--dt 0.1: the data were recorded at dt 0.4 s" in _one_line_error(capsys)
    assert not model.exists()


def test_an_older_model_counts_as_the_papers_step(tmp_path, capsys):
    shipped = TrainedModel.load(SHIPPED_MODEL)
    assert "dt" not in shipped.meta and shipped.dt == 0.4
    out = str(tmp_path / "run")
    args = ["interact", "--model", str(SHIPPED_MODEL), "--source", "scenario:held:1"]
    assert main([*args, "--out", out, "--dt", "0.1"]) == 2
    assert "was learned at dt 0.4 s" in _one_line_error(capsys)
    assert main(["serve", "--model", str(SHIPPED_MODEL), "--port", "0", "--dt", "0.1"]) == 2
    assert "was learned at dt 0.4 s" in _one_line_error(capsys)


def test_a_model_file_with_a_bad_step_time_is_refused(tmp_path):
    shipped = TrainedModel.load(SHIPPED_MODEL)
    path = tmp_path / "bad.npz"
    replace(shipped, meta={**shipped.meta, "dt": -1}).save(path)
    with pytest.raises(ModelFileError, match="step time dt -1 is not a number of seconds"):
        TrainedModel.load(path)


def test_serve_refuses_models_of_different_step_times(tmp_path, capsys):
    shipped = TrainedModel.load(SHIPPED_MODEL)
    folder = tmp_path / "models"
    shipped.save(folder / "paper.npz")
    replace(shipped, meta={**shipped.meta, "dt": 0.1}).save(folder / "fast.npz")
    assert main(["serve", "--model", str(folder), "--port", "0"]) == 2
    error = _one_line_error(capsys)
    assert (
        "different step times" in error and "fast.npz 0.1 s" in error and "paper.npz 0.4 s" in error
    )
