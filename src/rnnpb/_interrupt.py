"""Ctrl-C that stops a command only where stopping is safe.

Python raises ``KeyboardInterrupt`` at whatever bytecode the main thread runs next. During the
first seconds of a command that is often code JAX or jaxlib runs on behalf of C++: a C
extension's module initialisation while jaxlib is imported, or a Python callback during an XLA
compilation. An exception there is not handled by the C++ side: the process crashed with a
segmentation fault (in the import), crashed at exit because an XLA thread was still compiling
while the interpreter shut down, or the exception was printed as "Exception ignored" and
dropped, so the run went on to the end.

:class:`SafeInterrupts` replaces Python's SIGINT handler while a command runs: a signal only
sets a flag, and the command calls :meth:`SafeInterrupts.check` at points where no XLA work is
in flight — between training chunks (after the chunk's error has been read back) and between
interaction steps — which raises ``KeyboardInterrupt`` there. A second Ctrl-C before the next
safe point raises at once, for a command stuck where it never reaches one.
"""

from __future__ import annotations

import os
import signal
import threading
from types import FrameType, TracebackType

NOTICE = b"rnnpb: interrupt received, stopping at the next safe point (Ctrl-C again: now)\n"


class SafeInterrupts:
    """While entered (in the main thread), SIGINT sets :attr:`requested` instead of raising."""

    def __init__(self) -> None:
        self.requested = False
        self._previous: signal.Handlers | object | None = None
        self._installed = False

    def _on_signal(self, signum: int, frame: FrameType | None) -> None:
        if self.requested:
            raise KeyboardInterrupt
        self.requested = True
        # os.write, not print: the main thread may be inside a buffered write to stderr (the
        # progress bar), and re-entering that buffer raises RuntimeError.
        try:
            os.write(2, NOTICE)
        except OSError:
            pass

    def check(self) -> None:
        """Raise ``KeyboardInterrupt`` here if Ctrl-C was pressed since the last check."""
        if self.requested:
            self.requested = False
            raise KeyboardInterrupt

    def __enter__(self) -> SafeInterrupts:
        if threading.current_thread() is threading.main_thread():
            self._previous = signal.signal(signal.SIGINT, self._on_signal)
            self._installed = True
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        if self._installed:
            signal.signal(signal.SIGINT, self._previous)  # type: ignore[arg-type]
            self._installed = False


_current = SafeInterrupts()


def safe_interrupts() -> SafeInterrupts:
    """The process's handler (the command line enters it around commands that check it)."""
    return _current


def check() -> None:
    """A safe point: raise ``KeyboardInterrupt`` if Ctrl-C was pressed (see the module)."""
    _current.check()
