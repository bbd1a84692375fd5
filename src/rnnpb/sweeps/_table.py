"""A sweep's files: one small JSON record per finished run, and the Parquet table of them all.

``DIR/runs/RUN.json`` is written atomically when a run ends, so a rerun knows what is done;
``DIR/results.parquet`` is assembled from them (atomically too) with one row per run and
measure, in :data:`SCHEMA`:

========== ======= ===========================================================================
column     type    meaning
========== ======= ===========================================================================
sweep      string  the spec's ``name``
run        string  the run's id (``setK-TRAINING-seedS-ONLINE-drawD``)
learning_set string ``1`` … ``4`` or ``full``
training   string  the training setting's name in the spec
seed       int64   the training seed (a study's run: its StudyOptions.seed)
online     string  the on-line setting's name in the spec
user_draw  int64   the draw of the user's imperfection (scenario seed); null for a study
study      string  the study's name (``rnnpb study``); empty for a learning set's run
status     string  ``ok`` or ``failed``
measure    string  a name of :data:`rnnpb.sweeps.MEASURES` (empty for a failed run's one row)
key        string  pattern, ``a->b`` pair or novel-pattern input; empty when one per run
value      float64 the measure; null when the event never happened (or the run failed)
error      string  why the run failed; empty when ok
model      string  the cached model file (a study's: its output folder), relative to DIR
config     string  JSON of everything that made the run: train and on-line configs, seeds …
rnnpb_version string the version that measured it
========== ======= ===========================================================================
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from rnnpb._atomic import atomic_write
from rnnpb.errors import DataFileError
from rnnpb.sweeps._runs import RunRecord
from rnnpb.sweeps._spec import AnyRun

RUNS_DIR = "runs"
TABLE_FILE = "results.parquet"
COLUMNS = (
    ("sweep", "string"),
    ("run", "string"),
    ("learning_set", "string"),
    ("training", "string"),
    ("seed", "int64"),
    ("online", "string"),
    ("user_draw", "int64"),
    ("study", "string"),
    ("status", "string"),
    ("measure", "string"),
    ("key", "string"),
    ("value", "float64"),
    ("error", "string"),
    ("model", "string"),
    ("config", "string"),
    ("rnnpb_version", "string"),
)


def schema():
    """The table's :class:`pyarrow.Schema` (see the module doc)."""
    import pyarrow as pa

    return pa.schema([(name, getattr(pa, kind)()) for name, kind in COLUMNS])


def record_path(out: Path, run: AnyRun) -> Path:
    return out / RUNS_DIR / f"{run.run_id}.json"


def write_record(out: Path, run: AnyRun, record: RunRecord) -> None:
    """Keep ``record`` as ``DIR/runs/RUN.json``, atomically."""
    path = record_path(out, run)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_write(path, "w", encoding="utf-8") as handle:
        json.dump(record.to_json(), handle)


def read_record(out: Path, run: AnyRun) -> RunRecord | None:
    """The run's record, or None if it has none (a malformed one counts as none: it is
    rerun)."""
    path = record_path(out, run)
    try:
        return RunRecord.from_json(json.loads(path.read_text(encoding="utf-8")))
    except (OSError, ValueError, KeyError, IndexError, TypeError):
        return None


def rows(run: AnyRun, record: RunRecord) -> list[dict]:
    base = {
        "sweep": run.sweep,
        "run": run.run_id,
        **run.grid_columns(),
        "status": record.status,
        "error": record.error,
        "model": record.model,
        "config": run.config_json(),
        "rnnpb_version": record.rnnpb_version,
    }
    if record.status != "ok":
        return [{**base, "measure": "", "key": "", "value": None}]
    return [{**base, "measure": m, "key": k, "value": v} for m, k, v in record.measures]


def write_table(out: Path, runs: list[AnyRun], records: dict[str, RunRecord]) -> Path:
    """Assemble ``DIR/results.parquet`` from the records of ``runs`` (in grid order),
    atomically."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    table_rows = [
        r for run in runs if run.run_id in records for r in rows(run, records[run.run_id])
    ]
    columns = {name: [r[name] for r in table_rows] for name, _ in COLUMNS}
    table = pa.Table.from_pydict(columns, schema=schema())
    path = out / TABLE_FILE
    with atomic_write(path, "wb") as handle:
        pq.write_table(table, handle)
    return path


def read_table(path: str | os.PathLike[str]):
    """The table (a :class:`pyarrow.Table`), checked against :func:`schema`."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    try:
        table = pq.read_table(path)
    except (OSError, pa.ArrowException) as error:
        raise DataFileError(f"sweep table {path}: cannot read it ({error})") from None
    if not table.schema.equals(schema()):
        if table.schema.names == [n for n, _ in COLUMNS if n != "study"]:
            raise DataFileError(
                f"sweep table {path}: written by an earlier rnnpb (no 'study' column); rerun "
                "its `rnnpb sweep SPEC --out DIR` to rebuild it from the runs' records"
            )
        raise DataFileError(f"sweep table {path}: its columns are not a sweep table's")
    return table
