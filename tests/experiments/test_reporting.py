"""What every report shares: tables, values, figures and the two files, written whole."""

import json
import math

import numpy as np
import pytest

from rnnpb.experiments import reporting


def test_values_read_as_the_report_prints_them():
    assert reporting.fmt(None) == "never"
    assert reporting.fmt(math.nan) == "–"
    assert reporting.fmt(2.345, 2) == "2.35"
    assert reporting.fmt(7) == "7"
    assert reporting.sci(3e-4) == "3e-4"
    assert reporting.sci(2e-10) == "2e-10"
    assert reporting.median_and_worst([4, 6, 9]) == "median 6.0, worst 9"
    assert reporting.median_and_worst([4, None]) == "median 4.0, worst never"
    assert reporting.median_and_worst([]) == "–"


def test_a_table_and_a_figure_in_markdown():
    assert reporting.table(("set", "steps"), [("1", 4), ("2", "never")]) == [
        "| set | steps |",
        "|---|---|",
        "| 1 | 4 |",
        "| 2 | never |",
    ]
    assert reporting.embed("lock-on", "lock.png") == "![lock-on](figures/lock.png)"


def test_both_files_are_written_and_json_holds_plain_values(tmp_path):
    results = {
        "lag": math.nan,
        "steps": np.int64(3),
        "curve": np.arange(3.0),
        "per_seed": {100: (1, 2)},
    }
    reporting.write_outputs(tmp_path, ["# study", "", "text"], results)
    assert (tmp_path / "report.md").read_text() == "# study\n\ntext"
    assert json.loads((tmp_path / "results.json").read_text()) == {
        "lag": None,
        "steps": 3,
        "curve": [0.0, 1.0, 2.0],
        "per_seed": {"100": [1, 2]},
    }


def test_a_failed_write_leaves_the_old_results(tmp_path):
    reporting.write_json(tmp_path / "results.json", {"a": 1})
    with pytest.raises(TypeError):
        reporting.write_json(tmp_path / "results.json", {"a": object()})
    assert json.loads((tmp_path / "results.json").read_text()) == {"a": 1}
    assert [p.name for p in tmp_path.iterdir()] == ["results.json"]
