"""Teaching's work off the loop's thread: a consolidation in a process of its own
(:class:`BackgroundConsolidation`) and a new model version's mirror system built and compiled
in a thread (:class:`PreparedMirror`), so that a paced loop keeps its deadlines.

A consolidation's process is forked from a server process that has already imported JAX and
the model's modules (:func:`process_context`; started ahead by :func:`start_process_server`):
importing them takes about 1.4 s of CPU, which every spawned process would pay again. The
server never starts JAX's backend, so each process forked from it starts its own, as a spawned
one would. Where the platform cannot fork a server, each consolidation is a spawned process.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from rnnpb.model import TrainedModel
    from rnnpb.model.consolidation import ConsolidationConfig
    from rnnpb.presets import Overrides


# What the server imports before it forks a consolidation: JAX and what the worker imports.
PRELOAD = (
    "jax",
    "jax.numpy",
    "optax",
    "rnnpb.interaction.background",
    "rnnpb.memory",
    "rnnpb.model",
    "rnnpb.model.consolidation",
)


def process_context():
    """The multiprocessing context of a consolidation's process: ``forkserver`` with
    :data:`PRELOAD` imported where the platform has it, else ``spawn``."""
    import multiprocessing

    if "forkserver" not in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("spawn")
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(list(PRELOAD))
    return context


def start_process_server() -> None:
    """Start the server consolidations are forked from, if not yet running, without waiting
    for it: it imports :data:`PRELOAD` while the loop runs, so that the first consolidation
    starts at once. Nothing to do where consolidations are spawned."""
    context = process_context()
    if context.get_start_method() == "forkserver":
        from multiprocessing import forkserver

        forkserver.ensure_running()


def teaching_consolidation(
    model: TrainedModel, iterations: int | None = None, overrides: Overrides | None = None
) -> ConsolidationConfig:
    """The consolidation teaching runs on ``model``: the policy for ``"teach"``
    (:func:`rnnpb.model.consolidation.consolidation_config`), with ``iterations`` when given
    and a ``--config`` file's ``[teaching]`` and ``[consolidation]`` tables (``overrides``)
    over the preset's."""
    from rnnpb.model import consolidation_config

    return consolidation_config(model, "teach", iterations=iterations, overrides=overrides)


# The environment variables a consolidation reads: XLA's, JAX's and rnnpb's own.
SETTINGS = ("XLA_", "JAX_", "RNNPB_")


def _settings() -> dict[str, str]:
    """This process's :data:`SETTINGS` variables, for its consolidation's process."""
    return {name: value for name, value in os.environ.items() if name.startswith(SETTINGS)}


def _backend_on_one_core() -> None:
    """Start JAX's backend while this process may use one core, then give the process back
    every core it may use. XLA sizes its thread pools by the cores a process may use when its
    backend starts, and the flag of ``_xla.single_threaded`` leaves part of a larger model's
    learning to several threads, which costs CPU without saving time; kept to one core for
    good, two consolidations started on the same core would share it to their end."""
    import jax

    allowed = os.sched_getaffinity(0) if hasattr(os, "sched_getaffinity") else set()
    if len(allowed) > 1:
        current = _current_core()
        os.sched_setaffinity(
            0, {current if current is not None and current in allowed else max(allowed)}
        )
    try:
        jax.devices()
    finally:
        if len(allowed) > 1:
            os.sched_setaffinity(0, allowed)


def _current_core() -> int | None:
    """The core this process runs on (Linux: field 39 of /proc/self/stat), or None."""
    try:
        with open("/proc/self/stat") as stat:
            return int(stat.read().rsplit(")", 1)[1].split()[36])
    except (OSError, ValueError, IndexError):
        return None


def _consolidation_worker(
    model_path: str,
    memory_path: str,
    episode_ids: list[int],
    out_path: str,
    queue,
    iterations: int | None = None,
    overrides: Overrides | None = None,
    environment: Mapping[str, str] | None = None,
) -> None:
    """In a process of its own: consolidate the episodes into the model, write the new version,
    record the consolidation in the memory; report progress and the outcome on ``queue``.
    ``environment``: the settings of the process that started it (:func:`_settings`), which a
    process forked from a server started earlier would not have.

    The matrix products of learning are too small to share between threads: one thread gives
    the same model for about a fifth less CPU, which the loop's process keeps."""
    from rnnpb import _xla

    if environment is not None:
        for name in [n for n in os.environ if n.startswith(SETTINGS) and n not in environment]:
            del os.environ[name]
        os.environ.update(environment)
    _xla.follow_cache_settings()  # JAX was imported by the server, before this environment
    start = time.perf_counter()
    try:
        if not _xla.backend_started():  # the flag is read when the backend starts
            _xla.single_threaded()
            _backend_on_one_core()  # in here: a backend that cannot start is reported
        from rnnpb.memory import MemoryStore
        from rnnpb.model import TrainedModel, consolidate, rehearse

        model = TrainedModel.load(model_path)
        with MemoryStore(memory_path, create=False) as memory:
            sequences = [memory.episode(i).sequence() for i in episode_ids]

        def progress(p) -> None:
            queue.put(("progress", int(p.iteration), int(p.total), float(p.mse)))

        config = teaching_consolidation(model, iterations, overrides)
        learned = consolidate(
            model, sequences, config, parent=model_path, progress=progress, grow=True
        )
        learned.save(out_path)
        rehearsed = rehearse(
            model, config.rehearsal_steps, config.rehearsal_transient, config.rehearsal_source
        )
        seconds = time.perf_counter() - start
        with MemoryStore(memory_path, create=False) as memory:
            memory.add_consolidation(
                model_before=model_path,
                model_after=out_path,
                episode_ids=episode_ids,
                rehearsed=[*rehearsed, *sequences],
                seconds=seconds,
            )
        queue.put(("done", out_path, seconds, time.process_time()))
    except BaseException as error:  # the parent keeps its model and says why
        message = (
            f"{type(error).__name__}: {error}" if not str(error).startswith("rnnpb") else str(error)
        )
        try:
            from rnnpb.memory import MemoryStore

            with MemoryStore(memory_path, create=False) as memory:
                memory.add_consolidation(
                    model_before=model_path,
                    model_after="",
                    episode_ids=episode_ids,
                    rehearsed=[],
                    status="failed",
                    message=message[:500],
                    seconds=time.perf_counter() - start,
                )
        except BaseException:  # noqa: BLE001 - the message to the parent matters more
            pass
        queue.put(("failed", message, time.process_time()))


@dataclass(frozen=True)
class ConsolidationState:
    """Where a background consolidation is: ``running`` (``iteration`` of ``total``),
    ``done`` (``model_path`` of the new version, ``seconds``) or ``failed`` (``message``).
    ``cpu_s``: once it has ended, the CPU seconds its process took until it reported (NaN if
    the process ended without a word)."""

    state: str
    iteration: int = 0
    total: int = 0
    model_path: str = ""
    seconds: float = 0.0
    message: str = ""
    cpu_s: float = math.nan

    def describe(self) -> str:
        if self.state == "running":
            share = f" {100 * self.iteration / self.total:.0f} %" if self.total else ""
            return f"consolidating{share}"
        if self.state == "done":
            return f"consolidated in {self.seconds:.0f} s"
        return f"consolidation failed: {self.message}"


def ended_message(code: int | None, heard: bool) -> str:
    """Why a consolidation failed whose process ended without its outcome (``code``: its
    exit code; ``heard``: whether it reported anything before)."""
    message = f"the consolidation process ended (exit code {code})"
    if code == 1 and not heard:
        # multiprocessing starts the process by importing the main script: one that starts
        # teaching at its top level does so again in the new process, which then fails.
        message += (
            " before it began; if a script of yours started it, its code must run under "
            '`if __name__ == "__main__":`'
        )
    return message


class BackgroundConsolidation:
    """A consolidation in a process of its own (:func:`process_context`), so that the loop
    keeps its pace.

    The process loads the model, reads the episodes from the memory, runs
    :func:`rnnpb.model.consolidate` (rehearsal), writes the new version beside the model and
    records the consolidation in the memory; :meth:`poll` never blocks, :meth:`wait` does.
    The consolidation is :func:`teaching_consolidation`'s (``iterations`` and ``overrides``
    are its; the process gets ``overrides`` as they are).
    """

    def __init__(
        self,
        model_path: str | os.PathLike[str],
        memory_path: str | os.PathLike[str],
        episode_ids: list[int],
        out_path: str | os.PathLike[str],
        iterations: int | None = None,
        overrides: Overrides | None = None,
    ) -> None:
        context = process_context()
        self._queue = context.Queue()
        self.out_path = str(out_path)
        self._process = context.Process(
            target=_consolidation_worker,
            daemon=True,
            args=(
                str(model_path),
                str(memory_path),
                list(episode_ids),
                self.out_path,
                self._queue,
                iterations,
                overrides,
                _settings(),
            ),
        )
        self.state = ConsolidationState("running")
        self._heard = False  # whether the process reported anything
        self._process.start()

    def poll(self) -> ConsolidationState:
        """The latest state, reading what the process reported so far (never blocks)."""
        import queue as queues

        while self.state.state == "running":
            try:
                message = self._queue.get_nowait()
            except queues.Empty:
                if not self._process.is_alive() and self._queue.empty():
                    self.state = ConsolidationState(
                        "failed", message=ended_message(self._process.exitcode, self._heard)
                    )
                break
            self._heard = True
            self._take(message)
        return self.state

    def wait(self, timeout_s: float | None = None) -> ConsolidationState:
        """Block until the consolidation has finished (or ``timeout_s``), and its process
        has ended (up to 5 s more)."""
        deadline = None if timeout_s is None else time.perf_counter() + timeout_s
        while self.poll().state == "running":
            if deadline is not None and time.perf_counter() > deadline:
                break
            self._process.join(0.05)
        if self.state.state != "running":
            self._process.join(5.0)
        return self.state

    def _take(self, message: tuple) -> None:
        kind = message[0]
        if kind == "progress":
            self.state = ConsolidationState("running", message[1], message[2])
        elif kind == "done":
            # Not joined here: the process takes a moment to end after it reported (its
            # interpreter and JAX shut down), and poll() must never hold up a paced loop.
            # ``ended`` tells when it has; ``wait`` and ``cancel`` join it.
            self.state = ConsolidationState(
                "done", model_path=message[1], seconds=message[2], cpu_s=message[3]
            )
        else:
            self.state = ConsolidationState("failed", message=message[1], cpu_s=message[2])

    @property
    def ended(self) -> bool:
        """Whether the process has exited (and been reaped); never blocks."""
        return not self._process.is_alive()

    def cancel(self) -> None:
        if self._process.is_alive():
            self._process.terminate()
            self._process.join(5.0)


class PreparedMirror:
    """A new model version's mirror system, built and its first step compiled in a thread of
    its own (``mirror`` None when that failed: the swap then builds it, and says why)."""

    def __init__(self, path: str, make_mirror) -> None:
        import threading

        self.path = path
        self.model = None
        self.mirror = None
        self.error = ""
        self._make_mirror = make_mirror
        self._thread = threading.Thread(target=self._run, name="rnnpb-prepare", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        from rnnpb.model import TrainedModel

        try:
            model = TrainedModel.load(self.path)
            mirror = self._make_mirror(model)
            mirror.step(np.full(model.network.sensory_size, 0.5))  # compiles the step
            mirror.reset()
            self.model, self.mirror = model, mirror
        except Exception as error:  # noqa: BLE001 - the swap builds it on the loop's thread
            self.error = f"{type(error).__name__}: {error}"

    @property
    def done(self) -> bool:
        return not self._thread.is_alive()
