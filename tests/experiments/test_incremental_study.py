"""`rnnpb study incremental`: the quick form end to end (every method, the chain, the larger
set, the report and its figure), the judge on measures made here, and the exam's
configuration. Whether the study meets its targets (and how much fine-tuning forgets) is judged
by `rnnpb study incremental --exam`, not here."""

import json
import math
from dataclasses import replace

import pytest

from rnnpb.experiments.studies import StudyOptions, load_study


@pytest.mark.slow
def test_quick_study_writes_its_measures_report_and_verdicts(tmp_path):
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
    # Every method measures how far each old pattern moved (a distance > 0: every weight
    # changed); the new pattern, which the starting model lacked, and only it, has no "before".
    old = results["before"]["1"]["patterns"]
    for method, measured in after.items():
        moved = {name: p["generation_vs_before"] for name, p in measured["pattern"].items()}
        added = [name for name in measured["patterns"] if name not in old]
        assert len(added) == 1 and [n for n, v in moved.items() if v is None] == added, method
        assert all(math.isfinite(moved[n]) and moved[n] > 0 for n in old), (method, moved)
    # The verdict reads the same figure: the worst old pattern after rehearsal, over the sets.
    worst = max(
        p["generation_vs_before"]
        for measured in results["after"].values()
        for name, p in measured["rehearsal"]["pattern"].items()
        if p["generation_vs_before"] is not None
    )
    assert worst == worst_old("rehearsal") or len(results["after"]) > 1
    assert outcome.targets["rehearsal_old_generation"].value == pytest.approx(worst)
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
    # No --models: the starting models were learned into the output, under the demo's names.
    assert (tmp_path / "models" / "set1.npz").is_file()
    assert (tmp_path / "models" / "full.npz").is_file()
    # The exam's judge of the finished results gives the run's own verdicts.
    from rnnpb.experiments.exams import load_exam

    assert study.judge_results(results, load_exam("incremental")) == outcome.targets


def _measures(label, locks, generation, switch=5, cpu=2.0):
    from rnnpb.experiments.scenarios.incremental_measures import ModelMeasures, PatternMeasures

    patterns = tuple(locks)
    return ModelMeasures(
        label=label,
        patterns=patterns,
        pattern={
            p: PatternMeasures(p, lock, p, p, 12.0, generation.get(p), 0.01)
            for p, lock in locks.items()
        },
        switching={f"{a}->{b}": switch for a in patterns for b in patterns if a != b},
        train_mse_max=1e-4,
        seconds=3.0,
        iterations=200,
        cpu_seconds=cpu,
    )


def test_the_judge_reads_forgetting_time_and_following_against_the_exam():
    """Rehearsal that moved an old pattern by 0.03 in 2 s of CPU, every pattern locked on in
    4 steps: met against the default limits, missed against stricter ones."""
    from rnnpb.experiments.exams import load_exam
    from rnnpb.experiments.studies.incremental import judge

    rehearsed = _measures("rehearsal", {"1": 4, "2": 4}, {"1": 0.03})
    chain = [_measures("1", {"1": 4}, {}), _measures("+2", {"1": 4, "2": 4}, {"1": 0.01})]
    after = {"1": {"rehearsal": rehearsed}}
    default = judge(after, chain)
    assert all(t.met for t in default.values()), default
    assert "moved 0.030 RMS (limit 0.05)" in default["rehearsal_old_generation"].detail
    exam = load_exam("incremental")
    stricter = {
        "rehearsal_all_followed": {"parameters": {"lock_steps": 3, "switch_steps": 15}},
        "rehearsal_old_generation": {"limit": 0.02},
        "rehearsal_within_60s": {"limit": 1.0},
        "chain_all_followed": {"parameters": {"lock_steps": 3, "switch_steps": 15}},
    }
    targets = {name: replace(t, **stricter[name]) for name, t in exam.targets.items()}
    judged = judge(after, chain, replace(exam, targets=targets))
    assert not any(t.met for t in judged.values()), judged
    assert "(limit 0.02)" in judged["rehearsal_old_generation"].detail
    assert judged["chain_all_followed"].detail == "after 1 consolidation(s): 1: lock 4, 2: lock 4"


def test_the_exam_runs_the_full_form_on_its_own_draws():
    from rnnpb.experiments.exams import load_exam
    from rnnpb.experiments.studies.incremental import study_config

    exam = load_exam("incremental")
    config = study_config(StudyOptions(exam=exam))
    assert not config.quick and config.models is None
    assert config.new_data_seed == exam.seed_list("new_data")[0]
    assert config.scenario_seed == exam.seed_list("user")[0]
    assert config.learning_sets == exam.learning_sets
