"""Bad sweep specs and an unreachable cluster get one clear line."""

import socket
from pathlib import Path

import pytest

from rnnpb import cli
from rnnpb.errors import ConfigError
from rnnpb.model import OnlineConfig, TrainConfig
from rnnpb.sweeps import (
    ClusterError,
    RunRecord,
    RunSpec,
    Setting,
    StudyRunSpec,
    check_address,
    execute_run,
    load_spec,
    read_table,
)

GOOD = """
name = "grid"
learning_sets = ["1", "full"]
seeds = 3
user_draws = [100, 200]
[training.fast]
preset = "fast"
iterations = 500
[training.fast.pb]
integration_length = 10
[online.default]
[online.paper]
preset = "paper"
window = 20
"""


def _spec(tmp_path, text):
    path = tmp_path / "spec.toml"
    path.write_text(text)
    return path


def test_a_good_spec_is_the_whole_grid(tmp_path):
    spec = load_spec(_spec(tmp_path, GOOD))
    runs = spec.runs()
    assert len(runs) == 2 * 3 * 2 * 1 * 2
    assert len({r.run_id for r in runs}) == 24
    fast = spec.training[0].config
    assert fast.iterations == 500 and fast.pb.integration_length == 10
    assert spec.online[1].config.window == 20 and spec.online[1].config.surprise_gate == 0.0
    full = [r for r in runs if r.learning_set == "full"][0]
    assert full.experiments == ("follows",)
    # the same data, training and seed share one cached model, whatever the on-line setting
    keys = {(r.learning_set, r.seed): r.model_key for r in runs}
    assert all(r.model_key == keys[(r.learning_set, r.seed)] for r in runs)
    assert len(set(keys.values())) == 6


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (GOOD + "colour = 1\n", "unknown key 'colour'"),
        (GOOD.replace("seeds = 3", "seeds = []"), "the grid is empty: 'seeds' has no values"),
        (
            GOOD.replace('learning_sets = ["1", "full"]', "learning_sets = []"),
            "the grid is empty: give 'learning_sets' or 'studies'",
        ),
        ('learning_sets = ["1"]\nseeds = 1\n', "the grid is empty: 'training'"),
        (
            GOOD.replace("iterations = 500", "iteration = 500"),
            "[training.fast]: unknown key 'iteration'",
        ),
        (GOOD.replace('preset = "paper"', 'preset = "fastest"'), "preset 'fastest' is not one of"),
        (GOOD.replace('"full"]', '"7"]'), "learning set '7' is not one of"),
        ("seeds = [", "not TOML"),
    ],
)
def test_bad_specs_get_one_line(tmp_path, capsys, text, message):
    path = _spec(tmp_path, text)
    with pytest.raises(ConfigError, match="sweep spec .*spec.toml: ") as caught:
        load_spec(path)
    assert message in str(caught.value) and "\n" not in str(caught.value)
    assert cli.main(["sweep", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("rnnpb: error: sweep spec") and message in err and "\n" not in err
    assert not (tmp_path / "out").exists()


def test_an_unreachable_address_is_one_line_and_quick(tmp_path, capsys):
    with socket.socket() as free:  # a port nothing listens on
        free.bind(("127.0.0.1", 0))
        port = free.getsockname()[1]
    with pytest.raises(ClusterError, match=f"cannot reach a Ray cluster at 127.0.0.1:{port}"):
        check_address(f"127.0.0.1:{port}")
    with pytest.raises(ClusterError, match="is not HOST:PORT"):
        check_address("nowhere")
    path = _spec(tmp_path, GOOD)
    assert (
        cli.main(
            [
                "sweep",
                str(path),
                "--out",
                str(tmp_path / "out"),
                "--address",
                f"ray://127.0.0.1:{port}",
            ]
        )
        == 2
    )
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"rnnpb: error: cannot reach a Ray cluster at ray://127.0.0.1:{port}")
    assert "\n" not in err and not (tmp_path / "out").exists()


def test_a_run_that_raises_is_recorded_with_its_error(tmp_path):
    run = RunSpec(
        "s",
        "9",
        Setting("t", TrainConfig.fast(iterations=5)),
        0,
        Setting("o", OnlineConfig()),
        100,
        ("synchronization",),
        0,
        2,
        100,
        10,
        (1.0,),
    )
    record = execute_run(run, str(tmp_path))
    assert record.status == "failed" and record.measures == []
    assert "9" in record.error and record.error.split(":")[0].endswith("Error")


def test_the_specs_shipped_in_the_repository_load():
    shipped = sorted((Path(__file__).parents[2] / "sweeps").glob("*.toml"))
    assert shipped
    specs = {path.stem: load_spec(path) for path in shipped}
    larger = specs["larger_set_paper"]
    assert larger.learning_sets == ("full",) and len(larger.seeds) == 10
    assert larger.training[0].config.iterations == 100_000
    assert larger.training[0].config.optimizer == "momentum"
    from rnnpb.experiments.studies import load_study, study_names

    # The studies' spec sweeps every study that runs on a fresh clone (the people study reads
    # motion capture that is not part of rnnpb).
    runnable = {n for n in study_names() if not getattr(load_study(n), "NEEDS_DATA", False)}
    assert set(specs["studies_quick"].studies) == runnable and "people" not in runnable
    scaling = specs["scaling"].runs()
    assert len(scaling) == 2 * 5 * 2 and len({r.model_key for r in scaling}) == 10


STUDIES = """
name = "studies"
studies = ["novelty", "dyad"]
seeds = [0, 1, 2]
quick = true
"""


def test_a_study_sweep_runs_every_study_once_per_seed(tmp_path):
    spec = load_spec(_spec(tmp_path, STUDIES))
    runs = spec.runs()
    assert [r.run_id for r in runs] == [
        f"study-{name}-seed{seed}-quick" for name in ("novelty", "dyad") for seed in (0, 1, 2)
    ]
    assert all(isinstance(r, StudyRunSpec) and r.quick for r in runs)
    # No two runs share a group: a study learns or loads its own models.
    assert len({r.model_key for r in runs}) == 6
    both = load_spec(_spec(tmp_path, 'studies = ["safety"]\n' + GOOD)).runs()
    assert len(both) == 24 + 3 and both[-1].run_id == "study-safety-seed2"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (STUDIES.replace('"dyad"', '"tea"'), "study 'tea' is not one of novelty"),
        (STUDIES.replace('"dyad"', '"novelty"'), "'studies' repeats a value"),
        (STUDIES + "[training.fast]\n", "'training' applies to learning sets, and the spec"),
        (STUDIES.replace("quick = true", 'quick = "yes"'), "'quick' must be true or false"),
        (STUDIES.replace("seeds = [0, 1, 2]", "seeds = []"), "'seeds' has no values"),
    ],
)
def test_bad_study_specs_get_one_line(tmp_path, text, message):
    with pytest.raises(ConfigError, match=message):
        load_spec(_spec(tmp_path, text))


def test_a_study_that_fails_is_recorded_and_leaves_no_folder(tmp_path):
    # The dyad study refuses models it does not find in the folder given: the run is failed
    # with that one line, and neither its output folder nor a half-written one is left.
    record = execute_run(StudyRunSpec("s", "dyad", 0, True, str(tmp_path / "none")), str(tmp_path))
    assert record.status == "failed" and record.measures == []
    assert record.error.startswith(f"ConfigError: {tmp_path / 'none'}: no model set1.npz")
    assert not any((tmp_path / "studies").iterdir())


def test_the_studies_section_counts_the_seeds_that_met_each_target(tmp_path):
    from rnnpb.sweeps._sweep import _write_outputs

    spec = load_spec(_spec(tmp_path, STUDIES.replace(', "dyad"', "")))
    runs = spec.runs()
    records = {
        run.run_id: RunRecord(
            run.run_id,
            "ok",
            [
                ("study_target_met", "still", 1.0),
                ("study_target_met", "novel_within_3_cycles", float(run.seed != 1)),
                ("study_runtime_s", "", 10.0 + run.seed),
            ],
            "",
            f"studies/{run.run_id}",
            1.0,
        )
        for run in runs
    }
    table = read_table(_write_outputs(tmp_path, spec, runs, records, 3.0))
    rows = table.to_pylist()
    assert {r["study"] for r in rows} == {"novelty"} and {r["user_draw"] for r in rows} == {None}
    report = (tmp_path / "report.md").read_text()
    missed = next(line for line in report.splitlines() if "novel_within_3_cycles" in line)
    assert missed.startswith("| novelty | novel_within_3_cycles | 2 of 3 | 67% [")
    assert missed.endswith("| 1 |")
    assert "| novelty | still | 3 of 3 | 100% [100%, 100%] | – |" in report
    assert "`studies/study-novelty-seed1-quick/report.md`" in report
