"""`rnnpb study novelty`: its measures from stream runs, the judge on measures made here, its
registration, and the quick form end to end (files, report sections, the judge's verdicts from
results.json). Whether the study meets its targets is judged by `rnnpb study novelty --exam`,
not here."""

import numpy as np
import pytest

from rnnpb.experiments.exams import load_exam
from rnnpb.experiments.scenarios.novelty import StreamRun, measure
from rnnpb.experiments.studies import StudyOptions, load_study, study_names
from rnnpb.experiments.studies.novelty import judge, judge_results
from rnnpb.model import TrainConfig

EXAM = load_exam("novelty")
NEW_TARGETS = {"novel_slow_called_novel", "novel_fast_called_novel", "stopped_called_still"}
SETTLE_STEPS = int(EXAM.parameter("settle_steps"))


def _run(kind, movement, novelty, recognised, start=0, score=0.05, confidence=None, speed=1.0):
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
        speed,
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


def test_shapes_at_other_speeds_are_judged_over_the_same_cycles_and_a_stop_after_5_steps():
    start, n = 36, 36 + 4 * SETTLE_STEPS
    # At half speed the steps not judged are twice as many: those before are not counted.
    slow = _run(
        "novel-slow",
        "one-arm",
        ["familiar"] * (start + 2 * SETTLE_STEPS) + ["novel"] * (n - start - 2 * SETTLE_STEPS),
        [None] * n,
        start=start,
        speed=0.5,
    )
    # At twice the speed, from settle_steps: a quarter of the judged steps undecided.
    judged = n - start - SETTLE_STEPS
    fast = _run(
        "novel-fast",
        "one-arm",
        ["familiar"] * (start + SETTLE_STEPS)
        + [""] * (judged // 4)
        + ["novel"] * (judged - judged // 4),
        [None] * n,
        start=start,
        speed=2.0,
    )
    # The hands stop at step 36: 5 steps not judged, then one of 20 still steps missed.
    stop = _run(
        "stopped", "1", ["familiar"] * 41 + ["novel"] + ["still"] * 19, ["1"] * 61, start=36
    )
    m = measure([slow, fast, stop], SETTLE_STEPS, 36)
    assert m["novel_slow_called_novel"] == 1.0
    assert m["novel_fast_called_novel"] == pytest.approx(1 - (judged // 4) / judged)
    assert m["stopped_called_still"] == 19 / 20
    assert m["confusion"]["stopped"]["still"] == 19 and m["confusion"]["novel-slow"]["novel"] > 0
    older = {k: t.limit for k, t in EXAM.targets.items() if k not in NEW_TARGETS}
    targets = judge(m | older)
    assert NEW_TARGETS <= set(targets)
    assert targets["novel_slow_called_novel"].met and targets["stopped_called_still"].met
    assert targets["novel_fast_called_novel"].met == (m["novel_fast_called_novel"] >= 0.8)
    # Measures written before these streams: their targets are left out, not failed.
    assert set(judge(older)) == set(older)


def test_the_study_is_registered():
    assert "novelty" in study_names()
    assert load_study("novelty").NAME == "novelty"


def test_its_own_models_are_learned_under_its_names_and_kept(tmp_path, monkeypatch):
    """With no directory each model is learned on the draw of the seed given, the paper's
    learning or the fast preset, into ``OUT/models`` under the study's own names; a model
    already there is taken as it is."""
    from rnnpb.experiments.scenarios import novelty
    from rnnpb.experiments.scenarios import study_models as shared

    learned = []

    def learn(name, config, path, seed):
        learned.append((name, config, path.name, seed))
        path.write_bytes(b"")
        return str(path)

    monkeypatch.setattr(shared, "learn_model", learn)
    models = novelty.study_models(tmp_path, None, True, seed=3)
    folder = tmp_path / "models"
    assert models == {
        "fast-1": ("1", folder / "fast_set1.npz"),
        "fast-full": ("full", folder / "fast_full.npz"),
    }
    fast = TrainConfig.fast(seed=3)
    assert learned == [("1", fast, "fast_set1.npz", 3), ("full", fast, "fast_full.npz", 3)]
    learned.clear()
    models = novelty.study_models(tmp_path, None, False, seed=3, learning_sets=("2", "full"))
    assert list(models) == ["2", "full", "fast-full"]  # fast_full.npz is kept
    paper = TrainConfig(seed=3)
    assert learned == [("2", paper, "set2.npz", 3), ("full", paper, "full.npz", 3)]


def test_a_directorys_models_are_named_by_their_learning_set(tmp_path):
    import shutil

    from rnnpb.errors import ConfigError
    from rnnpb.experiments.scenarios import novelty
    from rnnpb.models import SHIPPED_MODEL

    shutil.copyfile(SHIPPED_MODEL, tmp_path / "set1.npz")
    shutil.copyfile(SHIPPED_MODEL, tmp_path / "full_seed0.npz")
    models = novelty.study_models(tmp_path / "out", str(tmp_path), True)
    assert models == {
        "1": ("1", tmp_path / "set1.npz"),
        "full": ("full", tmp_path / "full_seed0.npz"),
    }
    with pytest.raises(ConfigError, match=f"{tmp_path}: no model set2.npz for learning set 2"):
        novelty.study_models(tmp_path / "out", str(tmp_path), False)
    assert not (tmp_path / "out" / "models").exists()  # nothing learned


def test_the_judge_meets_each_target_at_its_limit_and_misses_it_beyond():
    """Every target of the exam, on measures at its limit and one point past it, over all
    models and per regression preset."""
    at_limit = {key: target.limit for key, target in EXAM.targets.items()}
    step = {">=": -0.01, "<=": 0.01}
    past = {key: t.limit + step[t.compare] for key, t in EXAM.targets.items()}
    assert all(t.met for t in judge(at_limit).values())
    assert not any(t.met for t in judge(past).values())
    results = {"overall": at_limit, "per_preset": {"fast": at_limit, "paper": past}}
    judged = judge_results(results, EXAM)
    assert set(judged) == set(EXAM.targets) | {
        f"{preset}: {key}" for preset in ("fast", "paper") for key in EXAM.targets
    }
    assert all(judged[key].met and judged[f"fast: {key}"].met for key in EXAM.targets)
    assert not any(judged[f"paper: {key}"].met for key in EXAM.targets)


def test_the_quick_form_writes_its_results_report_and_verdicts_with_the_taught_hands(tmp_path):
    # Two fast-preset models learned here, one draw of the user, two new shapes: every
    # target judged over all and per model (met or not: the exam judges them).
    import json

    outcome = load_study("novelty").run(tmp_path, StudyOptions(quick=True, workers=1))
    assert set(EXAM.targets) <= set(outcome.targets)
    results = json.loads((tmp_path / "results.json").read_text())
    assert set(results["per_set"]) == {"fast-1", "fast-full"}
    # The exam's judge gives the same verdicts from the finished results.json.
    assert judge_results(results, EXAM) == outcome.targets
    assert all(settings["taught_hands"] for settings in results["config"]["models"].values())
    # Beside it, the same evidence without the taught hands (what they add).
    assert set(results["without_taught_hands"]) == {"fast-1", "fast-full", "all"}
    assert set(results["without_taught_hands"]["all"]) == set(EXAM.targets)
    assert "## What the hands as taught add" in (tmp_path / "report.md").read_text()
