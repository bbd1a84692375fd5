"""The studies' exams: every study has one, each loads, a malformed one is one clear line."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import pytest

from rnnpb.errors import ConfigError
from rnnpb.experiments.exams import exam_names, load_exam, parse_exam
from rnnpb.experiments.studies import study_names

ROOT = Path(__file__).resolve().parents[2]


def _exam(**changes):
    data = {
        "exam": {"study": "s", "version": 1},
        "draws": {"user": [7000, 7001], "shapes": ["one-arm"]},
        "excluded": [{"first": 0, "last": 5, "why": "chosen on them"}],
        "targets": {
            "share": {"counts": "a share", "compare": ">=", "limit": 0.9},
            "count": {
                "counts": "a count",
                "compare": "<=",
                "limit": 0,
                "parameters": {"steps": 60},
            },
        },
    }
    data.update(changes)
    return data


def test_every_study_has_an_exam_that_loads():
    assert set(exam_names()) == set(study_names())
    for name in study_names():
        exam = load_exam(name)
        assert exam.study == name and exam.version >= 1 and exam.targets
        assert exam.excluded, f"the {name} exam names no draws used before"
        for target in exam.targets.values():
            assert target.counts and target.compare in (">=", "<=")


def test_exam_files_are_installed_with_the_package():
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    assert "experiments/exams/*.toml" in pyproject["tool"]["setuptools"]["package-data"]["rnnpb"]


def test_the_judge_reads_the_definition():
    exam = parse_exam(_exam())
    assert exam.draws() == {7000, 7001} and exam.shapes == ("one-arm",)
    assert exam.target("count").parameter("steps") == 60
    assert "`s` version 1" in exam.describe() and "user 7000, 7001" in exam.describe()
    assert exam.judge({"share": 0.9, "count": 0}) == {"share": True, "count": True}
    assert exam.judge({"share": 0.89, "count": 1}) == {"share": False, "count": False}
    # A measure that could not be taken is not met.
    assert exam.judge({"share": math.nan, "count": None}) == {"share": False, "count": False}
    with pytest.raises(ConfigError, match="not measured"):
        exam.judge({"share": 1.0})
    # Draws named by text (styles of a recording, takes …) besides the seeds.
    named = parse_exam(_exam(draws={"user": [7000], "styles": ["active", "elderly"]}))
    assert named.name_list("styles") == ("active", "elderly") and named.draws() == {7000}
    assert "styles active, elderly" in named.describe()
    assert named.to_json()["names"] == {"styles": ["active", "elderly"]}
    with pytest.raises(ConfigError, match="names no 'takes' draws"):
        named.name_list("takes")


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"exam": {"study": "s"}}, r"\[exam\]: missing \['version'\]"),
        ({"exam": {"study": "s", "version": 0}}, "version must be >= 1"),
        ({"draws": {"user": [1.5]}}, "draws.user must be a whole number"),
        ({"draws": {"shapes": ["one-arm"]}}, "names no seeds"),
        ({"draws": {"user": [3]}}, r"draws \[3\] are excluded"),
        ({"excluded": [{"first": 9, "last": 2, "why": "x"}]}, "last 2 is before first 9"),
        (
            {"targets": {"t": {"counts": "c", "compare": ">", "limit": 1}}},
            "targets.t.compare must be one of",
        ),
        ({"targets": {"t": {"counts": "c", "compare": ">="}}}, r"missing \['limit'\]"),
        ({"targets": {"t": {"counts": "c", "compare": ">=", "limit": "x"}}}, "finite number"),
        ({"targets": {}}, "defines no target"),
        ({"extra": 1}, r"unknown key\(s\) \['extra'\]"),
    ],
)
def test_a_malformed_exam_is_one_clear_line(changes, message):
    with pytest.raises(ConfigError, match=message) as error:
        parse_exam(_exam(**changes))
    assert "\n" not in str(error.value)


def test_an_unknown_exam_names_the_known_ones():
    with pytest.raises(ConfigError, match="no exam for study 'nothing' \\(exams: dyad"):
        load_exam("nothing")


def test_no_preset_chose_a_setting_on_an_exam_draw():
    """Neither the exams' draws of today nor those of any study's run the exam ledger holds
    (older versions too) are among a preset evidence's draws (scenario and learning seeds;
    the mirror game's judged draws in the ledger seed a browser's pointer player instead)."""
    from rnnpb.experiments.exams import ledger
    from rnnpb.presets import PRESET_NAMES, load_preset

    exams = {name: load_exam(name).draws() for name in exam_names()}
    for entry in ledger.entries():
        if entry.study not in exam_names():
            continue
        key = f"{entry.study} version {entry.version} (ledger)"
        exams[key] = exams.get(key, frozenset()) | entry.seeds()
    assert any(key.endswith("(ledger)") and draws for key, draws in exams.items())
    for preset_name in PRESET_NAMES:
        preset = load_preset(preset_name)
        assert preset.sources, f"preset {preset_name} names no evidence"
        for source in preset.sources.values():
            for study, draws in exams.items():
                shared = sorted(draws & set(source.draws))
                assert not shared, (
                    f"preset {preset_name}'s evidence {source.id!r} was chosen on draws "
                    f"{shared} of the {study} exam"
                )
