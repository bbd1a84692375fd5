"""`rnnpb study incremental --quick`: every method, the chain, the report and its figure."""

import json

import pytest

from rnnpb.experiments.studies import StudyOptions, load_study


@pytest.mark.slow
def test_quick_study_writes_its_measures_and_shows_forgetting(tmp_path):
    study = load_study("incremental")
    outcome = study.run(tmp_path, StudyOptions(quick=True, workers=1))
    results = json.loads((tmp_path / "results.json").read_text())
    assert set(results["after"]["1"]) == {"rehearsal", "finetune", "replay", "scratch"}
    assert (tmp_path / "figures" / "forgetting.png").stat().st_size > 0
    assert "## The chain" in (tmp_path / "report.md").read_text()
    assert set(outcome.targets) == {
        "rehearsal_all_followed",
        "rehearsal_old_generation",
        "rehearsal_within_60s",
        "chain_all_followed",
    }
    after = results["after"]["1"]

    def worst_old(method):
        return max(
            p["generation_vs_before"]
            for p in after[method]["pattern"].values()
            if p["generation_vs_before"] is not None
        )

    # Both readings of what the user performs: the on-line recognition's and the nearest PB.
    for method, measured in after.items():
        for name, p in measured["pattern"].items():
            assert p["nearest_pb"] in measured["patterns"], (method, name)
            assert p["recognized"] is None or p["recognized"] in measured["patterns"]
    # Fine-tuning on the new pattern alone moves the old patterns more than rehearsal does.
    assert worst_old("finetune") > worst_old("rehearsal")
    assert results["config"]["quick"] is True and results["versions"]["jax"]
    assert [m["patterns"] for m in results["chain"]] == [["1"], ["1", "2"]]
    # The larger set (learned here: the quick form has no demo models) and a new shape added.
    larger = results["larger_set"]
    assert set(larger) == {"before", "figure-eight"}
    assert larger["before"]["patterns"] == ["1", "2", "3", "4"]
    assert larger["figure-eight"]["patterns"] == ["1", "2", "3", "4", "figure-eight"]
    grown = larger["figure-eight"]["pattern"]
    assert all(grown[p]["generation_vs_before"] is not None for p in "1234")
    assert grown["figure-eight"]["generation_vs_before"] is None
    assert larger["figure-eight"]["cpu_seconds"] > 0
    assert "## The larger set and new shapes" in (tmp_path / "report.md").read_text()
