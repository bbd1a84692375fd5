"""tools/structure_periods.py: the structure test's evidence separates the new shapes at every
speed from random movement, and refuses exam draws."""

import json

import pytest

from rnnpb.presets import load_preset


@pytest.fixture(scope="module")
def tool(load_tool):
    return load_tool("structure_periods")


def test_the_presets_level_lies_between_the_shapes_and_random_movement(tool, tmp_path):
    out = tmp_path / "periods.json"
    assert tool.main(["--draws", "0", "--steps", "150", "--json", str(out)]) == 0
    figures = json.loads(out.read_text())
    level = load_preset("fast").section("recognition_untaught")["structure_level"]
    shapes = [figures[f"shape {s}"]["max"] for s in ("0.5x", "1x", "2x")]
    assert max(shapes) < level < figures["random"]["min"]


def test_an_exam_draw_is_refused(tool, capsys):
    with pytest.raises(SystemExit):
        tool.main(["--draws", "7010"])
    assert "exam" in capsys.readouterr().err
