"""Bare hands in the dashboard are framed as the running model learned people."""

from __future__ import annotations

import time
from dataclasses import replace

from rnnpb.model import TrainedModel
from rnnpb.models import SHIPPED_MODEL
from rnnpb.web import Session, find_models
from rnnpb.web._webcam import Webcam


def test_a_closed_webcam_takes_the_framing_for_its_next_opening():
    webcam = Webcam()
    assert webcam.framing is None
    assert webcam.frame_for(1.55) is None  # nothing open: nothing opened
    assert webcam.framing == 1.55 and webcam.source is None


def test_the_session_frames_bare_hands_at_the_loaded_models_framing(tmp_path):
    folder = tmp_path / "models"
    folder.mkdir()
    model = TrainedModel.load(SHIPPED_MODEL)
    replace(model, meta={**model.meta, "framing_m": 1.55}).save(folder / "people.npz")
    session = Session(find_models(folder), dt=0.02, workdir=tmp_path / "sessions")
    try:
        session.start()
        deadline = time.monotonic() + 90
        while session.mirror is None or session.loading:
            assert time.monotonic() < deadline, "the model did not load within 90 s"
            time.sleep(0.05)
        assert session.model.framing == 1.55
        assert session.webcam.framing == 1.55
    finally:
        session.close()
