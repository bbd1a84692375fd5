"""`rnnpb study safety`: its seeds, its judge by the exam's definitions, and models it cannot
find (the study's runs themselves are tested in tests/safety/test_online.py)."""

from __future__ import annotations

from rnnpb.cli import main
from rnnpb.experiments.exams import load_exam, parse_exam
from rnnpb.experiments.scenarios.safety import USERS, SafetySeeds
from rnnpb.experiments.studies import load_study, takes_exam


def _results(generated=(100, 5, 30), sent=0, lock=3, recognised_on=("1", "2", "3")):
    off, barrier, projection = generated
    learned = {
        guard: {
            "lock": {"1": 2, "2": lock, "3": 4},
            "switch": {"1->2": 3, "2->1": 5},
            "recognised": dict(zip(("1", "2", "3"), recognised_on, strict=True)),
        }
        for guard in ("barrier", "projection")
    }
    learned["off"] = {
        "lock": {"1": 2, "2": 2, "3": 2},
        "switch": {"1->2": 3, "2->1": 3},
        "recognised": {"1": "1", "2": "2", "3": "3"},
    }
    return {
        "totals": {
            "sent": sent,
            "generated_off": off,
            "generated_barrier": barrier,
            "generated_projection": projection,
        },
        "sets": {"1": {"learned": learned}},
    }


def test_the_seeds_of_a_first_seed_and_of_the_exam():
    seeds = SafetySeeds.from_first(3)
    assert seeds.model == 3 and seeds.learned == 7
    assert seeds.map_users == tuple(range(3, 3 + len(USERS)))
    assert seeds.users == tuple(range(1003, 1003 + len(USERS)))
    exam = load_exam("safety")
    from_exam = SafetySeeds.from_exam(exam)
    assert from_exam.users == exam.seed_list("users") and from_exam.model == 7100
    assert not {from_exam.model, from_exam.learned, *from_exam.users} & set(
        seeds.map_users + seeds.users
    )


def test_the_judge_reads_the_exams_definitions():
    study = load_study("safety")
    assert takes_exam(study)
    exam = load_exam("safety")
    targets = study.judge_results(_results(), exam)
    assert list(targets) == list(exam.targets)
    verdicts = [t.met for t in targets.values()]
    # Nothing sent; the barrier left 5 of 100 (met), the projection 30 (not); no cost.
    assert verdicts == [True, True, False, True, True]
    assert targets[list(exam.targets)[1]].detail == "unguarded 100, barrier 5 (95.0 % removed)"
    # One lock-on beyond the exam's 10 steps is a cost; a unit sent is a miss.
    late = study.judge_results(_results(sent=1, lock=11), exam)
    assert [t.met for t in late.values()] == [False, True, False, False, False]
    # Nothing to remove: not met (the share is undefined).
    none = study.judge_results(_results(generated=(0, 0, 0)), exam)
    assert not none[list(exam.targets)[1]].met
    assert "(none to remove)" in none[list(exam.targets)[1]].detail


def test_a_changed_definition_changes_the_verdict():
    # The limits are the exam's: with 40 % allowed, the projection's 30 of 100 passes.
    exam = load_exam("safety")
    data = {
        "exam": {"study": "safety", "version": 2},
        "draws": {k: list(v) for k, v in exam.seeds.items()},
        "targets": {
            name: {
                "counts": t.counts,
                "compare": t.compare,
                "limit": 0.4 if "removes" in name else t.limit,
                "parameters": dict(t.parameters),
            }
            for name, t in exam.targets.items()
        },
    }
    targets = load_study("safety").judge_results(_results(), parse_exam(data))
    assert all(t.met for t in targets.values())


def test_models_it_cannot_find_are_named_in_one_line(tmp_path, capsys):
    out = str(tmp_path / "out")
    assert main(["study", "safety", "--quick", "--models", str(tmp_path), "--out", out]) == 2
    error = capsys.readouterr().err.strip()
    assert error.startswith("rnnpb: error:") and "\n" not in error
    assert f"{tmp_path}: no model set1.npz for learning set 1" in error
