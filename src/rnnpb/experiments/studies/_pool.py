"""The studies' worker processes: one core each, or the jobs run here when there is one worker.

Every study that runs jobs in parallel takes its pool from :func:`study_pool`, so that each
worker keeps to one core with the on-line step's XLA setting (:mod:`rnnpb._xla`) and a single
worker runs the jobs in this process, in order, with no process to start and the
compilations shared.
"""

from __future__ import annotations

import multiprocessing
from concurrent.futures import Future, ProcessPoolExecutor
from typing import Any


def worker_init() -> None:
    """Keep this process to one core, with the on-line step's XLA setting (before JAX starts;
    the environment is inherited by the processes it starts)."""
    from rnnpb import _xla

    _xla.configure()
    _xla.single_threaded()


class InProcess:
    """The pool's interface, run here (one worker): each job runs when submitted."""

    def __enter__(self) -> InProcess:
        return self

    def __exit__(self, *exc: object) -> None:
        return None

    def submit(self, function: Any, *args: Any) -> Future:
        future: Future = Future()
        future.set_result(function(*args))
        return future


def study_pool(workers: int, *, init_here: bool = False) -> ProcessPoolExecutor | InProcess:
    """``workers`` spawned processes kept to one core each, or :class:`InProcess` for one.
    ``init_here``: keep this process to one core too (a study whose jobs run here, or start
    processes of their own that should inherit it)."""
    if init_here:
        worker_init()
    if workers == 1:
        return InProcess()
    return ProcessPoolExecutor(
        max_workers=workers,
        mp_context=multiprocessing.get_context("spawn"),
        initializer=worker_init,
    )
