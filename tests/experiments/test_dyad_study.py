"""`rnnpb study dyad`: registered, and clear about the models it needs (the study itself runs
on the paper-learned models of a full demo run, which the suite does not have)."""

from __future__ import annotations

from rnnpb.cli import main
from rnnpb.experiments.studies import load_study, study_names


def test_the_dyad_study_is_registered():
    assert "dyad" in study_names()
    study = load_study("dyad")
    assert study.NAME == "dyad" and "section 4.2" in study.SUMMARY


def test_without_its_models_the_study_says_which_file_it_needs(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("RNNPB_DYAD_MODELS", str(tmp_path / "none"))
    assert main(["study", "dyad", "--quick", "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err.strip()
    assert error.startswith("rnnpb: error:") and "set1.npz" in error
    assert "RNNPB_DYAD_MODELS" in error and "\n" not in error
