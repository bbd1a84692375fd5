"""The BVH reader: forward kinematics that agree with an independent writer, and one-line
errors naming the file and line for damaged files."""

from __future__ import annotations

import numpy as np
import pytest

from rnnpb.errors import DataFileError
from rnnpb.mocap import body_hands, read_bvh

from .bvh_files import demonstrator_hands, write_bvh

FPS = 30


@pytest.fixture(scope="module")
def good_file(tmp_path_factory):
    times = np.arange(60) / FPS
    path = tmp_path_factory.mktemp("bvh") / "take.bvh"
    return write_bvh(path, demonstrator_hands("4", times, 1.5), 1 / FPS)


def test_the_skeleton_and_motion_are_read(good_file):
    bvh = read_bvh(good_file)
    assert bvh.n_frames == 60
    assert bvh.frame_time == pytest.approx(1 / FPS)
    assert bvh.names[:3] == ("Hips", "Spine", "Chest")
    assert "LeftHandIndex1" in bvh.names
    hand = bvh.index("LeftHand")
    assert [bvh.names[i] for i in bvh.ancestors(hand)][:3] == [
        "LeftForeArm",
        "LeftArm",
        "LeftShoulder",
    ]
    # the forward kinematics keep every bone's length in every frame
    positions = bvh.world_positions()
    fore = bvh.index("LeftForeArm")
    lengths = np.linalg.norm(positions[:, hand] - positions[:, fore], axis=-1)
    np.testing.assert_allclose(lengths, 32.0, atol=1e-4)


def _damaged(tmp_path, good_file, change) -> tuple[str, int]:
    lines = good_file.read_text().splitlines()
    lines, line = change(lines)
    path = tmp_path / "damaged.bvh"
    path.write_text("\n".join(lines) + "\n")
    return str(path), line


def _motion_start(lines) -> int:
    return lines.index("MOTION") + 3  # index of the first frame's line


def _truncate(lines):
    start = _motion_start(lines)
    return lines[: start + 40], start + 41  # the missing frame would be on the next line


def _short_frame(lines):
    k = _motion_start(lines) + 7
    lines[k] = " ".join(lines[k].split()[:-1])
    return lines, k + 1


def _long_frame(lines):
    k = _motion_start(lines) + 3
    lines[k] += " 0.0"
    return lines, k + 1


def _nan(lines):
    k = _motion_start(lines) + 11
    values = lines[k].split()
    values[20] = "nan"
    lines[k] = " ".join(values)
    return lines, k + 1


def _channel_count(lines):
    k = next(i for i, line in enumerate(lines) if "CHANNELS 3" in line)
    lines[k] = lines[k].replace("CHANNELS 3", "CHANNELS 4")
    return lines, k + 1


@pytest.mark.parametrize(
    ("change", "says"),
    [
        (_truncate, "ends after 40 of the 60 frames"),
        (_short_frame, "has 44 values; the hierarchy has 45 channels"),
        (_long_frame, "has 46 values; the hierarchy has 45 channels"),
        (_nan, "'nan' is not a finite number"),
        (_channel_count, "CHANNELS 4 lists 3 channels"),
    ],
)
def test_a_damaged_file_is_one_line_naming_file_and_line(tmp_path, good_file, change, says):
    path, line = _damaged(tmp_path, good_file, change)
    with pytest.raises(DataFileError) as error:
        read_bvh(path)
    message = str(error.value)
    assert "\n" not in message
    assert message.startswith(f"{path}, line {line}: ")
    assert says in message


def test_a_file_that_is_not_bvh_is_refused(tmp_path):
    path = tmp_path / "notes.bvh"
    path.write_text("step,lhy\n1,0.5\n")
    with pytest.raises(DataFileError, match=r"notes\.bvh, line 1: expected HIERARCHY"):
        read_bvh(path)
    with pytest.raises(DataFileError, match="no such file"):
        read_bvh(tmp_path / "missing.bvh")


def test_hands_are_found_by_name_or_named(tmp_path, good_file):
    bvh = read_bvh(good_file)
    _, scale = body_hands(bvh)
    # the finger below the hand also says "hand": the hand is the shallower joint
    assert scale.hands == ("LeftHand", "RightHand")
    assert scale.shoulders == ("LeftArm", "RightArm")
    _, named = body_hands(bvh, hands=("LeftForeArm", "RightForeArm"))
    assert named.shoulders == ("LeftShoulder", "RightShoulder")
    with pytest.raises(DataFileError, match="no joint called 'Wrist'"):
        body_hands(bvh, hands=("Wrist", "RightHand"))
