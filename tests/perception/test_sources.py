"""Camera sources: missing devices and bad files fail fast and clearly; files round-trip."""

from __future__ import annotations

import time

import cv2
import numpy as np
import pytest

from rnnpb.errors import ConfigError, DataFileError, RnnpbError
from rnnpb.perception import (
    ImageFolderSource,
    SceneConfig,
    SyntheticCamera,
    VideoFileSource,
    VideoWriter,
    WebcamSource,
    call_with_timeout,
    open_camera_source,
    open_frame_source,
    oscillating_hands,
)


def _frames(n=6, **scene):
    with SyntheticCamera(oscillating_hands(n), scene=SceneConfig(**scene)) as camera:
        return list(camera)


def test_missing_webcam_is_a_clear_error_not_a_hang():
    start = time.monotonic()
    with pytest.raises(RnnpbError, match="webcam 97"):
        WebcamSource(97, open_timeout_s=3.0).connect()
    assert time.monotonic() - start < 5.0


def test_stuck_device_call_times_out():
    start = time.monotonic()
    with pytest.raises(RnnpbError, match="no answer within 0.2 s"):
        call_with_timeout(lambda: time.sleep(3), 0.2, "reading webcam 0")
    assert time.monotonic() - start < 1.0
    assert call_with_timeout(lambda: 42, 1.0, "x") == 42


def test_missing_and_unreadable_videos(tmp_path):
    with pytest.raises(DataFileError, match="no such video file"):
        VideoFileSource(tmp_path / "nope.mp4").connect()
    garbage = tmp_path / "garbage.mp4"
    garbage.write_bytes(b"not a video" * 100)
    start = time.monotonic()
    with pytest.raises(DataFileError, match="cannot decode"):
        VideoFileSource(garbage).connect()
    assert time.monotonic() - start < 5.0
    with pytest.raises(DataFileError, match="is not a file"):
        VideoFileSource(tmp_path).connect()


@pytest.mark.parametrize("suffix", [".mp4", ".avi"])
def test_video_round_trip_keeps_frames_and_tracking(tmp_path, suffix):
    frames = _frames(12, occlusion_probability=0.0)
    path = tmp_path / f"clip{suffix}"
    with VideoWriter(path, fps=10) as writer:
        for frame in frames:
            writer.write(frame)
    with open_camera_source("video", path) as source:
        observations = []
        while (obs := source.read()) is not None:
            observations.append(obs)
    assert len(observations) == 12
    with SyntheticCamera(oscillating_hands(12), scene=SceneConfig(occlusion_probability=0.0)) as c:
        truth = [c.render(t)[1]["sensory"] for t in range(12)]
    # lossy codecs: within 2 px of the truth
    err = np.abs(np.array([o.sensory for o in observations]) - np.array(truth))
    assert err.max() < 2.0 / 480


def test_failed_video_write_leaves_nothing(tmp_path):
    path = tmp_path / "clip.mp4"
    with pytest.raises(RuntimeError), VideoWriter(path) as writer:
        writer.write(_frames(1)[0])
        raise RuntimeError("stop")
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(RnnpbError, match=".mp4"):
        VideoWriter(tmp_path / "clip.mkv")


def test_image_folder_round_trip_in_natural_order(tmp_path):
    frames = _frames(12)
    for i, frame in enumerate(frames):
        cv2.imwrite(str(tmp_path / f"frame{i}.png"), frame)
    (tmp_path / "notes.txt").write_text("not an image")
    with ImageFolderSource(tmp_path) as source:
        read = list(source)
    assert len(read) == 12
    for a, b in zip(read, frames, strict=True):
        assert np.array_equal(a, b)  # frame10 after frame9, not after frame1


def test_image_folder_errors(tmp_path):
    with pytest.raises(DataFileError, match="holds no images"):
        ImageFolderSource(tmp_path).connect()
    with pytest.raises(DataFileError, match="no such folder"):
        ImageFolderSource(tmp_path / "nope").connect()
    (tmp_path / "broken.png").write_bytes(b"garbage")
    with ImageFolderSource(tmp_path) as source, pytest.raises(DataFileError, match="broken.png"):
        source.read()


def test_camera_sources_from_kind_and_argument():
    # Spec strings are parsed in rnnpb.interaction (tests/interaction); perception opens the parts.
    with pytest.raises(ConfigError, match="no camera source of kind 'camera'"):
        open_frame_source("camera", "0")
    with pytest.raises(ConfigError, match="integer"):
        open_frame_source("webcam", "0")
    with pytest.raises(ConfigError, match="unknown movement pattern"):
        open_frame_source("synthetic", "9")
    with pytest.raises(ConfigError, match="steps must be >= 1"):
        open_frame_source("synthetic", "2", steps=0)
    source = open_frame_source("synthetic", "2", steps=7)
    with source:
        assert len(list(source)) == 7
        assert source.last_truth["pattern"] == "2"


def test_camera_user_source_gives_observations_with_frames_and_nan_when_lost():
    scene = SceneConfig(occlusion_probability=0.0, occlusions=((1, 3, 6),))
    with open_camera_source("synthetic", "1", steps=10, scene=scene) as source:
        observations = []
        while (obs := source.read()) is not None:
            observations.append(obs)
    assert len(observations) == 10
    assert all(o.frame is not None and o.frame.shape == (480, 640, 3) for o in observations)
    seen = np.array([o.seen for o in observations])
    assert seen[:, 0].all()
    assert seen[:, 1].tolist() == [True] * 3 + [False] * 3 + [True] * 4
    assert source.lost_frames.tolist() == [0, 3]
    for o in observations:
        ok = ~np.isnan(o.sensory)
        assert np.abs(o.sensory[ok] - o.truth["sensory"][ok]).max() < 3.0 / 480
