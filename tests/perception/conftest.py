"""The pose model's tests (test_pose_model.py) need the ``rnnpb[hands]`` extra, which `make test`
installs in an environment of its own (.venv-hands). Elsewhere they skip, saying why; where
`make test` runs them it sets ``RNNPB_POSE_TESTS=required``, and a missing model, photograph
or filmed person is then a failure, so that they cannot pass by skipping."""

from __future__ import annotations

from pathlib import Path

import pytest

from ._required import VIDEO, skip_or_fail


@pytest.fixture(scope="session")
def pose_model() -> None:
    """The pose model is installed (``rnnpb[hands]``)."""
    from rnnpb.perception import HANDS_INSTALL, pose_available

    if not pose_available():
        skip_or_fail(f"the pose model is not installed ({HANDS_INSTALL})")


@pytest.fixture(scope="session")
def filmed_person(pose_model) -> Path:
    """A man facing the camera, waving his right hand above his head (0–5 s), then both
    (5–12.5 s); 420x420, 10 frames/s (../shared/data/video/README.md)."""
    path = VIDEO / "wave_both_hands.mp4"
    if not path.is_file():
        skip_or_fail(f"no filmed person at {path} (set RNNPB_VIDEO_DIR)")
    return path
