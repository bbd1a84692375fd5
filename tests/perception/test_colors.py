"""The colour file: validation with messages that name the file and the field."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rnnpb.errors import ConfigError
from rnnpb.perception import (
    BLUE,
    RED,
    BallColor,
    BallColors,
    load_ball_colors,
    save_ball_colors,
)


def _write(tmp_path, data):
    path = tmp_path / "colors.json"
    path.write_text(json.dumps(data) if not isinstance(data, str) else data)
    return path


GOOD = {
    "format": "rnnpb-ball-colors",
    "version": 1,
    "left": {"name": "red", "hue": [170, 8], "saturation": [120, 255], "value": [60, 255]},
    "right": {"name": "blue", "hue": [100, 130], "saturation": [120, 255], "value": [50, 255]},
}


def test_round_trip(tmp_path):
    colors = BallColors(BallColor("orange", (8, 20), (150, 255), (80, 255)), BLUE)
    path = tmp_path / "sub" / "colors.json"
    save_ball_colors(path, colors)
    assert load_ball_colors(path) == colors
    assert load_ball_colors(_write(tmp_path, GOOD)) == BallColors(RED, BLUE)


def test_red_wraps_through_hue_zero():
    hsv = np.array([[175, 200, 200], [3, 200, 200], [90, 200, 200], [5, 50, 200]], np.uint8)
    assert RED.wraps and not BLUE.wraps
    assert RED.contains(hsv).tolist() == [True, True, False, False]
    assert len(RED.bounds()) == 2 and len(BLUE.bounds()) == 1


@pytest.mark.parametrize(
    ("change", "field", "words"),
    [
        (("left", "hue", [170, 200]), "left.hue", "200 is outside 0…179"),
        (("right", "saturation", [200, 100]), "right.saturation", "low 200 is above high 100"),
        (("right", "value", [10]), "right.value", "expected [low, high]"),
        (("left", "hue", ["a", 3]), "left.hue", "two integers"),
        (("left", "value", [-1, 255]), "left.value", "outside 0…255"),
    ],
)
def test_bad_ranges_name_file_and_field(tmp_path, change, field, words):
    data = json.loads(json.dumps(GOOD))
    side, key, value = change
    data[side][key] = value
    path = _write(tmp_path, data)
    with pytest.raises(ConfigError) as info:
        load_ball_colors(path)
    message = str(info.value)
    assert str(path) in message
    assert f"'{field}'" in message
    assert words in message


def test_malformed_files(tmp_path):
    with pytest.raises(ConfigError, match="not valid JSON"):
        load_ball_colors(_write(tmp_path, "{nope"))
    with pytest.raises(ConfigError, match="no such colour file"):
        load_ball_colors(tmp_path / "missing.json")
    with pytest.raises(ConfigError, match="field 'left'"):
        load_ball_colors(_write(tmp_path, {"right": GOOD["right"]}))
    with pytest.raises(ConfigError, match="left.hue' is missing"):
        load_ball_colors(_write(tmp_path, {"left": {"name": "x"}, "right": GOOD["right"]}))
    with pytest.raises(ConfigError, match="unknown field"):
        load_ball_colors(_write(tmp_path, {**GOOD, "colour": 1}))
    with pytest.raises(ConfigError, match="version"):
        load_ball_colors(_write(tmp_path, {**GOOD, "version": 7}))


def test_a_calibration_error_without_a_ball_name_reads_as_english():
    import pytest

    from rnnpb.errors import RnnpbError
    from rnnpb.perception import calibrate_from_pixel

    grey = np.full((40, 40, 3), 128, np.uint8)
    with pytest.raises(RnnpbError) as outside:
        calibrate_from_pixel(grey, (100, 5))
    with pytest.raises(RnnpbError) as no_colour:
        calibrate_from_pixel(grey, (20, 20))
    for error in (outside, no_colour):
        assert "None" not in str(error.value) and "(the ball)" in str(error.value)
