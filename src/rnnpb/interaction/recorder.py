"""Session recordings: one CSV row per step of the interaction loop, flushed as it goes.

Columns: ``step``, ``time_s``, the observed hands ``lhy lhz rhy rhz`` (empty where the hand was
not seen), the hands the network predicted for this step one step before (``pred_lhy`` …), the
motor command sent (``lshp`` … ``relp``, radians), the PB (``pb0`` …), ``prediction_error``
(mean squared error of that prediction), ``window_error`` (after the PB regression),
``lost_left``/``lost_right`` (1 where the hand was not seen), ``held`` (1 where the regression
failed numerically and the last good state was kept), what the step recognised —
``recognised`` (the learned pattern's name, empty when none), ``confidence`` (in [0, 1]) and
``novelty`` (``familiar``, ``novel``, ``unstructured``, ``still``, or empty while undecided;
:mod:`rnnpb.model.recognition`) —, when the source knows it, the ground truth
``truth_pattern``, and from the command filter (docs/safety.md) ``unsafe`` (why the
generated command was unsafe, empty when safe) and ``filtered`` (what the filter did:
``slowed``, ``shortened``, ``held``, or empty), and from the meta-level ``regime`` (what
drove the motion: ``following``, ``lost``, ``still``, ``novel``, ``unstructured``) and
``inhibited`` (why the generated command was held, empty when it was sent). With a routine
level (``interact --routines``) two more: ``routine`` (the routine recognised, empty when
none) and ``anticipated`` (the movement it says comes next).

Every row is flushed to the operating system when written, so a session interrupted by Ctrl-C
or a crash keeps every step up to the last one written. A row is complete only with its line
break: :func:`read_session` ignores a last line that does not end with one (the row being
written when the process died); anything else malformed is an error naming the file and line.
"""

from __future__ import annotations

import csv
import math
import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb.errors import DataFileError
from rnnpb.vectors import (
    MOTOR_NAMES,
    PREDICTED_PREFIX,
    SENSORY_NAMES,
    STEP_COLUMN,
    TRUTH_PATTERN_COLUMN,
    pb_column,
)

TEXT_COLUMNS = (
    "recognised",
    "novelty",
    TRUTH_PATTERN_COLUMN,
    "unsafe",
    "filtered",
    "regime",
    "inhibited",
    "routine",
    "anticipated",
)
"""The columns that hold words, not numbers."""
DYAD_PREFIXES = ("a_", "b_")
"""Each agent's columns in a two-agent recording (:func:`dyad_columns`)."""


def _is_text(name: str) -> bool:
    """Whether column ``name`` holds words (an agent's ``a_``/``b_`` columns included)."""
    for prefix in DYAD_PREFIXES:
        if name.startswith(prefix):
            return name[len(prefix) :] in (*TEXT_COLUMNS, "intent")
    return name in TEXT_COLUMNS


def session_columns(pb_size: int) -> list[str]:
    return [
        STEP_COLUMN,
        "time_s",
        *SENSORY_NAMES,
        *(PREDICTED_PREFIX + name for name in SENSORY_NAMES),
        *MOTOR_NAMES,
        *(pb_column(i) for i in range(pb_size)),
        "prediction_error",
        "window_error",
        "lost_left",
        "lost_right",
        "held",
        "recognised",
        "confidence",
        "novelty",
        TRUTH_PATTERN_COLUMN,
        "unsafe",
        "filtered",
        "regime",
        "inhibited",
    ]


def _fmt(value: float) -> str:
    return "" if not math.isfinite(value) else f"{value:.6g}"


class SessionRecorder:
    """Writes a session recording row by row (a context manager)."""

    def __init__(
        self,
        path: str | os.PathLike[str],
        pb_size: int = 4,
        extra_columns: tuple[str, ...] = (),
        extra: Callable[[Any], Sequence[str]] | None = None,
    ) -> None:
        """``extra_columns``: columns after the usual ones, their values per step from
        ``extra(record)`` (the routine level's ``routine`` and ``anticipated``)."""
        self.path = Path(path)
        self.columns = session_columns(pb_size) + list(extra_columns)
        self._extra = extra if extra_columns else None
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
        assert self._writer is not None and self._handle is not None  # open() set both
        seen = np.isfinite(record.observed)
        row = [
            record.step,
            f"{record.time_s:.4f}",
            *(_fmt(v) for v in record.observed),
            *(_fmt(v) for v in record.predicted),
            *(f"{v:.6f}" for v in record.motor),
            *(f"{v:.6f}" for v in record.pb),
            _fmt(record.prediction_error),
            _fmt(record.window_error),
            int(not seen[:2].all()),
            int(not seen[2:].all()),
            int(record.held),
            record.recognised or "",
            _fmt(record.confidence),
            record.novelty,
            record.truth.get("pattern", ""),
            record.unsafe,
            record.filtered,
            record.regime,
            record.inhibited,
        ]
        if self._extra is not None:
            row += list(self._extra(record))
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


def read_session(
    path: str | os.PathLike[str], required: list[str] | None = None
) -> dict[str, np.ndarray]:
    """Read a session recording into arrays by column (empty cells → NaN; strings kept).

    A last line without its line break is a row cut short by an interrupted write and is left
    out; every other row must have one field per column and numbers (or nothing) in the numeric
    columns, else :class:`DataFileError` names the file, line and column. Only a regular file of
    at most 256 MiB with lines of at most 64 Ki characters is read, and each column name may
    appear once.
    """
    import array
    import re

    from rnnpb._reading import MAX_TEXT_FILE_BYTES, bounded_lines, open_regular_file

    path = Path(path)
    # surrogateescape: bytes that are not UTF-8 are kept as lone surrogates rather than raised
    # at once, because a write cut short may split a character in the unfinished last row, which
    # is left out anyway; in any other line they are an error.
    handle = open_regular_file(
        path,
        DataFileError,
        "a session recording (.csv)",
        MAX_TEXT_FILE_BYTES,
        newline="",
        encoding="utf-8-sig",
        errors="surrogateescape",
    )
    undecodable = re.compile("[\udc80-\udcff]")

    def complete_lines():
        previous, any_break = None, False
        for line in bounded_lines(handle, path, DataFileError):
            if previous is not None:
                yield previous
            any_break = any_break or line.endswith("\n")
            previous = line
        if previous is not None and (previous.endswith("\n") or not any_break):
            yield previous

    def decoded(lines):
        for line in lines:
            if undecodable.search(line):
                raise DataFileError(f"{path}: not a text CSV file (cannot decode as UTF-8)")
            yield line

    columns: dict[str, array.array | list] = {}
    try:
        with handle:
            reader = csv.reader(decoded(complete_lines()))
            header = next(reader, None)
            if not header:
                raise DataFileError(f"{path}: empty file, expected a session recording header")
            header = [name.strip() for name in header]
            required = required or [STEP_COLUMN, *SENSORY_NAMES, *MOTOR_NAMES]
            missing = [c for c in required if c not in header]
            if missing:
                raise DataFileError(
                    f"{path}: not a session recording: missing column(s) {', '.join(missing)}"
                )
            repeated = sorted({name for name in header if name and header.count(name) > 1})
            if repeated:
                raise DataFileError(
                    f"{path}: column(s) {', '.join(map(repr, repeated))[:200]} "
                    "appear more than once in the header"
                )
            columns = {name: [] if _is_text(name) else array.array("d") for name in header}
            cells = list(columns.values())
            numeric = [not isinstance(cell, list) for cell in cells]
            labels: dict[str, str] = {}  # one string object per distinct truth label
            for row in reader:
                if not row:
                    continue
                if len(row) != len(header):
                    raise DataFileError(
                        f"{path}: line {reader.line_num}: expected "
                        f"{len(header)} fields, found {len(row)}"
                    )
                for name, value, cell, is_number in zip(header, row, cells, numeric, strict=True):
                    if not is_number:
                        cell.append(labels.setdefault(value, value))
                        continue
                    try:
                        cell.append(float(value) if value.strip() else math.nan)
                    except ValueError:
                        raise DataFileError(
                            f"{path}: line {reader.line_num}, column {name!r}: "
                            f"{value[:40]!r} is not a number"
                        ) from None
    except csv.Error as error:
        raise DataFileError(f"{path}: malformed CSV: {error}") from None
    except OSError as error:
        raise DataFileError(f"{path}: cannot read: {error.strerror or error}") from None
    return {
        name: np.array(cell, dtype=object)
        if isinstance(cell, list)
        else np.frombuffer(cell, dtype=np.float64)
        for name, cell in columns.items()
    }


# --- two-agent recordings ------------------------------------------------------------------
DYAD_AGENT_COLUMNS = ("intent", "initiative")


def dyad_columns(pb_size: int) -> list[str]:
    """A two-agent recording: ``step``, ``time_s``, then each agent's columns prefixed ``a_``
    and ``b_``: what it saw (``lhy`` …), its hands as its partner's camera sees them
    (``shown_lhy`` …), its motor command (a subject's is empty), its PB, its prediction and
    window errors, the pattern it means to play (``intent``) and whether it took the
    initiative this step (``initiative``, 1 or 0)."""
    per_agent = [
        *SENSORY_NAMES,
        *(f"shown_{name}" for name in SENSORY_NAMES),
        *MOTOR_NAMES,
        *(pb_column(i) for i in range(pb_size)),
        "prediction_error",
        "window_error",
        *DYAD_AGENT_COLUMNS,
    ]
    return [
        STEP_COLUMN,
        "time_s",
        *(prefix + name for prefix in DYAD_PREFIXES for name in per_agent),
    ]


class DyadRecorder(SessionRecorder):
    """Writes a two-agent recording row by row (:func:`dyad_columns`); rows are
    :class:`rnnpb.interaction.dyad.DyadStep`. :func:`read_session` reads it back."""

    def __init__(self, path: str | os.PathLike[str], pb_size: int = 4, dt: float = 0.4) -> None:
        super().__init__(path, pb_size)
        self.columns = dyad_columns(pb_size)
        self.pb_size = pb_size
        self.dt = dt

    def write(self, record) -> None:
        if self._writer is None:
            self.open()
        assert self._writer is not None and self._handle is not None  # open() set both
        row: list[object] = [record.step, f"{record.step * self.dt:.4f}"]
        for agent, shown in ((record.a, record.shown_a), (record.b, record.shown_b)):
            result = agent.result
            motor = agent.motor if agent.motor is not None else np.full(len(MOTOR_NAMES), np.nan)
            pb = agent.pb if agent.pb is not None else np.full(self.pb_size, np.nan)
            row += [
                *(_fmt(v) for v in agent.view),
                *(_fmt(v) for v in shown),
                *(_fmt(v) for v in motor),
                *(_fmt(v) for v in pb),
                _fmt(result.prediction_error if result is not None else math.nan),
                _fmt(result.window_error if result is not None else math.nan),
                agent.intent,
                int(agent.initiative),
            ]
        if self._extra is not None:
            row += list(self._extra(record))
        self._writer.writerow(row)
        self._handle.flush()
        self.rows += 1


def read_dyad_session(path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """Read a two-agent recording (:func:`dyad_columns`) as :func:`read_session` does."""
    return read_session(
        path,
        [
            STEP_COLUMN,
            *(prefix + name for prefix in DYAD_PREFIXES for name in (*SENSORY_NAMES, *MOTOR_NAMES)),
        ],
    )
