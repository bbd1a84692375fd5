"""`rnnpb study safety`: its seeds, its judge by the exam's definitions, and models it cannot
find (the study's runs themselves are tested in tests/safety/test_online.py)."""

from __future__ import annotations

import math

from rnnpb.cli import main
from rnnpb.experiments.exams import load_exam, parse_exam
from rnnpb.experiments.scenarios.safety import USERS, SafetySeeds, roc_auc
from rnnpb.experiments.studies import load_study, takes_exam


def _results(steered=5, prevented=(2, 2), inhibited=0, sent=0, lock=3, risk_auc=0.97):
    learned = {
        "everything": {
            "lock": {"1": 2, "2": lock, "3": 4},
            "switch": {"1->2": 3, "2->1": 5},
            "recognised": {"1": "1", "2": "2", "3": "3"},
        },
        "unguarded": {
            "lock": {"1": 2, "2": 2, "3": 2},
            "switch": {"1->2": 3, "2->1": 3},
            "recognised": {"1": "1", "2": "2", "3": "3"},
        },
    }
    totals = {
        "steer_unguarded": 100,
        "steer_steered": steered,
        "inhibit_cases": prevented[1],
        "inhibit_prevented": prevented[0],
        "learned_steps": 900,
        "learned_inhibited": inhibited,
        "sent_unsafe": sent,
        "sent_judged_unsafe": sent,
    }
    return {
        "sets": {
            "1": {
                "learned": learned,
                "totals": totals,
                "prediction": {"risk_auc": risk_auc},
                "familiarity": {"familiarity_auc": 0.93},
            }
        }
    }


def test_the_seeds_of_a_first_seed_and_of_the_exam():
    seeds = SafetySeeds.from_first(3)
    assert seeds.model == 3 and seeds.learned == 7
    assert seeds.map_users == tuple(range(3, 3 + len(USERS)))
    assert seeds.users == tuple(range(1003, 1003 + len(USERS)))
    exam = load_exam("safety")
    assert exam.version == 4
    from_exam = SafetySeeds.from_exam(exam)
    assert from_exam.users == exam.seed_list("users") and from_exam.model == 14200
    development = SafetySeeds.from_first(0)
    used = {
        development.model,
        development.learned,
        development.held_out,
        development.unknown,
        *development.map_users,
        *development.users,
    }
    exam_draws = {
        from_exam.model,
        from_exam.learned,
        from_exam.held_out,
        from_exam.unknown,
        *from_exam.map_users,
        *from_exam.users,
    }
    assert not used & exam_draws


def test_the_judge_reads_the_exams_definitions():
    study = load_study("safety")
    assert takes_exam(study)
    exam = load_exam("safety")
    targets = study.judge_results(_results(), exam)
    assert list(targets) == list(exam.targets)
    assert all(t.met for t in targets.values())
    assert "95.0 % removed" in targets[study.STEERS].detail
    bad = study.judge_results(
        _results(steered=20, prevented=(1, 2), inhibited=10, sent=1, lock=11, risk_auc=0.9), exam
    )
    assert [t.met for t in bad.values()] == [False, True, False, False, False, False, False]
    # No case of inhibition: undefined, so not met.
    none = study.judge_results(_results(prevented=(0, 0)), exam)
    assert not none[study.INHIBITS].met and "no case arose" in none[study.INHIBITS].detail


def test_a_changed_definition_changes_the_verdict():
    exam = load_exam("safety")
    study = load_study("safety")
    data = {
        "exam": {"study": "safety", "version": 5},
        "draws": {k: list(v) for k, v in exam.seeds.items()},
        "targets": {
            name: {
                "counts": t.counts,
                "compare": t.compare,
                "limit": 0.25 if name == study.STEERS else t.limit,
                "parameters": dict(t.parameters),
            }
            for name, t in exam.targets.items()
        },
    }
    targets = study.judge_results(_results(steered=20), parse_exam(data))
    assert targets[study.STEERS].met
    assert not study.judge_results(_results(steered=20), exam)[study.STEERS].met


def test_roc_auc_counts_ties_half_and_is_undefined_for_one_class():
    assert roc_auc([0.1, 0.4, 0.35, 0.8], [False, False, True, True]) == 0.75
    assert roc_auc([0.5, 0.5], [True, False]) == 0.5
    assert math.isnan(roc_auc([0.1, 0.2], [True, True]))


def test_models_it_cannot_find_are_named_in_one_line(tmp_path, capsys):
    out = str(tmp_path / "out")
    assert main(["study", "safety", "--quick", "--models", str(tmp_path), "--out", out]) == 2
    error = capsys.readouterr().err.strip()
    assert error.startswith("rnnpb: error:") and "\n" not in error
    assert f"{tmp_path}: no model set1.npz for learning set 1" in error


def test_the_unsafe_pattern_user_performs_the_most_often_unsafe_pbs(monkeypatch):
    # A model no PB of which is unsafe from every start still gives the unsafe-pattern user
    # the PBs unsafe from the most starts; one whose generation is never unsafe is refused.
    import numpy as np
    import pytest

    import rnnpb.safety as safety
    from rnnpb.errors import ConfigError
    from rnnpb.experiments.scenarios import safety as scenario

    pbs = np.array([[0.1, 0.1], [0.9, 0.9], [0.5, 0.5]])
    chosen: list[np.ndarray] = []

    class Found:
        pb = pbs
        share = np.array([0.0, 0.5, 0.0])

    def generate(model, pb, contexts, inputs, n, sensory):
        chosen.append(pb)
        return np.full((n, 1, 4), 0.25)

    monkeypatch.setattr(safety, "explore", lambda model, config: Found)
    monkeypatch.setattr(safety, "sample_starts", lambda model, n, config, rng: (None, None))
    monkeypatch.setattr(safety, "generate_from", generate)
    hands = scenario._unsafe_pattern(object(), 150, seed=3, each=100)
    assert hands.shape == (150, 4) and len(chosen) == 2
    assert all(np.array_equal(pb, pbs[1:2]) for pb in chosen)
    Found.share = np.zeros(3)
    with pytest.raises(ConfigError, match="no PB of the model generates unsafe movement"):
        scenario._unsafe_pattern(object(), 150, seed=3)


def test_a_model_that_generates_nothing_unsafe_has_no_unsafe_pattern_user(monkeypatch, capsys):
    import numpy as np

    from rnnpb.experiments.scenarios import safety as scenario

    def stream(kind, n_steps, seed, learning_set, patterns=(), model=None):
        if kind == "unsafe_pattern":
            raise scenario.NoUnsafeMovement("no PB of the model generates unsafe movement")
        return np.full((n_steps, 4), 0.5)

    class Model:
        patterns = ("1",)

    class Config:
        steps = 5

    monkeypatch.setattr(scenario, "user_stream", stream)
    monkeypatch.setattr(scenario, "_pattern_stream", lambda p, n, s: np.full((n, 4), 0.5))
    monkeypatch.setattr(Config, "learned_steps", 5, raising=False)
    streams = scenario._streams(Model(), Config(), range(len(USERS)), 7, "1")
    assert "unsafe_pattern" not in streams and set(USERS) - {"unsafe_pattern"} <= set(streams)
    assert "no unsafe_pattern user" in capsys.readouterr().err


def test_commands_sent_are_judged_by_mujoco_s_contacts_the_servo_and_the_mjcf_ranges():
    import numpy as np

    from rnnpb.experiments.scenarios.safety import judged_commands
    from rnnpb.robot import ELBOW_AT_ZERO_PITCH

    rest = np.array([0.0, 0.0, 0.0, ELBOW_AT_ZERO_PITCH] * 2)
    fast = rest.copy()
    fast[0] += 1.0  # a shoulder turned 1 rad in one 0.4 s step: the servo turns about 2.5
    outside = fast.copy()
    outside[3] = 50.0  # an elbow far beyond its range, reached by a jump
    reasons = judged_commands(np.array([rest, fast, fast, outside]), rest, 0.4)
    assert reasons[:3] == ["", "", ""]
    assert "limits" in reasons[3] and "speed" in reasons[3]
    assert "speed" in judged_commands(np.array([fast]), rest, 0.1)[0]
    assert judged_commands(np.zeros((0, 8)), rest, 0.4) == []
