"""The pose model itself (the ``rnnpb[hands]`` extra; `make test` runs these in .venv-hands):
real photographs and a filmed person, the tracker in a worker thread against the direct call,
the commands and the dashboard with bare hands."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from rnnpb.cli import main
from rnnpb.perception import (
    PerceivedObservation,
    PoseConfig,
    PoseTracker,
    open_camera_source,
    person_frame,
    pose_benchmark,
)
from rnnpb.sequences import read_sensory_stream

from ._required import skip_or_fail

pytestmark = pytest.mark.usefixtures("pose_model")


def _photo(path) -> np.ndarray:
    image = cv2.imread(str(path), cv2.IMREAD_COLOR)
    assert image is not None, path
    return image


def test_a_photographed_person_shoulders_found_hands_out_of_view_lost():
    from matplotlib import cbook

    photo = _photo(cbook.get_sample_data("grace_hopper.jpg", asfileobj=False))
    result = PoseTracker(static_images=True).track(photo)
    assert photo.shape == (600, 512, 3)
    # Grace Hopper's portrait, 512x600: her shoulders at the frame's lower corners (labelled
    # by eye: her left on the image's right), her hands out of the picture.
    np.testing.assert_allclose(result.shoulders_px, [[456, 428], [96, 423]], atol=25)
    assert result.status == ("lost", "lost") and np.isnan(result.sensory).all()


def test_a_photographed_person_a_wrist_found_and_one_hidden():
    try:
        from skimage import data
    except ImportError:
        skip_or_fail("the astronaut photograph ships with scikit-image, which is missing")
    photo = cv2.cvtColor(data.astronaut(), cv2.COLOR_RGB2BGR)
    # Eileen Collins: her right hand at the picture's lower left, her left behind the helmet.
    # The model is unsure of a wrist half out of the frame: accept it from 0.3.
    result = PoseTracker(PoseConfig(min_visibility=0.3), static_images=True).track(photo)
    np.testing.assert_allclose(result.shoulders_px, [[306, 257], [113, 240]], atol=20)
    assert result.status == ("lost", "tracked")
    np.testing.assert_allclose(result.balls[1].center_px, [140, 480], atol=25)
    assert 0.0 < result.sensory[2] < 0.5 and 0.0 < result.sensory[3] < 1.0


FILMED_FRAMES = 60  # 6 s: the right hand waving above the head, then both hands up


@pytest.fixture(scope="module")
def filmed_hands(filmed_person):
    """The filmed person's first 6 s through the pose tracker, read directly and in a worker
    thread: the observations both ways."""
    observations = {}
    for in_worker in (False, True):
        with open_camera_source(
            "video", filmed_person, steps=FILMED_FRAMES, perception="pose", in_worker=in_worker
        ) as source:
            observations[in_worker] = list(iter(source.read, None))
    return observations


def test_the_worker_thread_finds_the_same_hands_as_the_direct_call(filmed_hands):
    direct, worker = filmed_hands[False], filmed_hands[True]
    assert len(direct) == len(worker) == FILMED_FRAMES
    assert all(isinstance(o, PerceivedObservation) and not o.reused for o in worker)
    np.testing.assert_array_equal(
        [o.sensory for o in worker], [o.sensory for o in direct], strict=True
    )


def test_the_filmed_person_waves_his_right_hand_then_raises_both(filmed_hands):
    hands = np.array([o.sensory for o in filmed_hands[True]])  # lhy lhz rhy rhz per frame
    # 1–4 s: his right hand (rhy rhz) up by his head, waving from side to side; his left down.
    waving = hands[10:40]
    assert np.isfinite(waving).all()
    assert (waving[:, 3] > waving[:, 1] + 0.5).all()
    assert np.ptp(waving[:, 2]) > 0.2
    # 5.5–6 s: both hands up.
    assert (hands[55:60, [1, 3]] > 0.8).all()


def test_the_synthetic_render_gives_nan_hands_not_a_failure(tmp_path):
    """The pose model finds no body in the synthetic renders (flat shapes, the head cut by
    the frame): the hands are lost, as the balls are when unseen."""
    with open_camera_source("synthetic", "1", steps=5, perception="pose") as source:
        rows = [observation.sensory for observation in iter(source.read, None)]
    assert len(rows) == 5
    assert source.lost_frames.tolist() == [5, 5] and np.isnan(rows).all()


def test_track_writes_bare_hands_from_an_image_folder(tmp_path, capsys):
    folder = tmp_path / "frames"
    folder.mkdir()
    for i in range(3):
        cv2.imwrite(str(folder / f"{i}.png"), np.roll(person_frame(), 4 * i, axis=1))
    out = tmp_path / "bare.csv"
    assert main(["track", f"images:{folder}", "--perception", "pose", "--out", str(out)]) == 0
    assert read_sensory_stream(out).shape == (3, 4)
    assert "left hand lost in 3 of 3 frames" in capsys.readouterr().out


def test_the_bench_times_following_and_finding_the_body():
    figures = pose_benchmark(n_frames=3, warmup=1)
    assert figures["found"] == 1.0
    for key in ("median_ms", "p95_ms", "detect_median_ms", "detect_p95_ms"):
        assert 0 < figures[key] < 10_000, key


def test_the_dashboard_switches_to_bare_hands(tmp_path):
    from rnnpb.models import default_model
    from rnnpb.web import find_models
    from rnnpb.web._session import Session

    session = Session(find_models(default_model()), workdir=tmp_path)
    try:
        session._apply({"type": "perception", "perception": "pose"})
        assert session.perception == "pose"  # the webcam opens with the pose tracker
    finally:
        session.close()


def test_a_looped_video_plays_on_past_its_end_with_one_tracker(filmed_person):
    """The people study's paced video: sampled every other frame at 0.2 s (the 10 frames/s
    clip holds 63 such steps), read on past its end, the file opened again and the pose
    tracker the same, its hands found on the looped frames too."""
    from rnnpb.experiments.scenarios.people import looped_video
    from rnnpb.sources import FrameStepSource

    source = looped_video(filmed_person, 0.2, 1.55)
    assert isinstance(source, FrameStepSource)
    tracker = source.inner.tracker
    with source:
        observations = [source.read() for _ in range(70)]
    assert all(o is not None for o in observations)
    assert source.inner.tracker is tracker
    # the raised right hand is found on the second pass as on the first
    second = np.array([o.sensory[2:] for o in observations[63:]])
    assert np.isfinite(second).all()
    first = np.array([o.sensory[2:] for o in observations[:7]])
    assert np.abs(second.mean(axis=0) - first.mean(axis=0)).max() < 0.1
