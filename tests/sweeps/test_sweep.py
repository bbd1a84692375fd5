"""Sweeps on a local Ray instance: a two-run sweep, its table, a killed worker, a resumed sweep.

One Ray instance serves the module (starting it is the slow part). The runs are tiny (30
learning iterations, a short regression, the synchronization experiment); what is checked is
the machinery: the results of an interrupted sweep, once finished, are those of an
uninterrupted one, exactly.
"""

import os
import shutil
from pathlib import Path

import pytest

from rnnpb.sweeps import COLUMNS, execute_run, load_spec, read_table, run_sweep, schema

SPEC = """
name = "tiny"
learning_sets = ["1"]
seeds = 2
user_draws = [100]
experiments = ["synchronization"]
retries = {retries}

[training.tiny]
preset = "fast"
iterations = 30

[online.short]
preset = "ungated"
window = 8
iterations = 5
"""


@pytest.fixture(scope="module")
def ray_instance():
    pytest.importorskip("ray")
    from rnnpb.sweeps import ray_cluster

    with ray_cluster(workers=2):  # one local instance for the module, as rnnpb sweep starts it
        yield


def _spec(folder: Path, retries: int = 2):
    path = folder / "tiny.toml"
    path.write_text(SPEC.format(retries=retries))
    return load_spec(path)


def _dies_once(marker: str, victim: str):
    """A run function whose worker dies (as if killed) the first time it starts ``victim``."""

    def run(run_spec, out):
        if run_spec.run_id == victim and not os.path.exists(marker):
            Path(marker).touch()
            os._exit(1)
        return execute_run(run_spec, out)

    return run


@pytest.fixture(scope="module")
def reference(ray_instance, tmp_path_factory):
    folder = tmp_path_factory.mktemp("reference")
    spec = _spec(folder)
    seen = []
    outcome = run_sweep(spec, folder / "out", log=lambda _: None, on_progress=seen.append)
    return spec, folder / "out", outcome, seen


def _comparable(path):
    return read_table(path).drop_columns(["model"]).to_pylist()


def test_a_two_run_sweep_writes_its_table_report_and_progress(reference):
    spec, out, outcome, seen = reference
    assert outcome.ran == 2 and not outcome.failed
    assert [p.done for p in seen] == [1, 2] and seen[-1].left_s == 0
    assert "2/2 done, 0 running, 0 failed" in seen[-1].describe()
    assert sorted(p.name for p in out.iterdir()) == [
        "figures",
        "models",
        "report.md",
        "results.json",
        "results.parquet",
        "runs",
    ]
    assert not list(out.rglob(".*.tmp"))
    report = (out / "report.md").read_text()
    assert "steps until locked on a learned pattern" in report and "95 %" in report


def test_the_table_reads_back_with_the_documented_schema(reference):
    spec, out, outcome, _ = reference
    table = read_table(out / "results.parquet")
    assert table.schema.equals(schema())
    assert table.column_names == [name for name, _ in COLUMNS]
    rows = table.to_pylist()
    runs = {r["run"] for r in rows}
    assert runs == {r.run_id for r in spec.runs()}
    for row in rows:
        assert row["status"] == "ok" and row["error"] == "" and row["sweep"] == "tiny"
        assert row["rnnpb_version"] and '"iterations": 30' in row["config"]
    # one row per run and measure: 2 training errors + 6 measures x 3 patterns, per run
    assert len(rows) == 2 * (2 + 6 * 3)
    locks = [r for r in rows if r["measure"] == "steps_to_lock"]
    assert {r["key"] for r in locks} == {"1", "2", "3"}
    assert {r["seed"] for r in rows} == {0, 1}


def test_a_killed_worker_is_retried_and_the_results_are_exact(reference, tmp_path):
    spec, out, _, _ = reference
    folder = tmp_path / "out"
    victim = spec.runs()[0].run_id
    outcome = run_sweep(
        spec, folder, log=lambda _: None, run_function=_dies_once(str(tmp_path / "died"), victim)
    )
    assert (tmp_path / "died").exists() and not outcome.failed
    assert _comparable(folder / "results.parquet") == _comparable(out / "results.parquet")


def test_rerunning_after_a_lost_run_finishes_it_exactly(reference, tmp_path):
    spec, out, _, _ = reference
    spec = _spec(tmp_path, retries=0)  # the killed run is lost, not retried
    folder = tmp_path / "out"
    shutil.copytree(out / "models", folder / "models")  # the cache serves the rerun
    victim = spec.runs()[0].run_id
    first = run_sweep(
        spec, folder, log=lambda _: None, run_function=_dies_once(str(tmp_path / "died"), victim)
    )
    assert [r.run_id for r in first.failed] == [victim]
    assert "Error" in first.failed[0].error
    assert "## Failed runs" in (folder / "report.md").read_text()
    again = run_sweep(spec, folder, log=lambda _: None)
    assert again.ran == 1 and not again.failed  # the finished run was skipped
    assert _comparable(folder / "results.parquet") == _comparable(out / "results.parquet")
    assert run_sweep(spec, folder, log=lambda _: None).ran == 0
