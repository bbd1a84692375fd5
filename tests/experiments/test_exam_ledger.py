"""The exam ledger: every exam run is written in it, a judged version is never run again, and
the runs recorded from the notes name their notes and hold their exams' fingerprints."""

from __future__ import annotations

import json
import types
from pathlib import Path

import pytest

from rnnpb.cli import main
from rnnpb.errors import ConfigError
from rnnpb.experiments.exams import exam_names, load_exam, recorded_versions
from rnnpb.experiments.exams import ledger as exam_ledger
from rnnpb.experiments.studies import StudyOutcome
from rnnpb.experiments.summary import Target

ROOT = Path(__file__).resolve().parents[2]
LEDGER = ROOT / "src" / "rnnpb" / "experiments" / "exams" / "ledger.jsonl"


def _fake_study(monkeypatch, run):
    """``rnnpb study dyad`` with ``run`` in place of the study: the ledger's part of an exam
    run without the study's minutes, with the ledger given by ``--ledger`` the only one read
    (the package's holds the dyad exam's judged run)."""
    fake = types.SimpleNamespace(run=run, judge_results=lambda results, exam: {})
    monkeypatch.setattr("rnnpb.experiments.studies.load_study", lambda name: fake)
    monkeypatch.setattr(exam_ledger, "packaged_ledger", lambda: None)


def _dyad_targets(met: bool = True) -> dict[str, Target]:
    return {
        "robots_lock_from_random_starts": Target(met, "19/20 within 60 steps", 0.95),
        "phase_diagram_both_regimes": Target(met, "2 holding, 3 shifting", 2),
        "subject_finds_all": Target(met, "11/12 sessions", float("nan")),
    }


def _entry(**changes) -> exam_ledger.LedgerEntry:
    exam = load_exam("dyad")
    values = {
        "run": "r1",
        "study": "dyad",
        "version": exam.version,
        "fingerprint": exam.fingerprint,
        "status": "judged",
        "recorded": "run",
        "date": "2026-12-07T10:00:00Z",
        "commit": "abc",
        "dirty": False,
        "rnnpb": "0.1.0",
        "processor": "cpu",
        "draws": exam_ledger.exam_draws(exam),
    }
    return exam_ledger.LedgerEntry(**(values | changes))


def test_the_committed_ledger_reads_and_names_where_each_run_comes_from():
    entries = exam_ledger.read(LEDGER)
    assert entries, "the ledger holds the runs the notes report"
    assert len({e.run for e in entries}) == len(entries)
    recorded = recorded_versions()
    for entry in entries:
        assert entry.status in exam_ledger.STATUSES
        if entry.study in exam_names():
            # The version judged is the one versions.toml records, with the same values.
            assert recorded[entry.study, entry.version].fingerprint == entry.fingerprint, entry.run
        if entry.recorded == "notes":
            source = ROOT / entry.source.split(" ")[0]
            assert source.is_file(), (entry.run, entry.source)
        if entry.study in exam_names() and entry.version == load_exam(entry.study).version:
            # Each target recorded is one the exam defines (an older version's may differ).
            assert {t.name for t in entry.targets} <= set(load_exam(entry.study).targets)
    # The runs the notes report, as the ledger holds them.
    assert exam_ledger.judged_versions("people", [LEDGER]) >= {1}
    people = [e for e in entries if e.study == "people" and e.version == 1]
    (recognised,) = [t for t in people[0].targets if t.name == "followed_recognised"]
    assert recognised.value == pytest.approx(0.376) and recognised.met is False
    # Since runs are written by --exam, no version is judged twice (the notes' runs predate it).
    judged = [(e.study, e.version) for e in entries if e.judged and e.recorded == "run"]
    assert len(judged) == len(set(judged)), judged


def test_the_ledger_is_installed_with_the_package():
    import tomllib

    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    data = pyproject["tool"]["setuptools"]["package-data"]["rnnpb"]
    assert "experiments/exams/*.jsonl" in data and "experiments/exams/*.toml" in data
    assert exam_ledger.packaged_ledger() is not None


def test_a_judged_version_is_refused_and_a_stopped_one_needs_the_override(tmp_path):
    exam = load_exam("dyad")
    path = tmp_path / "ledger.jsonl"
    assert exam_ledger.check_may_run(exam, [path]) == ()
    with pytest.raises(ConfigError, match="no earlier run to follow"):
        exam_ledger.check_may_run(exam, [path], rerun_unjudged=True)
    exam_ledger.append(_entry(run="r1", status="failed", error="ConfigError: x"), path)
    with pytest.raises(ConfigError, match="never judged .*--rerun-unjudged"):
        exam_ledger.check_may_run(exam, [path])
    assert exam_ledger.check_may_run(exam, [path], rerun_unjudged=True) == ("r1",)
    exam_ledger.append(_entry(run="r2"), path)
    for rerun in (False, True):
        with pytest.raises(ConfigError, match="judged already .*make a new version"):
            exam_ledger.check_may_run(exam, [path], rerun_unjudged=rerun)
    assert exam_ledger.judged_versions("dyad", [path]) == {exam.version}
    with pytest.raises(ConfigError, match="holds run r2 already"):
        exam_ledger.append(_entry(run="r2"), path)


def test_an_exam_run_is_written_when_it_starts_and_when_it_is_judged(tmp_path, monkeypatch, capsys):
    path = tmp_path / "ledger.jsonl"
    seen = []

    def run(out, options):
        # While the study runs, its start is in the ledger.
        (entry,) = exam_ledger.read(path)
        seen.append(entry.status)
        assert options.exam.study == "dyad"
        return StudyOutcome(12.0, _dyad_targets())

    _fake_study(monkeypatch, run)
    out = tmp_path / "out"
    assert main(["study", "dyad", "--exam", "--ledger", str(path), "--out", str(out)]) == 0
    assert seen == ["running"]
    (entry,) = exam_ledger.read(path)
    exam = load_exam("dyad")
    assert (entry.study, entry.version, entry.fingerprint) == ("dyad", 2, exam.fingerprint)
    assert entry.status == "judged" and entry.recorded == "run"
    assert entry.out == str(out.resolve()) and entry.finished
    assert entry.commit and isinstance(entry.dirty, bool) and entry.processor
    assert entry.draws == exam_ledger.exam_draws(exam) and entry.seeds() == exam.draws()
    assert [(t.name, t.met, t.value) for t in entry.targets] == [
        ("robots_lock_from_random_starts", True, 0.95),
        ("phase_diagram_both_regimes", True, 2),
        ("subject_finds_all", True, None),  # a figure that could not be taken
    ]
    assert f"as run {entry.run}" in capsys.readouterr().out
    # The same version again: one line, exit status 2.
    assert main(["study", "dyad", "--exam", "--ledger", str(path), "--out", str(out)]) == 2
    error = capsys.readouterr().err
    assert error.startswith("rnnpb: error: the dyad exam's version 2 was judged already")
    assert error.count("\n") == 1 and "fresh draws" in error
    assert len(exam_ledger.read(path)) == 1


def test_a_run_that_stops_is_written_as_failed_and_rerun_only_when_asked(
    tmp_path, monkeypatch, capsys
):
    path = tmp_path / "ledger.jsonl"

    def crash(out, options):
        raise ConfigError("no model set1.npz in DIR")

    _fake_study(monkeypatch, crash)
    args = ["study", "dyad", "--exam", "--ledger", str(path), "--out", str(tmp_path / "o")]
    assert main(args) == 2
    (failed,) = exam_ledger.read(path)
    assert failed.status == "failed" and failed.targets == ()
    assert failed.error == "ConfigError: no model set1.npz in DIR"
    capsys.readouterr()
    assert main(args) == 2
    assert "--rerun-unjudged" in capsys.readouterr().err
    _fake_study(monkeypatch, lambda out, options: StudyOutcome(1.0, _dyad_targets(False)))
    assert main([*args, "--rerun-unjudged"]) == 0
    first, second = exam_ledger.read(path)
    assert first == failed
    assert second.status == "judged" and second.retry_of == (failed.run,)
    assert not any(t.met for t in second.targets)


def test_an_installed_rnnpb_runs_no_exam_without_a_ledger(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(exam_ledger, "checkout_ledger", lambda: None)
    _fake_study(monkeypatch, lambda out, options: pytest.fail("the study must not start"))
    assert main(["study", "dyad", "--exam", "--out", str(tmp_path / "o")]) == 2
    assert "give --ledger FILE" in capsys.readouterr().err
    assert main(["study", "dyad", "--ledger", str(tmp_path / "l"), "--out", "o"]) == 2
    assert "go with --exam" in capsys.readouterr().err


def test_an_exam_whose_values_changed_under_its_version_is_refused(tmp_path, monkeypatch):
    from dataclasses import replace

    changed = replace(load_exam("dyad"), fingerprint="0000000000000000")
    with pytest.raises(ConfigError, match="values changed under version 2"):
        with exam_ledger.exam_run(changed, tmp_path / "o", tmp_path / "ledger.jsonl"):
            pytest.fail("the run must not start")
    assert not (tmp_path / "ledger.jsonl").exists()


def test_a_malformed_ledger_line_names_the_file_and_line(tmp_path):
    path = tmp_path / "ledger.jsonl"
    path.write_text(_entry().line() + "\n{not json\n", encoding="utf-8")
    with pytest.raises(ConfigError, match=r"ledger.jsonl, line 2: not JSON"):
        exam_ledger.read(path)
    path.write_text(json.dumps({"run": "x"}) + "\n", encoding="utf-8")
    with pytest.raises(ConfigError, match=r"line 1: not a ledger entry"):
        exam_ledger.read(path)


def test_a_target_keeps_its_figure_in_results_json():
    assert Target(True, "3/4", 0.75).to_json() == {"met": True, "detail": "3/4", "value": 0.75}
    assert "value" not in Target(False, "none", float("nan")).to_json()
    assert Target(False, "none", float("nan")) == Target(False, "none", float("nan"))
    assert Target(True, "2/2 within 10").to_json() == {"met": True, "detail": "2/2 within 10"}
