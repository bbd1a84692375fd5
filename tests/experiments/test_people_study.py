"""`rnnpb study people`: real motion capture through the learning phase, teaching and
following; clear about missing data; its quick form runs on the shared development takes."""

from __future__ import annotations

import json

import pytest

from rnnpb.cli import main
from rnnpb.experiments.exams import load_exam
from rnnpb.experiments.scenarios import people as scenario
from rnnpb.experiments.studies import load_study, study_names


def test_the_people_study_is_registered_and_needs_its_data(tmp_path, capsys):
    assert "people" in study_names() and load_study("people").NAME == "people"
    out = str(tmp_path / "out")
    assert main(["study", "people", "--quick", "--out", out]) == 2
    assert "give --data DIR" in capsys.readouterr().err
    assert main(["study", "people", "--quick", "--data", str(tmp_path / "no"), "--out", out]) == 2
    error = capsys.readouterr().err.strip()
    assert error.startswith("rnnpb: error:") and "\n" not in error and "no such directory" in error


def test_takes_are_chosen_by_their_names_in_id_order(tmp_path):
    for name in ("normal_010", "normal_002", "normal_001", "active_001"):
        (tmp_path / f"dataset-2_wave-both-hands_{name}.bvh").write_text("")
    for side, ids in (("left", ("001", "002")), ("right", ("001", "002"))):
        for i in ids:
            (tmp_path / f"dataset-2_raise-up-{side}-hand_normal_{i}.bvh").write_text("")
    takes = scenario.takes_of(tmp_path, "wave-both-hands", "normal", 2)
    assert [t.name for t in takes] == [
        "dataset-2_wave-both-hands_normal_001.bvh",
        "dataset-2_wave-both-hands_normal_002.bvh",
    ]
    turn = [
        t.name.split("_")[1] for t in scenario.takes_of(tmp_path, scenario.IN_TURN, "normal", 2)
    ]
    assert turn == ["raise-up-left-hand", "raise-up-right-hand"] * 2
    with pytest.raises(Exception, match="3 takes of 'wave-both-hands' by 'normal'"):
        scenario.takes_of(tmp_path, "wave-both-hands", "normal", 4)


def test_settled_steps_leave_out_the_start_of_each_movement():
    labels = ["a"] * 5 + ["b"] * 5
    assert (
        scenario.judged_steps(labels, 3).tolist()
        == [False] * 3 + [True] * 2 + [False] * 3 + [True] * 2
    )
    runs = [
        {
            "labels": labels,
            "recognised": ["a"] * 5 + ["a", "a", "b", "b", None],
            "filtered": [False] * 9 + [True],
        }
    ]
    measured = scenario.measure(runs, 3)
    assert measured["judged_steps"] == 4 and measured["recognised_share"] == 0.75
    assert measured["per_movement"] == {"a": 1.0, "b": 0.5} and measured["filtered_share"] == 0.1


def test_the_quick_form_records_safely_and_is_judged_by_its_exam(tmp_path, mocap_dir):
    from rnnpb.experiments.studies import StudyOptions

    study = load_study("people")
    outcome = study.run(tmp_path / "out", StudyOptions(quick=True, data=str(mocap_dir)))
    results = json.loads((tmp_path / "out" / "results.json").read_text())
    assert set(outcome.targets) == set(load_exam("people").targets)
    assert set(results["takes"]["learn"]) == {"raise-up-both-hands", "wave-both-hands"}
    recordings = results["recordings"]
    assert any("taught" in name for name in recordings)  # the teaching path was measured
    assert all(r["collision"] == 0 and r["speed"] == 0 for r in recordings.values())
    assert outcome.targets["recorded_colliding_steps"].met
    assert results["demonstrator_reach"]["ratio"] == pytest.approx(1.0)
    assert (tmp_path / "out" / "figures" / "following.png").stat().st_size > 10_000
    assert "## Following another performer" in (tmp_path / "out" / "report.md").read_text()
