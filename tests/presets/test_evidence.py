"""Each preset value's evidence: the harnesses named exist and run, `rnnpb presets evidence`
shows them, and `--check` holds a harness's figures to what its source expects."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from rnnpb.cli import main
from rnnpb.presets import KINDS, PRESET_NAMES, Source, load_preset
from rnnpb.presets import evidence as evidence_module
from rnnpb.presets.evidence import CheckResult, FigureCheck, check, checkout, evidence_rows

ROOT = Path(__file__).resolve().parents[2]


def _harnesses() -> dict[str, list[str]]:
    """Every harness a preset's evidence names, with the sources that name it."""
    named: dict[str, list[str]] = {}
    for name in PRESET_NAMES:
        for source in load_preset(name).sources.values():
            if source.command:
                named.setdefault(source.harness, []).append(f"{name}:{source.id}")
    return named


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(ROOT / "src"), "MPLBACKEND": "Agg"}


def test_every_harness_named_exists_and_parses_its_arguments():
    harnesses = _harnesses()
    assert harnesses, "no source names a harness"
    missing = {h: s for h, s in harnesses.items() if not (ROOT / h).is_file()}
    assert not missing, f"harnesses named by the presets that the repository lacks: {missing}"
    # Every --help at once: each is a process of its own.
    running = {
        harness: subprocess.Popen(
            [sys.executable, harness, "--help"],
            cwd=ROOT,
            env=_env(),
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for harness in harnesses
    }
    for harness, process in running.items():
        out, err = process.communicate(timeout=120)
        assert process.returncode == 0, f"{harness} --help: {err.strip().splitlines()[-1:]}"
        assert "usage:" in out, harness


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_a_measured_value_names_a_harness_of_the_checkout(name):
    for source in load_preset(name).sources.values():
        if source.kind == "measured":
            assert source.harness.split("/")[0] in ("benchmarks", "tools"), source.id
            assert source.command and source.figure, source.id
        if source.expect:
            assert "JSON" in source.command.split(), source.id


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_the_evidence_command_shows_every_value_and_its_kind(name, tmp_path, capsys):
    out_file = tmp_path / "evidence.json"
    assert main(["presets", "evidence", name, "--json", str(out_file)]) == 0
    shown = capsys.readouterr().out
    preset = load_preset(name)
    rows = evidence_rows(preset)
    assert len(rows) == sum(len(preset.section(s)) for s in preset.sections)
    assert "[online] surprise_gate" in shown and "values by kind: paper" in shown
    data = json.loads(out_file.read_text(encoding="utf-8"))
    assert len(data["values"]) == len(rows)
    assert sum(data["counts"].values()) == len(rows) and set(data["counts"]) == set(KINDS)
    window = next(v for v in data["values"] if (v["section"], v["key"]) == ("online", "window"))
    assert window["kind"] == "paper" and data["sources"][window["source"]]["command"] == ""
    # Every measured source shows the command that repeats it.
    for source_id, source in data["sources"].items():
        if source["kind"] == "measured":
            assert f"    command: {source['command']}" in shown, source_id


@pytest.mark.slow
def test_the_cheapest_harness_gives_the_figures_its_source_expects(capsys):
    """The fast preset's learning (a few seconds): run again, its errors are the expected."""
    assert checkout() == ROOT
    source = load_preset("fast").sources["fast-learning"]
    assert source.cost == "cheap" and source.expect
    status = main(["presets", "evidence", "--check", "--source", "fast-learning", "fast"])
    out = capsys.readouterr().out
    assert status == 0, out
    assert "fast-learning: held" in out


def test_a_figure_that_differs_fails_the_check_naming_its_source(monkeypatch, capsys):
    def differing(source, root, timeout=0):
        figure = FigureCheck("shapes_max", 0.244, 0.3, False)
        return CheckResult(source.id, (figure,), "", 0.1)

    monkeypatch.setattr(evidence_module, "check", differing)
    assert main(["presets", "evidence", "--check", "paper"]) == 1
    captured = capsys.readouterr()
    assert "structure-periods: DIFFERS" in captured.out
    assert "expected 0.244" in captured.out
    assert "differs from what it expects: structure-periods" in captured.err


@pytest.mark.slow
def test_check_compares_the_harness_s_json_with_the_expectation():
    """A real run of a model-free harness on one short draw, held to a figure it gives, to
    one it gives otherwise and to one it does not give."""
    command = "python tools/structure_periods.py --draws 0 --steps 120 --json JSON"
    expect = {"draws": [0], "lags": [5, 41], "a/b": 1.0}
    source = Source("short", command, (0,), "f", "", "measured", "cheap", expect, 0.5)
    result = check(source, ROOT)
    assert not result.error
    assert [f.held for f in result.figures] == [True, False, False]
    assert result.figures[1].got == [5, 40] and result.figures[2].got is None
    assert "DIFFERS" in result.describe(0.5) and "none given" in result.describe(0.5)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--check", "--source", "nowhere", "fast"], "no measured source 'nowhere'"),
        (["--check", "--source", "paper", "fast"], "no measured source 'paper'"),
        (["--source", "fast-learning", "fast"], "--source goes with --check"),
    ],
)
def test_a_bad_request_is_one_line(args, message, capsys):
    assert main(["presets", "evidence", *args]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
