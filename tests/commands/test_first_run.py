"""The first run: commands find a model with none given, pick the regression that suits it,
and list the cameras present."""

import json
import shutil

import numpy as np
import pytest

from rnnpb.cli import main
from rnnpb.commands import cameras
from rnnpb.model import TrainedModel
from rnnpb.models import SHIPPED_MODEL, default_model, first_model_file


def test_the_shipped_model_is_a_fast_preset_set_1_model():
    model = TrainedModel.load(SHIPPED_MODEL)
    assert model.patterns == ("1", "2", "3")
    assert model.meta["train_config"]["optimizer"] == "adam"
    assert model.meta["train_config"]["seed"] == 0
    assert SHIPPED_MODEL.stat().st_size < 200_000


def test_models_are_found_in_the_demo_folder_else_the_shipped_one(tmp_path):
    assert default_model(tmp_path) == SHIPPED_MODEL
    demo = tmp_path / "results" / "demo" / "models"
    demo.mkdir(parents=True)
    (demo / "set2.checkpoint.npz").write_bytes(b"")
    assert default_model(tmp_path) == SHIPPED_MODEL  # a checkpoint is no model
    shutil.copy(SHIPPED_MODEL, demo / "set2.npz")
    shutil.copy(SHIPPED_MODEL, demo / "set1.npz")
    assert default_model(tmp_path) == demo
    assert first_model_file(demo) == demo / "set1.npz"
    own = tmp_path / "models"
    own.mkdir()
    shutil.copy(SHIPPED_MODEL, own / "mine.npz")
    assert default_model(tmp_path) == own


@pytest.mark.slow
def test_interact_without_a_model_runs_the_shipped_one_with_its_regression(
    tmp_path, monkeypatch, capsys
):
    monkeypatch.chdir(tmp_path)
    assert main(["interact", "--source", "scenario:held:1", "--steps", "4", "--out", "run"]) == 0
    out = capsys.readouterr().out
    assert (
        "(ungated on-line regression, chosen as the model was learned with Adam, the fast "
        "preset; --online overrides;"
    ) in out
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["model"] == str(SHIPPED_MODEL) and summary["online"] == "ungated"
    assert summary["online_config"]["surprise_gate"] == 0.0
    assert (
        main(
            [
                "interact",
                "--source",
                "scenario:held:1",
                "--steps",
                "2",
                "--online",
                "default",
                "--out",
                "run2",
            ]
        )
        == 0
    )
    assert "(default on-line regression; kinematic robot)" in capsys.readouterr().out
    summary = json.loads((tmp_path / "run2" / "summary.json").read_text())
    assert summary["online"] == "default" and summary["online_config"]["surprise_gate"] > 0


def test_interact_help_names_paths_that_exist_or_are_made(capsys):
    with pytest.raises(SystemExit):
        main(["interact", "--help"])
    out = capsys.readouterr().out
    assert "results/models/" not in out and "results/demo/models/" in out


class _FakeCapture:
    """OpenCV's VideoCapture as a camera (or a metadata node) answers it."""

    def __init__(self, frame_shape, fps, opens=True):
        self.frame_shape, self.fps, self.opens, self.released = frame_shape, fps, opens, False

    def isOpened(self):  # noqa: N802 (OpenCV's name)
        return self.opens

    def read(self):
        if self.frame_shape is None:
            return False, None
        return True, np.zeros(self.frame_shape, np.uint8)

    def get(self, prop):
        return self.fps

    def release(self):
        self.released = True


def test_cameras_lists_the_cameras_that_deliver_a_frame(monkeypatch, capsys):
    captures = {
        0: _FakeCapture((480, 640, 3), 30.0),
        1: _FakeCapture(None, 0.0),
        2: _FakeCapture((720, 1280, 3), 0.0),
        3: _FakeCapture(None, 0.0, opens=False),
    }
    devices = [(i, f"/dev/video{i}") for i in captures]
    found = cameras.probe_cameras(devices, captures.__getitem__)
    assert [(c.index, c.width, c.height, c.fps) for c in found] == [
        (0, 640, 480, 30.0),
        (2, 1280, 720, 0.0),
    ]
    assert all(c.released for c in captures.values())
    monkeypatch.setattr(cameras, "candidate_devices", lambda: devices)
    monkeypatch.setattr("cv2.VideoCapture", captures.__getitem__)
    assert main(["cameras"]) == 0
    out = capsys.readouterr().out
    assert "2 camera(s)" in out
    assert "webcam:0  /dev/video0  640x480, 30 frames/s" in out
    assert "webcam:2  /dev/video2  1280x720, frame rate not reported" in out


def test_cameras_says_cleanly_when_there_is_none(monkeypatch, capsys):
    monkeypatch.setattr(cameras, "candidate_devices", lambda: [])
    assert main(["cameras"]) == 0
    captured = capsys.readouterr()
    assert captured.out.startswith("no camera found: no video devices") and not captured.err
