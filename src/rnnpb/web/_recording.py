"""The dashboard's session recordings: one CSV per run, in parts of a bounded size, the oldest
files deleted beyond a number kept (docs/robustness.md, "The dashboard's session: errors,
recordings, command limits")."""

from __future__ import annotations

import contextlib
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from rnnpb.errors import ConfigError


@dataclass(frozen=True)
class RecordingLimits:
    """How much the dashboard keeps on disk.

    Attributes
    ----------
    rows_per_file : int
        A recording that reaches this many rows (steps) goes on in a new file (the next part
        of the same run). 50,000 rows are about 12 MB: 17 minutes at ``dt`` 0.02, 5.5 hours
        at the paper's 0.4.
    keep_files : int
        Recording files kept; the oldest beyond this number are deleted (the newest, being
        written, is always kept). So the session's files are bounded by
        ``keep_files × rows_per_file`` rows, about 60 MB with the defaults.
    """

    rows_per_file: int = 50_000
    keep_files: int = 5

    def __post_init__(self) -> None:
        if self.rows_per_file < 1 or self.keep_files < 1:
            raise ConfigError("recording limits must be >= 1 row per file and >= 1 file kept")


class Recordings:
    """The runs' recordings in ``folder``, at most ``limits.keep_files`` files (the oldest
    deleted)."""

    def __init__(self, folder: Path, limits: RecordingLimits) -> None:
        self.folder = folder
        self.limits = limits
        self._files: deque[Path] = deque()

    @property
    def files(self) -> list[Path]:
        """The recordings kept, oldest first."""
        return list(self._files)

    def start(self, run: int, pb_size: int, on_failure: Callable[[str], None]) -> Recording:
        """Run ``run``'s recording (``on_failure(text)`` hears of a write that failed). Raises
        :class:`OSError` when its first file cannot be opened."""
        return Recording(self, run, pb_size, on_failure)

    def keep(self, path: Path) -> None:
        """Note a new recording file; delete the oldest beyond ``keep_files``."""
        self._files.append(path)
        while len(self._files) > self.limits.keep_files:
            old = self._files.popleft()
            with contextlib.suppress(FileNotFoundError):
                old.unlink()


class Recording:
    """The recorder the loop writes to: one run's CSV in parts of at most
    ``limits.rows_per_file`` rows. A write that fails (a full disk) turns the recording off and
    reports it through ``on_failure``; the robot is not stopped for it."""

    def __init__(
        self, recordings: Recordings, run: int, pb_size: int, on_failure: Callable[[str], None]
    ) -> None:
        self.recordings = recordings
        self.run = run
        self.pb_size = pb_size
        self.on_failure = on_failure
        self.part = 0
        self.failed: str | None = None
        self.rows = 0
        self.path: Path | None = None
        self._recorder = None
        self._next_part()

    def _next_part(self) -> None:
        from rnnpb.interaction import SessionRecorder

        self._close_part()
        self.part += 1
        suffix = "" if self.part == 1 else f"-part{self.part}"
        path = self.recordings.folder / f"session-{self.run:03d}{suffix}.csv"
        recorder = SessionRecorder(path, self.pb_size)
        recorder.open()
        self._recorder = recorder
        self.path = path
        self.recordings.keep(path)

    def write(self, record) -> None:
        if self.failed is not None or self._recorder is None:
            return
        try:
            if self._recorder.rows >= self.recordings.limits.rows_per_file:
                self._next_part()
            self._recorder.write(record)
            self.rows += 1
        except OSError as error:
            name = self.path.name if self.path is not None else "the recording"
            self.failed = f"recording stopped: {name}: {error.strerror or error}"
            with contextlib.suppress(OSError):  # already reported
                self._close_part()
            self.on_failure(
                f"{self.failed}; the robot goes on without recording (Reset starts a new recording)"
            )

    def _close_part(self) -> None:
        recorder, self._recorder = self._recorder, None
        if recorder is not None:
            recorder.close()

    def close(self) -> None:
        with contextlib.suppress(OSError):  # already reported
            self._close_part()
