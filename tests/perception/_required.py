"""Where `make test` requires the pose tests to run (``RNNPB_POSE_TESTS=required``), what
they would skip for is a failure instead."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

POSE_TESTS_REQUIRED = os.environ.get("RNNPB_POSE_TESTS") == "required"

# A real filmed person: test data read where it is (RNNPB_VIDEO_DIR, else
# ../shared/data/video beside the checkout), never copied into the project.
VIDEO = Path(
    os.environ.get(
        "RNNPB_VIDEO_DIR", Path(__file__).resolve().parents[2].parent / "shared/data/video"
    )
)


def skip_or_fail(reason: str) -> None:
    """Skip the test for ``reason``, or fail it where the pose tests are required."""
    if POSE_TESTS_REQUIRED:
        pytest.fail(f"{reason}; RNNPB_POSE_TESTS=required, so this test must run")
    pytest.skip(reason)
