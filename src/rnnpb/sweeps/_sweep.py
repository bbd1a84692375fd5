"""Running a sweep: every run of the grid on Ray, resumable, with progress.

Runs whose record says ``ok`` are skipped (a rerun of the same command finishes what is left;
failed runs are tried again). Runs that share a model (same learning set, training setting and
seed) wait for the first of them, which trains and caches it, so no model is learned twice.
"""

from __future__ import annotations

import contextlib
import shutil
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from rnnpb.sweeps._ray import Job, check_address, ray_cluster, run_tasks
from rnnpb.sweeps._report import write_report
from rnnpb.sweeps._runs import MODELS_DIR, STUDIES_DIR, RunRecord, execute_run, failed
from rnnpb.sweeps._spec import AnyRun, SweepSpec
from rnnpb.sweeps._table import RUNS_DIR, read_record, read_table, write_record, write_table

RunFunction = Callable[[AnyRun, str], RunRecord]


@dataclass(frozen=True)
class Progress:
    """Where a sweep stands: runs done (this time and before), running, failed, time left."""

    total: int
    done: int
    running: int
    failed: int
    elapsed_s: float
    left_s: float | None  # None until a run has finished

    def describe(self) -> str:
        left = "–" if self.left_s is None else _duration(self.left_s)
        return (
            f"runs: {self.done}/{self.total} done, {self.running} running, "
            f"{self.failed} failed; {_duration(self.elapsed_s)} elapsed, about {left} left"
        )


@dataclass(frozen=True)
class SweepOutcome:
    """What a sweep left in its folder."""

    records: dict[str, RunRecord]  # every run's, by run id
    table: Path
    ran: int  # runs executed this time (the others were finished before)
    runtime_s: float

    @property
    def failed(self) -> list[RunRecord]:
        return [r for r in self.records.values() if r.status != "ok"]


def _duration(seconds: float) -> str:
    minutes, rest = divmod(int(round(seconds)), 60)
    return f"{minutes}m{rest:02d}s" if minutes else f"{rest}s"


def _clear_leftovers(out: Path) -> None:
    """Temporary files of writes a killed process never finished (never a finished file)."""
    for folder in (out / RUNS_DIR, out / MODELS_DIR):
        for leftover in folder.glob(".*.tmp"):
            with contextlib.suppress(FileNotFoundError):
                leftover.unlink()
    for leftover in (out / STUDIES_DIR).glob(".*.tmp"):
        shutil.rmtree(leftover, ignore_errors=True)  # a study a killed worker left unfinished


def run_sweep(
    spec: SweepSpec,
    out: str | Path,
    address: str | None = None,
    workers: int | None = None,
    log: Callable[[str], None] = print,
    run_function: RunFunction = execute_run,
    on_progress: Callable[[Progress], None] | None = None,
) -> SweepOutcome:
    """Run every unfinished run of ``spec`` on Ray (local, or the cluster at ``address``),
    keep each run's record, then assemble ``out/results.parquet`` and write ``out/report.md``,
    ``out/results.json`` and ``out/figures/``.

    ``run_function`` runs one run in a worker (default :func:`execute_run`); the model cache
    is ``out/models`` (on a cluster, ``out`` should be on a file system every node shares).
    """
    start = time.perf_counter()
    if address is not None:
        check_address(address)  # before anything is written
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    _clear_leftovers(out)
    runs = spec.runs()
    records: dict[str, RunRecord] = {}
    pending: list[AnyRun] = []
    for run in runs:
        record = read_record(out, run)
        if record is not None and record.status == "ok":
            records[run.run_id] = record
        else:
            pending.append(run)
    finished_before = len(records)
    log(
        f"sweep {spec.name}: {len(runs)} runs, {finished_before} finished before, "
        f"{len(pending)} to run"
    )
    # Runs that share a model wait for the first of them, which trains it.
    groups: dict[str, list[AnyRun]] = {}
    for run in pending:
        groups.setdefault(run.model_key, []).append(run)
    by_id = {run.run_id: run for run in pending}
    try:
        if pending:
            with ray_cluster(address, workers) as capacity:
                log(f"on Ray, {capacity} at once")
                jobs: deque[Job] = deque(
                    (group[0].run_id, run_function, (group[0], str(out)))
                    for group in groups.values()
                )
                failures = done = 0
                for run_id, result, error in run_tasks(jobs, capacity, spec.retries):
                    run = by_id[run_id]
                    if error is not None:
                        first_line = str(error).strip().splitlines()[0] if str(error) else ""
                        result = failed(run, f"{type(error).__name__}: {first_line}")
                    write_record(out, run, result)
                    records[run_id] = result
                    done += 1
                    failures += result.status != "ok"
                    group = groups[run.model_key]
                    if group and group[0].run_id == run_id:
                        # The model is cached now: its other runs go first, so that every
                        # model's runs finish together and an interrupted sweep keeps whole
                        # models' results.
                        jobs.extendleft(
                            (r.run_id, run_function, (r, str(out))) for r in reversed(group[1:])
                        )
                        group.clear()
                    elapsed = time.perf_counter() - start
                    progress = Progress(
                        total=len(runs),
                        done=finished_before + done,
                        running=min(capacity, len(pending) - done),
                        failed=failures,
                        elapsed_s=elapsed,
                        left_s=elapsed / done * (len(pending) - done),
                    )
                    log(progress.describe())
                    if on_progress is not None:
                        on_progress(progress)
    except BaseException:
        # Interrupted (Ctrl-C) or broken: the table and report still show what finished.
        _write_outputs(out, spec, runs, records, time.perf_counter() - start)
        raise
    runtime = time.perf_counter() - start
    table = _write_outputs(out, spec, runs, records, runtime)
    return SweepOutcome(records=records, table=table, ran=len(pending), runtime_s=runtime)


def _write_outputs(
    out: Path, spec: SweepSpec, runs: list[AnyRun], records: dict[str, RunRecord], runtime: float
) -> Path:
    table = write_table(out, runs, records)
    write_report(out, spec, read_table(table).to_pylist(), runtime)
    return table
