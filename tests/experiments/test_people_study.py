"""`rnnpb study people`: real people through the learning phase and followed in others, at
their own speed; clear about missing data; its quick form runs on the shared development
takes."""

from __future__ import annotations

import json

import numpy as np
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
    for name in ("normal_010", "normal_002", "normal_001", "active_001", "normal_003"):
        (tmp_path / f"dataset-2_wave-both-hands_{name}.bvh").write_text("")
    for side, ids in (("left", ("001", "002", "003")), ("right", ("001", "002", "003"))):
        for i in ids:
            (tmp_path / f"dataset-2_raise-up-{side}-hand_normal_{i}.bvh").write_text("")
    takes = scenario.takes_of(tmp_path, "wave-both-hands", "normal", 2, 2)
    assert [t.name for t in takes] == [
        "dataset-2_wave-both-hands_normal_002.bvh",
        "dataset-2_wave-both-hands_normal_003.bvh",
    ]
    turn = [
        t.name.split("_")[1] for t in scenario.takes_of(tmp_path, scenario.IN_TURN, "normal", 1, 2)
    ]
    assert turn == ["raise-up-left-hand", "raise-up-right-hand"] * 2
    with pytest.raises(Exception, match="4 takes of 'wave-both-hands' by 'normal'"):
        scenario.takes_of(tmp_path, "wave-both-hands", "normal", 2, 4)


def test_settled_steps_segments_and_jumps_are_measured_as_defined():
    labels = ["a"] * 30 + ["b"] * 30
    assert scenario.settled_steps(labels, 3)[:5].tolist() == [False] * 3 + [True] * 2
    t = np.arange(60)
    swing = np.stack([np.sin(2 * np.pi * t / 10)] * 8, axis=1)
    pb = np.zeros((60, 4))
    pb[40, 0] = 0.5  # one jump onto step 40 and one back off it
    run = {
        "labels": labels,
        "recognised": ["a"] * 30 + ["b"] * 29 + [None],
        "filtered": [False] * 59 + [True],
        "pb": pb,
        "motor": np.roll(swing, 3, axis=0),  # three steps behind the target
        "target": swing,
    }
    config = scenario.PeopleConfig(dt=0.4, settle_seconds=1.2, segment_seconds=4.0)
    measured = scenario.measure([run], config)
    assert measured["judged_steps"] == 54 and measured["recognised_share"] == pytest.approx(53 / 54)
    assert measured["per_movement"]["a"] == 1.0
    assert measured["pb_jump_share"] == pytest.approx(2 / 54)
    assert measured["in_step_share"] == 0.0 and measured["segments"] > 0
    run["motor"] = swing  # in step
    assert scenario.measure([run], config)["in_step_share"] == 1.0
    assert measured["filtered"] == 1 and measured["commands"] == 60


def test_the_quick_form_records_and_follows_at_the_people_s_own_speed(tmp_path, mocap_dir):
    from rnnpb.experiments.studies import StudyOptions

    study = load_study("people")
    outcome = study.run(tmp_path / "out", StudyOptions(quick=True, data=str(mocap_dir)))
    results = json.loads((tmp_path / "out" / "results.json").read_text())
    assert set(outcome.targets) == set(load_exam("people").targets)
    assert set(results["plan"]["learn"]) == {"raise-up-both-hands", "wave-both-hands"}
    sources = results["sources"]["capture dt 0.1"]
    # recorded with the learning phase's defaults, learned without a refusal, judged safe
    assert all(not s["refused"] for s in sources.values())
    assert all(
        s["judged"]["colliding"] == 0 and s["judged"]["too_fast"] == 0 for s in sources.values()
    )
    assert all(not s["time"]["retimed"] for s in sources.values())  # 0.1 s holds them
    assert outcome.targets["recorded_then_refused"].met
    assert outcome.targets["learned_unsafe_steps"].met
    assert results["following"]["dt0.1"]["judged_steps"] > 0
    assert (tmp_path / "out" / "figures" / "following_dt0.1.png").stat().st_size > 10_000
    assert "## Following another performer" in (tmp_path / "out" / "report.md").read_text()
