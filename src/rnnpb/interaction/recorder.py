"""Session recordings: one CSV row per step of the interaction loop, flushed as it goes.

Columns: ``step``, ``time_s``, the observed hands ``lhy lhz rhy rhz`` (empty where the hand was
not seen), the hands the network predicted for this step one step before (``pred_lhy`` …), the
motor command sent (``lshp`` … ``relp``, radians), the PB (``pb0`` …), ``prediction_error``
(mean squared error of that prediction), ``window_error`` (after the PB regression),
``lost_left``/``lost_right`` (1 where the hand was not seen), ``held`` (1 where the regression
failed numerically and the last good state was kept) and, when the source knows it, the ground
truth ``truth_pattern``.

Every row is flushed to the operating system when written, so a session interrupted by Ctrl-C
or a crash keeps every step up to the last one written. A row is complete only with its line
break: :func:`read_session` ignores a last line that does not end with one (the row being
written when the process died); anything else malformed is an error naming the file and line.
"""

from __future__ import annotations

import csv
import io
import math
import os
from pathlib import Path

import numpy as np

from rnnpb.errors import DataFileError
from rnnpb.vectors import MOTOR_NAMES, PREDICTED_PREFIX, SENSORY_NAMES, STEP_COLUMN

PB_COLUMNS_PREFIX = "pb"


def session_columns(pb_size: int) -> list[str]:
    return [STEP_COLUMN, "time_s", *SENSORY_NAMES,
            *(PREDICTED_PREFIX + name for name in SENSORY_NAMES), *MOTOR_NAMES,
            *(f"{PB_COLUMNS_PREFIX}{i}" for i in range(pb_size)),
            "prediction_error", "window_error", "lost_left", "lost_right", "held",
            "truth_pattern"]


def _fmt(value: float) -> str:
    return "" if not math.isfinite(value) else f"{value:.6g}"


class SessionRecorder:
    """Writes a session recording row by row (a context manager)."""

    def __init__(self, path: str | os.PathLike[str], pb_size: int = 4) -> None:
        self.path = Path(path)
        self.columns = session_columns(pb_size)
        self._handle = None
        self._writer = None
        self.rows = 0

    def open(self) -> None:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._handle = open(self.path, "w", newline="", encoding="utf-8")
        self._writer = csv.writer(self._handle)
        self._writer.writerow(self.columns)
        self._handle.flush()

    def write(self, record) -> None:
        """Append one :class:`rnnpb.interaction.loop.StepRecord`."""
        if self._writer is None:
            self.open()
        seen = np.isfinite(record.observed)
        row = [record.step, f"{record.time_s:.4f}", *(_fmt(v) for v in record.observed),
               *(_fmt(v) for v in record.predicted), *(f"{v:.6f}" for v in record.motor),
               *(f"{v:.6f}" for v in record.pb), _fmt(record.prediction_error),
               _fmt(record.window_error), int(not seen[:2].all()), int(not seen[2:].all()),
               int(record.held), record.truth.get("pattern", "")]
        self._writer.writerow(row)
        self._handle.flush()
        self.rows += 1

    def close(self) -> None:
        if self._handle is not None:
            self._handle.flush()
            os.fsync(self._handle.fileno())
            self._handle.close()
            self._handle = None
            self._writer = None

    def __enter__(self) -> SessionRecorder:
        self.open()
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()


def read_session(path: str | os.PathLike[str], required: list[str] | None = None
                 ) -> dict[str, np.ndarray]:
    """Read a session recording into arrays by column (empty cells → NaN; strings kept).

    A last line without its line break is a row cut short by an interrupted write and is left
    out; every other row must have one field per column and numbers (or nothing) in the numeric
    columns, else :class:`DataFileError` names the file, line and column.
    """
    path = Path(path)
    if not path.exists():
        raise DataFileError(f"{path}: no such file")
    if path.is_dir():
        raise DataFileError(f"{path}: is a directory, expected a session recording (.csv)")
    try:
        data = path.read_bytes()
    except OSError as error:
        raise DataFileError(f"{path}: cannot read: {error.strerror or error}") from None
    header_end = data.find(b"\n")
    last_break = data.rfind(b"\n")
    if header_end != -1 and last_break != len(data) - 1:
        data = data[:last_break + 1]
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise DataFileError(f"{path}: not a text CSV file (cannot decode as UTF-8)") from None
    try:
        reader = csv.reader(io.StringIO(text, newline=""))
        header = next(reader, None)
        if not header:
            raise DataFileError(f"{path}: empty file, expected a session recording header")
        header = [name.strip() for name in header]
        required = required or [STEP_COLUMN, *SENSORY_NAMES, *MOTOR_NAMES]
        missing = [c for c in required if c not in header]
        if missing:
            raise DataFileError(f"{path}: not a session recording: missing column(s) "
                                f"{', '.join(missing)}")
        rows, lines = [], []
        for row in reader:
            if not row:
                continue
            if len(row) != len(header):
                raise DataFileError(f"{path}: line {reader.line_num}: expected {len(header)} "
                                    f"fields, found {len(row)}")
            rows.append(row)
            lines.append(reader.line_num)
    except csv.Error as error:
        raise DataFileError(f"{path}: malformed CSV: {error}") from None
    out: dict[str, np.ndarray] = {}
    for j, name in enumerate(header):
        values = [row[j] for row in rows]
        if name == "truth_pattern":
            out[name] = np.array(values, dtype=object)
            continue
        column = np.empty(len(values))
        for i, value in enumerate(values):
            try:
                column[i] = float(value) if value.strip() else math.nan
            except ValueError:
                raise DataFileError(f"{path}: line {lines[i]}, column {name!r}: {value!r} is "
                                    "not a number") from None
        out[name] = column
    return out


# --- two-agent recordings ------------------------------------------------------------------
DYAD_PREFIXES = ("a_", "b_")
DYAD_AGENT_COLUMNS = ("intent", "initiative")


def dyad_columns(pb_size: int) -> list[str]:
    """A two-agent recording: ``step``, ``time_s``, then each agent's columns prefixed ``a_``
    and ``b_``: what it saw (``lhy`` …), its hands as its partner's camera sees them
    (``shown_lhy`` …), its motor command (a subject's is empty), its PB, its prediction and
    window errors, the pattern it means to play (``intent``) and whether it took the
    initiative this step (``initiative``, 1 or 0)."""
    per_agent = [*SENSORY_NAMES, *(f"shown_{name}" for name in SENSORY_NAMES), *MOTOR_NAMES,
                 *(f"{PB_COLUMNS_PREFIX}{i}" for i in range(pb_size)), "prediction_error",
                 "window_error", *DYAD_AGENT_COLUMNS]
    return [STEP_COLUMN, "time_s",
            *(prefix + name for prefix in DYAD_PREFIXES for name in per_agent)]


class DyadRecorder(SessionRecorder):
    """Writes a two-agent recording row by row (:func:`dyad_columns`); rows are
    :class:`rnnpb.interaction.dyad.DyadStep`. :func:`read_session` reads it back."""

    def __init__(self, path: str | os.PathLike[str], pb_size: int = 4, dt: float = 0.4
                 ) -> None:
        super().__init__(path, pb_size)
        self.columns = dyad_columns(pb_size)
        self.pb_size = pb_size
        self.dt = dt

    def write(self, record) -> None:
        if self._writer is None:
            self.open()
        row: list[object] = [record.step, f"{record.step * self.dt:.4f}"]
        for agent, shown in ((record.a, record.shown_a), (record.b, record.shown_b)):
            result = agent.result
            motor = agent.motor if agent.motor is not None else np.full(len(MOTOR_NAMES), np.nan)
            pb = agent.pb if agent.pb is not None else np.full(self.pb_size, np.nan)
            row += [*(_fmt(v) for v in agent.view), *(_fmt(v) for v in shown),
                    *(_fmt(v) for v in motor), *(_fmt(v) for v in pb),
                    _fmt(result.prediction_error if result is not None else math.nan),
                    _fmt(result.window_error if result is not None else math.nan),
                    agent.intent, int(agent.initiative)]
        self._writer.writerow(row)
        self._handle.flush()
        self.rows += 1


def read_dyad_session(path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """Read a two-agent recording (:func:`dyad_columns`) as :func:`read_session` does."""
    return read_session(path, [STEP_COLUMN, *(prefix + name for prefix in DYAD_PREFIXES
                                              for name in (*SENSORY_NAMES, *MOTOR_NAMES))])
