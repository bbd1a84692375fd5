"""The routines study: its measures count what the runs did, and its quick form writes a
report with its sections and a results file the exam's judge reads."""

from __future__ import annotations

import json

import numpy as np

from rnnpb.experiments.exams import load_exam
from rnnpb.experiments.scenarios.routines import RoutineRun, measure
from rnnpb.experiments.studies import StudyOptions, load_study, study_names
from rnnpb.experiments.studies.routines import judge, judge_results

EXAM = load_exam("routines")


def _run(kind, nearest, labels, switches, said=None, prior=True, routine="A"):
    n = len(labels)
    return RoutineRun(
        kind=kind,
        routine=routine,
        seed=0,
        prior=prior,
        switches=tuple(switches),
        labels=tuple(labels),
        lower_pb=np.zeros((n, 4)),
        higher_pb=np.zeros((n, 2)),
        said=tuple(said or [None] * n),
        nearest=tuple(nearest),
    )


def test_the_measures_count_what_each_run_did():
    labels = ["1"] * 10 + ["3"] * 10
    on_time = _run("learned", ["1"] * 10 + ["3"] * 10, labels, [10], said=["A"] * 20)
    late = _run("learned", ["1"] * 14 + ["3"] * 6, labels, [10], prior=False)
    assert on_time.lags() == [0] and late.lags() == [4]
    never = _run("deviation", ["1"] * 20, labels, [10])
    unlearned = _run("unlearned", labels, labels, [10], said=[None] * 15 + ["B"] * 5)
    m = measure([on_time, late, never, unlearned], within=3, deviation_steps=15, judged_from=10)
    assert m["median_lag_with"] == 0 and m["median_lag_without"] == 4
    assert m["switches_within_with"] == 1.0 and m["switches_within_without"] == 0.0
    assert m["deviation_followed_with"] == 0.0
    assert m["recognised_in_first_segment"] == 1.0
    assert m["unlearned_taken_for_learned"] == 0.5
    verdicts = judge(m, EXAM)
    assert verdicts["median_lag_with"].met and not verdicts["deviation_followed_with"].met
    assert not verdicts["unlearned_taken_for_learned"].met


def test_the_quick_form_writes_its_report_and_results(tmp_path):
    assert "routines" in study_names()
    outcome = load_study("routines").run(tmp_path, StudyOptions(quick=True, workers=1))
    assert set(outcome.targets) == set(EXAM.targets)
    results = json.loads((tmp_path / "results.json").read_text())
    assert judge_results(results, EXAM) == outcome.targets
    assert results["config"]["lower_fingerprint"] and results["versions"]
    report = (tmp_path / "report.md").read_text()
    for section in ("## Targets", "## Switch lag with and without", "## The two levels"):
        assert section in report
    assert (tmp_path / "figures" / "two_levels.png").stat().st_size > 0
