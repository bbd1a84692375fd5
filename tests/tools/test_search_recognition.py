"""tools/search_recognition.py: the recognition settings' search refuses exam draws, scores the
preset's current values beside its trials, and writes a fragment in the preset files' form."""

import json
import shutil
import tomllib

import pytest

from rnnpb.experiments.exams import load_exam
from rnnpb.model.recognition import RecognitionConfig
from rnnpb.models import SHIPPED_MODEL


@pytest.fixture(scope="module")
def tool(load_tool):
    return load_tool("search_recognition")


def test_an_exam_draw_is_refused_in_one_line(tool, tmp_path, capsys):
    # 7010 is a draw of the novelty study's exam: nothing may be chosen on it.
    assert tool.main(["--draws", "0,7010", "--out", str(tmp_path)]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "7010" in error and "exam" in error
    assert not (tmp_path / "search.json").exists()


@pytest.mark.slow
def test_a_tiny_search_writes_its_trials_and_a_fragment_to_paste(tool, tmp_path, capsys):
    # The shipped model is the novelty study's fast-preset model of learning set 1 (seed 0).
    models = tmp_path / "models"
    models.mkdir()
    shutil.copy(SHIPPED_MODEL, models / "fast_set1.npz")
    out = tmp_path / "out"
    argv = ["--models", str(models), "--sets", "1", "--draws", "3", "--trials", "2",
            "--steps", "30", "--shapes", "0", "--out", str(out)]  # fmt: skip
    assert tool.main(argv) == 0
    printed = capsys.readouterr().out
    assert "current" in printed and "best" in printed

    results = json.loads((out / "search.json").read_text())
    assert results["draws"] == [3]
    assert results["preset"]["name"] == "fast" and results["preset"]["version"] >= 1
    assert "--trials 2" in results["command"]
    assert [t["trial"] for t in results["trials"]] == [0, 1]
    keys = set(tool.searched_keys("fast", "recognition"))
    current = results["current"]
    assert set(current["values"]) == keys
    assert current["values"] == {k: RecognitionConfig.fast().tuning[k] for k in keys}
    for result in [current, *results["trials"]]:
        assert 0 <= result["met"] <= result["of"] == len(load_exam("novelty").targets)
        assert result["met"] <= result["score"] <= result["met"] + 1
    # Each trial changed the searched values, and the best is the best-scored trial.
    assert all(set(t["values"]) == keys for t in results["trials"])
    assert results["best"]["score"] == max(t["score"] for t in results["trials"])
    assert results["pick"] == "best" and results["chosen"] == results["best"]

    fragment = tomllib.loads((out / "preset_fragment.toml").read_text())
    assert set(fragment["recognition"]) <= set(RecognitionConfig().tuning)  # the tuned names
    assert fragment["recognition"] == results["chosen"]["values"]
    source = fragment["sources"]["recognition-search-fast"]
    assert source["draws"] == [3]
    assert source["command"] == results["command"]
    assert set(source) == {"kind", "command", "draws", "figure", "note"}
    assert source["kind"] == "measured"
    # The best values are ones RecognitionConfig takes.
    RecognitionConfig.fast().with_tuning(**fragment["recognition"])
