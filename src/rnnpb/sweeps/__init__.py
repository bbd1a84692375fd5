"""Sweeps: grids of learning sets × seeds × settings × draws of the user, and of studies ×
seeds, on Ray.

``rnnpb sweep SPEC --out DIR`` reads a TOML spec (:func:`load_spec`), runs every run of its grid
as a Ray task (:func:`run_sweep`; a local instance, or a cluster at ``--address``), keeps each
finished run's record in ``DIR/runs/`` (a rerun skips them), caches every trained model in
``DIR/models/`` by data, config and seed, and writes ``DIR/results.parquet`` (one row per run and
measure, :func:`schema`), ``DIR/report.md`` and ``DIR/results.json`` (medians and shares with
95 % bootstrap intervals) and ``DIR/figures/``. docs/sweeps.md is the guide.
"""

from rnnpb.sweeps._ray import ClusterError, check_address, ray_cluster, ray_runner, run_tasks
from rnnpb.sweeps._report import (
    LIMITS,
    MeasureSummary,
    StudyTargetSummary,
    study_summaries,
    summaries,
    write_report,
)
from rnnpb.sweeps._runs import (
    MEASURES,
    STUDIES_DIR,
    RunRecord,
    cached_model,
    execute_run,
    measure,
    run_study,
)
from rnnpb.sweeps._spec import (
    EXPERIMENTS,
    LEARNING_SETS,
    ONLINE_PRESETS,
    TRAIN_PRESETS,
    RunSpec,
    Setting,
    StudyRunSpec,
    SweepSpec,
    load_spec,
    parse_spec,
)
from rnnpb.sweeps._sweep import Progress, SweepOutcome, run_sweep
from rnnpb.sweeps._table import COLUMNS, TABLE_FILE, read_table, schema

__all__ = [
    "COLUMNS",
    "EXPERIMENTS",
    "LEARNING_SETS",
    "LIMITS",
    "MEASURES",
    "ONLINE_PRESETS",
    "STUDIES_DIR",
    "TABLE_FILE",
    "TRAIN_PRESETS",
    "ClusterError",
    "MeasureSummary",
    "Progress",
    "RunRecord",
    "RunSpec",
    "Setting",
    "StudyRunSpec",
    "StudyTargetSummary",
    "SweepOutcome",
    "SweepSpec",
    "cached_model",
    "check_address",
    "execute_run",
    "load_spec",
    "measure",
    "parse_spec",
    "ray_cluster",
    "ray_runner",
    "read_table",
    "run_study",
    "run_sweep",
    "run_tasks",
    "schema",
    "study_summaries",
    "summaries",
    "write_report",
]
