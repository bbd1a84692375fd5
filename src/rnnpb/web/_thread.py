"""The session's one thread and its command queue.

Control messages from every tab wait in one queue; the thread applies them one at a time, so
two tabs can never interleave half-applied changes. While a loop runs, the thread is inside
:meth:`InteractionLoop.run <rnnpb.interaction.InteractionLoop.run>`, which paces the steps at
``dt`` and hands the waits between them back here to apply the commands (and to let teaching
follow its consolidation); while stopped, the thread waits for commands itself. Nothing a
step or a command raises ends the thread.
"""

from __future__ import annotations

import contextlib
import logging
import queue
import threading
import time
from collections.abc import Callable
from typing import Any

from rnnpb.errors import RnnpbError

log = logging.getLogger("rnnpb.web")

MAX_QUEUED_COMMANDS = 64
"""Commands waiting for the session thread; more are refused with an error reply."""
IDLE_WAIT_S = 0.5
"""How long a stopped session waits for a command before it looks again."""


class SessionThread:
    """Runs ``loop`` (set it to the loop that should run, None to stop) and applies the
    queued commands.

    Parameters
    ----------
    apply : callable(command)
        Applies one command; never raises (it reports what went wrong itself).
    idle : callable() -> float
        Called between steps and while stopped (teaching follows its consolidation there);
        never raises; returns how long a stopped session may wait for a command.
    stopped : callable(reason)
        The loop stopped by itself: its source failed or ended, or a step raised
        (``reason`` says so for the pages).
    max_queued : int
    """

    def __init__(
        self,
        apply: Callable[[dict[str, Any]], None],
        idle: Callable[[], float],
        stopped: Callable[[str], None],
        max_queued: int = MAX_QUEUED_COMMANDS,
    ) -> None:
        self.apply = apply
        self.idle = idle
        self.stopped = stopped
        self.loop: Any = None
        self.source_name = ""  # who drives, for the reasons the pages are given
        self._commands: queue.Queue[dict[str, Any]] = queue.Queue(maxsize=max_queued)
        self._closed = threading.Event()
        self._thread: threading.Thread | None = None

    def start(self) -> None:
        self._thread = threading.Thread(target=self._run, name="rnnpb-session", daemon=True)
        self._thread.start()

    def close(self) -> None:
        self._closed.set()
        with contextlib.suppress(queue.Full):
            self._commands.put_nowait({"type": "_wake"})
        if self._thread is not None:
            self._thread.join(timeout=10)

    @property
    def closed(self) -> bool:
        return self._closed.is_set()

    def submit(self, command: dict[str, Any]) -> bool:
        """Queue ``command``; ``False`` (and nothing queued) when the queue is full."""
        try:
            self._commands.put_nowait(command)
        except queue.Full:
            return False
        return True

    def _run(self) -> None:
        while not self._closed.is_set():
            try:
                loop = self.loop
                if loop is not None:
                    self._drive(loop)
                else:
                    self._apply_queued(timeout_s=self.idle())
            except Exception as error:  # the thread must outlive anything a step raises
                log.exception("session: unexpected failure")
                self.loop = None
                with contextlib.suppress(Exception):
                    self.stopped(f"the session stopped the robot: {type(error).__name__}: {error}")
                time.sleep(0.05)  # a failure that repeats must not spin

    def _drive(self, loop) -> None:
        """Let ``loop`` run (it paces itself) until a command stops or replaces it, the session
        closes, or its source ends or fails; the queued commands are applied between steps.
        Whatever a step raises stops the robot with the reason on every page; the thread
        goes on taking commands (Start tries again)."""

        def between_steps(wait_s: float) -> None:
            started = time.perf_counter()
            self.idle()
            self._apply_queued(timeout_s=max(0.0, wait_s - (time.perf_counter() - started)))
            if self._closed.is_set() or self.loop is not loop:
                loop.stop()

        try:
            loop.run(between_steps=between_steps)
        except RnnpbError as error:
            self._stop(loop, f"the {self.source_name} source failed: {error}")
            return
        except Exception as error:  # an OSError, a bug, a failing camera driver...
            log.exception("session: step %d failed", loop.steps)
            self._stop(
                loop,
                f"step {loop.steps} failed, the robot is stopped: {type(error).__name__}: {error}",
            )
            return
        if self.loop is loop and not self._closed.is_set():
            self._stop(loop, f"the {self.source_name} source has ended")

    def _stop(self, loop, reason: str) -> None:
        if self.loop is loop:
            self.loop = None
        self.stopped(reason)

    def _apply_queued(self, timeout_s: float) -> None:
        """Apply every queued command, waiting up to ``timeout_s`` for the first."""
        try:
            command = self._commands.get(timeout=timeout_s)
        except queue.Empty:
            return
        while True:
            if command["type"] != "_wake":
                self.apply(command)
            try:
                command = self._commands.get_nowait()
            except queue.Empty:
                return
