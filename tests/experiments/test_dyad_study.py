"""`rnnpb study dyad`: registered, clear about models it cannot find, and its quick form runs on
a fresh clone (it learns its own models) and is judged by its exam."""

from __future__ import annotations

import json

import pytest

from rnnpb.cli import main
from rnnpb.experiments.exams import load_exam
from rnnpb.experiments.studies import StudyOptions, load_study, study_names


def test_the_dyad_study_is_registered():
    assert "dyad" in study_names()
    study = load_study("dyad")
    assert study.NAME == "dyad" and "section 4.2" in study.SUMMARY


def test_models_it_cannot_find_are_named_in_one_line(tmp_path, capsys):
    models = str(tmp_path / "none")
    assert (
        main(["study", "dyad", "--quick", "--models", models, "--out", str(tmp_path / "out")]) == 2
    )
    error = capsys.readouterr().err.strip()
    assert error.startswith("rnnpb: error:") and "\n" not in error
    assert f"{models}: no model set1.npz for learning set 1" in error and "--models" in error


@pytest.mark.slow
def test_the_quick_form_learns_its_models_and_is_judged_by_its_exam(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # no results/ of an earlier demo to lean on
    study = load_study("dyad")
    outcome = study.run(tmp_path / "out", StudyOptions(quick=True, workers=1))
    results = json.loads((tmp_path / "out" / "results.json").read_text())
    assert set(results["config"]["models"]) == {"set1", "set2"}
    assert all((tmp_path / "out" / "models" / f"{name}.npz").is_file() for name in ("set1", "set2"))
    assert len(results["random_starts"]) == 4 and len(results["subject"]) == 1
    assert set(outcome.targets) == set(load_exam("dyad").targets)
    # The exam's judge gives the same verdicts from the finished results.json.
    assert study.judge_results(results, load_exam("dyad")) == outcome.targets
    assert (tmp_path / "out" / "figures" / "phase_diagram.png").is_file()


def test_the_exam_names_its_own_seeds_and_sizes():
    from rnnpb.experiments.scenarios.dyad import DyadSeeds, DyadStudySize

    exam = load_exam("dyad")
    seeds = DyadSeeds.from_exam(exam)
    assert seeds.starts == exam.seed_list("starts") and seeds.training == 7700
    size = seeds.sized(DyadStudySize.for_options(StudyOptions()))
    assert (size.start_seeds, size.grid_seeds, size.subject_seeds) == (5, 3, 12)
    default = DyadSeeds.from_first(size, 0)
    assert not set(default.starts + default.grid + default.subject) & exam.draws()


def test_an_exam_takes_no_seed_and_no_quick_form(tmp_path, capsys):
    out = str(tmp_path / "out")
    assert main(["study", "dyad", "--exam", "--seed", "3", "--out", out]) == 2
    assert "--exam takes no --seed" in capsys.readouterr().err
    assert main(["study", "dyad", "--exam", "--quick", "--out", out]) == 2
    assert "--exam and --quick exclude each other" in capsys.readouterr().err
