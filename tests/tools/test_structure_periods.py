"""tools/structure_periods.py: the structure test's evidence separates the new shapes at every
speed from random movement, and refuses exam draws."""

import importlib.util
import json
import sys
from pathlib import Path

import pytest

from rnnpb.presets import load_preset

SCRIPT = Path(__file__).resolve().parents[2] / "tools" / "structure_periods.py"


@pytest.fixture(scope="module")
def tool():
    spec = importlib.util.spec_from_file_location("structure_periods", SCRIPT)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    yield module
    sys.modules.pop(spec.name, None)


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
