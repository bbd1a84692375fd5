"""The routine level: segments of the lower PB, a two-routine higher level learned from the
demonstrator, its anticipation, deviations, and its file."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rnnpb.demonstrator import routine_scenario
from rnnpb.errors import ConfigError, ModelFileError
from rnnpb.model import TrainedModel
from rnnpb.model.routines import (
    RoutineLearning,
    RoutineModel,
    SegmentConfig,
    TwoLevelMirror,
    generate_routine,
    learn_routines,
    routine_events,
    segment_pb,
)
from rnnpb.models import SHIPPED_MODEL

DANCE = [("1", 3), ("3", 2), ("2", 4)]
WAVE = [("2", 2), ("3", 3), ("1", 3)]


@pytest.fixture(scope="module")
def lower():
    return TrainedModel.load(SHIPPED_MODEL)


@pytest.fixture(scope="module")
def routines(lower):
    recordings = {
        "dance": [routine_scenario(DANCE, seed=201).sensory],
        "wave": [routine_scenario(WAVE, seed=201).sensory],
    }
    return learn_routines(lower, recordings, RoutineLearning(iterations=1500))


def test_segments_follow_the_nearest_learned_pb_and_ignore_a_short_excursion():
    learned = np.array([[0.9, 0.9], [0.1, 0.1], [0.9, 0.1]])
    stream = np.array(
        [[0.85, 0.8]] * 30 + [[0.15, 0.1]] * 20 + [[0.8, 0.15]] * 8 + [[0.1, 0.2]] * 25
    )
    segments = segment_pb(stream, learned, SegmentConfig(hold=6, min_length=12))
    assert [(s.start, s.pattern) for s in segments] == [(0, 0), (30, 1)]
    assert segments[-1].stop == len(stream)
    events = routine_events(segments)
    # The start event, then each code with the duration of the segment before (of 80 steps).
    assert np.allclose(events[0], [0.5, 0.5, 0.0])
    assert np.allclose(events[1], [0.9, 0.9, 0.0]) and np.allclose(events[2], [0.1, 0.1, 30 / 80])


def test_a_learned_routine_is_recognised_and_its_switch_anticipated(lower, routines):
    scenario = routine_scenario(DANCE, seed=101)
    two = TwoLevelMirror(lower, routines)
    steps = [two.step(u) for u in scenario.sensory]
    switch = scenario.switch_steps[0]
    before = steps[switch - 1]
    # Before the person switches, the higher level knows the routine and says what comes next.
    assert before.higher.routine == "dance"
    assert before.anticipated == "3"
    assert abs(before.higher.steps_left) <= 6  # when it ends: within half a cycle
    # And an order no routine has is not taken for one.
    other = TwoLevelMirror(lower, routines)
    said = [other.step(u).higher.routine for u in routine_scenario(
        [("3", 2), ("1", 3), ("2", 2)], seed=101).sensory]  # fmt: skip
    assert sum(s is not None for s in said[12:]) <= 0.05 * len(said[12:])


def test_a_deviation_from_the_routine_is_followed(lower, routines):
    scenario = routine_scenario([("1", 3), ("2", 3)], seed=102)  # the dance goes on with 3
    two = TwoLevelMirror(lower, routines)
    nearest = [lower.nearest_pattern(two.step(u).lower.pb)[0] for u in scenario.sensory]
    switch = scenario.switch_steps[0]
    assert all(p == "2" for p in nearest[switch + 15 :])


def test_the_file_round_trips_and_is_refused_for_another_lower_model(lower, routines, tmp_path):
    path = tmp_path / "routines.npz"
    routines.save(path)
    loaded = RoutineModel.load(path, lower)
    assert loaded.routines == ("dance", "wave")
    for name in loaded.routines:
        assert np.array_equal(loaded.routine_pb[name], routines.routine_pb[name])
    assert loaded.lower_fingerprint == lower.fingerprint
    assert loaded.segments == routines.segments
    params = lower.params._replace(b_h=np.asarray(lower.params.b_h) + 0.01)
    other = dataclasses.replace(lower, params=params)
    with pytest.raises(ModelFileError, match="learned over another lower model"):
        RoutineModel.load(path, other)
    with pytest.raises(ModelFileError, match="another lower model"):
        TwoLevelMirror(other, loaded)
    # A file whose numbers are not finite is refused, not half-used.
    bad = dataclasses.replace(loaded, recognition_error=float("nan"))
    bad.save(tmp_path / "bad.npz")
    with pytest.raises(ModelFileError, match="must be finite"):
        RoutineModel.load(tmp_path / "bad.npz")
    # A model file is not a routine file.
    with pytest.raises(ModelFileError, match=str(SHIPPED_MODEL.name)):
        RoutineModel.load(SHIPPED_MODEL)


def test_a_routine_is_performed_alone_top_down(lower, routines):
    pbs, hands, motor = generate_routine(lower, routines, "dance", 100)
    assert hands.shape == (100, 4) and motor.shape == (100, 8)
    order = [lower.nearest_pattern(pb)[0] for pb in pbs]
    parts = [p for i, p in enumerate(order) if i == 0 or p != order[i - 1]]
    assert parts[:3] == ["1", "3", "2"]
    with pytest.raises(ConfigError, match="unknown routine"):
        generate_routine(lower, routines, "salsa", 10)


def test_interact_records_the_routine_and_what_it_anticipates(routines, tmp_path, capsys):
    from rnnpb.cli import main
    from rnnpb.interaction import read_session

    path = tmp_path / "routines.npz"
    routines.save(path)
    out = tmp_path / "run"
    argv = ["interact", "--source", "scenario:routine:1*3,3*2", "--routines", str(path),
            "--robot", "kinematic", "--no-progress", "--out", str(out)]  # fmt: skip
    assert main(argv) == 0
    session = read_session(out / "session.csv")
    said = list(session["routine"])
    assert said[30] == "dance" and session["anticipated"][30] == "3"
    # Routines learned over another model: one line, exit status 2.
    other = tmp_path / "other.npz"
    model = TrainedModel.load(SHIPPED_MODEL)
    params = model.params._replace(b_h=np.asarray(model.params.b_h) + 0.01)
    dataclasses.replace(model, params=params).save(other)
    argv = ["interact", "--model", str(other), *argv[1:-1], str(tmp_path / "run2")]
    assert main(argv) == 2
    assert "learned over another lower model" in capsys.readouterr().err


def test_train_routines_refuses_a_recording_of_one_movement(tmp_path, capsys):
    from rnnpb.cli import main

    record = ["record", "scenario:held:1", "--steps", "40", "--cut", "whole",
              "--pattern", "still", "--out", str(tmp_path / "one")]  # fmt: skip
    assert main(record) == 0
    argv = ["train-routines", "--model", str(SHIPPED_MODEL), "--data", str(tmp_path / "one"),
            "--out", str(tmp_path / "r.npz")]  # fmt: skip
    assert main(argv) == 2
    assert "a routine needs at least two movements" in capsys.readouterr().err
    assert not (tmp_path / "r.npz").exists()
