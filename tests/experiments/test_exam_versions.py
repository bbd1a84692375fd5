"""Exam versions: a value changed without a new version fails here."""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

from rnnpb.errors import ConfigError
from rnnpb.experiments.exams import (
    check_recorded,
    exam_fingerprint,
    exam_names,
    load_exam,
    parse_exam,
    recorded_versions,
)

ROOT = Path(__file__).resolve().parents[2]
EXAMS = ROOT / "src" / "rnnpb" / "experiments" / "exams"


@pytest.mark.parametrize("name", exam_names())
def test_every_exam_version_is_recorded_with_the_fingerprint_of_its_values(name):
    exam = load_exam(name)
    recorded = recorded_versions().get((name, exam.version))
    assert recorded is not None, (
        f"record the {name} exam's version {exam.version} in exams/versions.toml: "
        f'fingerprint = "{exam.fingerprint}"'
    )
    assert recorded.fingerprint == exam.fingerprint, (
        f"the {name} exam's values changed under version {exam.version} (now "
        f"{exam.fingerprint}, recorded {recorded.fingerprint}): make a new version with fresh "
        "draws, its old draws excluded"
    )
    check_recorded(exam)
    # Every earlier version is recorded too, and the versions count up from 1.
    versions = sorted(v for (study, v) in recorded_versions() if study == name)
    assert versions == list(range(1, exam.version + 1))


def test_the_fingerprint_covers_the_values_and_nothing_else():
    text = (EXAMS / "novelty.toml").read_text(encoding="utf-8")
    data = tomllib.loads(text)
    base = exam_fingerprint(data)
    assert parse_exam(data).fingerprint == base
    # Comments, the version, the excluded draws and the order of a table's keys: the same.
    assert exam_fingerprint(tomllib.loads("# a comment\n" + text)) == base
    moved = {**data, "exam": {**data["exam"], "version": 9}, "excluded": []}
    assert exam_fingerprint(moved) == base
    reordered = {**data, "targets": dict(reversed(list(data["targets"].items())))}
    assert exam_fingerprint(reordered) == base
    # A limit, a draw, a parameter, a count written as a float: another fingerprint.
    targets = data["targets"]
    for changed in (
        {
            **data,
            "targets": {
                **targets,
                "still_called_still": {**targets["still_called_still"], "limit": 0.91},
            },
        },
        {**data, "draws": {**data["draws"], "user": [7010, 7012]}},
        {**data, "draws": {**data["draws"], "user": [7011, 7010]}},
        {**data, "parameters": {"settle_steps": 24.0}},
    ):
        assert exam_fingerprint(changed) != base
    with pytest.raises(ConfigError, match="values changed under version 2"):
        check_recorded(parse_exam({**data, "draws": {**data["draws"], "user": [7012, 7013]}}))
    with pytest.raises(ConfigError, match="not recorded"):
        check_recorded(parse_exam({**data, "exam": {"study": "novelty", "version": 99}}))


def test_the_versions_file_is_no_exam():
    assert "versions" not in exam_names()
