"""Ray: a local instance on this machine's cores, or an existing cluster; jobs run as tasks.

Every task keeps JAX to one core (the cluster's CPUs provide the parallelism) and chooses the
on-line step's XLA setting before JAX starts in its worker (:mod:`rnnpb._xla`). A task whose
worker dies is retried by Ray; an exception a job raises is the job's result to handle, not
retried (it would raise again).
"""

from __future__ import annotations

import contextlib
import os
import socket
import warnings
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from rnnpb.errors import RnnpbError

ADDRESS_TIMEOUT_S = 5.0
WAIT_S = 0.5


class ClusterError(RnnpbError, RuntimeError):
    """The Ray cluster cannot be reached or started."""


def _worker_init() -> None:
    from rnnpb import _xla

    _xla.configure()
    _xla.single_threaded()
    _xla.compilation_cache()  # a cluster's node keeps its own


def _call(function: Callable[..., Any], args: tuple[Any, ...]) -> Any:
    _worker_init()
    return function(*args)


def check_address(address: str) -> None:
    """Fail in one line, quickly, when nothing listens at ``address`` (``HOST:PORT`` or
    ``ray://HOST:PORT``); ``auto`` is Ray's to resolve."""
    if address == "auto":
        return
    bare = address.removeprefix("ray://")
    host, _, port = bare.rpartition(":")
    if not host or not port.isdigit():
        raise ClusterError(f"--address {address!r} is not HOST:PORT (or ray://HOST:PORT)")
    try:
        with socket.create_connection((host, int(port)), timeout=ADDRESS_TIMEOUT_S):
            pass
    except OSError as error:
        raise ClusterError(f"cannot reach a Ray cluster at {address}: {error}") from None


@contextlib.contextmanager
def ray_cluster(address: str | None = None, workers: int | None = None) -> Iterator[int]:
    """Connect to Ray (``address``) or start a local instance with ``workers`` CPUs (default:
    this machine's); yield how many tasks may run at once. An instance already running in this
    process is used as it is and left running."""
    import ray

    if ray.is_initialized():
        yield _capacity(workers)
        return
    if address is not None:
        check_address(address)
    # Ray's worker processes inherit the environment: they find rnnpb where this process does.
    try:
        with warnings.catch_warnings():
            # Ray starts its own services with a pre-exec hook, which runs JAX's fork warning
            # in this process; the children exec Ray's programs at once and never touch JAX.
            warnings.filterwarnings(
                "ignore", message=r"os\.fork\(\) was called", category=RuntimeWarning
            )
            _init(ray, address, workers)
    except (ConnectionError, RuntimeError, ValueError) as error:
        raise ClusterError(
            f"cannot {'start' if address is None else 'join'} Ray: "
            f"{str(error).splitlines()[0] if str(error) else error}"
        ) from None
    try:
        yield _capacity(workers)
    finally:
        ray.shutdown()


def _init(ray, address: str | None, workers: int | None) -> None:
    if address is None:
        ray.init(
            num_cpus=workers or os.cpu_count() or 1,
            include_dashboard=False,
            log_to_driver=False,
            configure_logging=False,
        )
    else:
        ray.init(address=address, log_to_driver=False, configure_logging=False)


def _capacity(workers: int | None) -> int:
    import ray

    cpus = int(ray.cluster_resources().get("CPU", 1))
    return max(1, min(workers, cpus) if workers else cpus)


Job = tuple[Any, Callable[..., Any], tuple[Any, ...]]


def run_tasks(
    jobs: deque[Job], capacity: int, retries: int = 2
) -> Iterator[tuple[Any, Any, BaseException | None]]:
    """Run ``(key, function, args)`` jobs as Ray tasks, in order, at most ``capacity`` at
    once; yield ``(key, result, None)`` as each ends, or ``(key, None, error)`` when its worker
    died more than ``retries`` times (or the task could not run). Jobs the caller appends to
    ``jobs`` meanwhile run too."""
    import ray

    remote = ray.remote(num_cpus=1, max_retries=retries, retry_exceptions=False)(_call)
    running: dict[Any, Any] = {}
    while jobs or running:
        while jobs and len(running) < capacity:
            key, function, args = jobs.popleft()
            running[remote.remote(function, args)] = key
        # A bounded wait: Ctrl-C reaches Python between waits, not only when a task ends.
        done, _ = ray.wait(list(running), num_returns=1, timeout=WAIT_S)
        for ref in done:
            key = running.pop(ref)
            try:
                yield key, ray.get(ref), None
            except (ray.exceptions.RayError, OSError) as error:
                yield key, None, error


def ray_runner(
    address: str | None = None, workers: int | None = None, retries: int = 2
) -> Callable[[Sequence[Job]], Iterator[tuple[Any, Any]]]:
    """A job runner for :func:`rnnpb.experiments.demo.run_demo`: the demo's jobs as Ray
    tasks; a job that fails fails the demo."""

    def run(jobs: Sequence[Job]) -> Iterator[tuple[Any, Any]]:
        import ray

        with ray_cluster(address, workers) as capacity:
            for key, result, error in run_tasks(deque(jobs), capacity, retries):
                if isinstance(error, ray.exceptions.RayTaskError):
                    raise error.as_instanceof_cause()  # the job's own error, as a pool gives
                if error is not None:
                    raise error
                yield key, result

    return run
