"""`rnnpb study novelty`: its measures from stream runs, and its registration."""

import numpy as np
import pytest

from rnnpb.experiments.exams import load_exam
from rnnpb.experiments.scenarios.novelty import StreamRun, measure
from rnnpb.experiments.studies import StudyOptions, load_study, study_names
from rnnpb.experiments.studies.novelty import judge, judge_results

EXAM = load_exam("novelty")
SETTLE_STEPS = int(EXAM.parameter("settle_steps"))


def _run(kind, movement, novelty, recognised, start=0, score=0.05, confidence=None):
    n = len(novelty)
    return StreamRun(
        "1",
        kind,
        movement,
        0,
        start,
        tuple(novelty),
        tuple(recognised),
        tuple(["1"] * n),
        np.full(n, score),
        np.zeros((n, 4)),
        np.zeros((n, 3)),
        np.zeros((n, 4)),
        tuple(confidence) if confidence is not None else (0.9,) * n,
    )


def test_the_measures_count_what_each_step_said():
    n = SETTLE_STEPS + 20
    learned = _run(
        "learned",
        "1",
        ["familiar"] * n,
        ["1"] * (n - 5) + ["2"] * 5,
        score=0.02,
        confidence=[0.9] * (n - 5) + [0.6] * 5,
    )
    # Called novel 30 steps after it starts, then on every step.
    novel = _run(
        "novel",
        "figure-eight",
        ["familiar"] * 66 + ["novel"] * 30,
        ["1"] * 66 + [None] * 30,
        start=36,
        score=0.08,
    )
    late = _run("novel", "one-arm", ["familiar"] * 96, ["1"] * 96, start=36, score=0.02)
    walk = _run("unstructured", "random-walk", ["unstructured"] * n, [None] * n)
    still = _run("still", "pause", ["still"] * n, [None] * n)
    m = measure([learned, novel, late, walk, still], SETTLE_STEPS, 36)
    assert m["learned_recognised"] == 15 / 20
    assert m["learned_nearest_pb"] == 1.0 and m["learned_called_novel"] == 0.0
    assert m["novel_delay_steps"] == [30, None]
    assert m["novel_within_3_cycles"] == 0.5 and m["novel_after_detection"] == 0.5
    assert m["unstructured_called_novel"] == 0.0 and m["still_called_still"] == 1.0
    assert m["confusion"]["still"]["still"] == 20
    # Confidence where the answer was right and where it was wrong (5 wrong judged steps).
    assert m["confidence_right"] == pytest.approx(0.9)
    assert m["confidence_wrong"] == pytest.approx(0.6)
    assert m["wrong_steps"] == 5
    # Half the judged novel steps score above every learned step, half tie with them.
    assert m["roc_auc"] == 0.75
    targets = judge(m)
    assert not targets["learned_recognised"].met and targets["still_called_still"].met


def test_the_study_is_registered():
    assert "novelty" in study_names()
    assert load_study("novelty").NAME == "novelty"


def test_the_quick_form_meets_every_target_with_the_taught_hands(tmp_path):
    # Two fast-preset models learned here, one draw of the user (seed 1000),
    # two new shapes: the six targets, over all and per model.
    import json

    outcome = load_study("novelty").run(tmp_path, StudyOptions(quick=True, workers=1))
    assert all(target.met for target in outcome.targets.values()), outcome.targets
    results = json.loads((tmp_path / "results.json").read_text())
    assert set(results["per_set"]) == {"fast-1", "fast-full"}
    # The exam's judge gives the same verdicts from the finished results.json.
    assert judge_results(results, EXAM) == outcome.targets
    assert all(settings["taught_hands"] for settings in results["config"]["models"].values())
    # Beside it, the same evidence without the taught hands (what they add).
    assert set(results["without_taught_hands"]) == {"fast-1", "fast-full", "all"}
    assert set(results["without_taught_hands"]["all"]) == set(EXAM.targets)
    assert "## What the hands as taught add" in (tmp_path / "report.md").read_text()
