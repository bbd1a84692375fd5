"""Sequence files: paired user-hand / robot-joint sequences as CSV (docs/design.md).

A sequence file has a header row and one row per step. Columns: ``step``, the sensory values
``lhy lhz rhy rhz`` (normalized to [0, 1]) and the motor values ``lshp … relp`` (radians).
An optional ``pattern`` column names the movement pattern; without it the pattern is taken from
the file name (``wave_1.csv`` and ``wave-2.csv`` are both pattern ``wave``); either way the name
must pass :func:`pattern_name_problem`. Extra columns are ignored; a column name may appear only
once. A sensory stream (the input of the interaction phase) needs only ``step`` and the
sensory columns.

Files are read as UTF-8, with or without a byte-order mark, with any line endings; only regular
files of at most 256 MiB with lines of at most 64 Ki characters are read. Every problem with a
file raises :class:`rnnpb.errors.DataFileError` naming the file (and the line and column where
there is one); see docs/robustness.md.
"""

from __future__ import annotations

import array
import csv
import math
import os
import re
from collections.abc import Sequence as SequenceABC
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rnnpb._atomic import atomic_write
from rnnpb._reading import MAX_TEXT_FILE_BYTES, bounded_lines, open_regular_file
from rnnpb.errors import DataFileError
from rnnpb.vectors import MOTOR_NAMES, MOTOR_SIZE, SENSORY_NAMES, SENSORY_SIZE, STEP_COLUMN

PATTERN_COLUMN = "pattern"
PATTERN_NAME_MAX_LENGTH = 32
_PATTERN_NAME_PUNCTUATION = frozenset("-_. ")


def pattern_name_problem(name: object) -> str | None:
    """Why ``name`` is not a valid pattern name, or ``None`` if it is one.

    A pattern name is 1 to 32 characters: letters and digits of any script (as
    :meth:`str.isalnum` has them), ``-``, ``_``, ``.`` and spaces, neither starting nor ending
    with a space. Pattern names reach file names, figure titles, reports and the dashboard's
    page, so nothing that markup, a terminal or a shell gives a meaning (``<``, ``&``, quotes,
    control characters, line breaks) is part of one.
    """
    if not isinstance(name, str):
        return f"is not text but {type(name).__name__}"
    if not 1 <= len(name) <= PATTERN_NAME_MAX_LENGTH:
        return f"has {len(name)} characters, expected 1 to {PATTERN_NAME_MAX_LENGTH}"
    if name != name.strip(" "):
        return "starts or ends with a space"
    bad = [c for c in name if not (c.isalnum() or c in _PATTERN_NAME_PUNCTUATION)]
    if bad:
        return (
            f"holds {bad[0]!r}; a pattern name has only letters, digits, '-', '_', '.' and spaces"
        )
    return None


def _shown_name(name: object) -> str:
    text = repr(name)
    return text if len(text) <= 40 else text[:40] + "…"


@dataclass(frozen=True)
class Sequence:
    """One demonstration: a sensory sequence and the paired motor sequence.

    Attributes
    ----------
    sensory : array, shape (n_steps, 4)
        User hand positions ``lhy lhz rhy rhz`` in [0, 1].
    motor : array, shape (n_steps, 8)
        Robot joint angles ``lshp … relp`` in radians.
    pattern : str
        The movement pattern this sequence demonstrates.
    source : str
        Where it came from (a file path or a generator description), for messages.
    """

    sensory: np.ndarray
    motor: np.ndarray
    pattern: str
    source: str = ""
    meta: dict = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        sensory = np.asarray(self.sensory, dtype=np.float64)
        motor = np.asarray(self.motor, dtype=np.float64)
        where = self.source or "sequence"
        if sensory.ndim != 2 or sensory.shape[1] != SENSORY_SIZE:
            raise DataFileError(
                f"{where}: sensory must have shape (n_steps, {SENSORY_SIZE}), got {sensory.shape}"
            )
        if motor.ndim != 2 or motor.shape[1] != MOTOR_SIZE:
            raise DataFileError(
                f"{where}: motor must have shape (n_steps, {MOTOR_SIZE}), got {motor.shape}"
            )
        if sensory.shape[0] != motor.shape[0]:
            raise DataFileError(
                f"{where}: sensory has {sensory.shape[0]} steps but motor has {motor.shape[0]}"
            )
        if sensory.shape[0] < 2:
            raise DataFileError(
                f"{where}: a sequence needs at least 2 steps, got {sensory.shape[0]}"
            )
        if not (np.all(np.isfinite(sensory)) and np.all(np.isfinite(motor))):
            raise DataFileError(f"{where}: contains NaN or infinite values")
        if not self.pattern:
            raise DataFileError(f"{where}: the pattern name is empty")
        problem = pattern_name_problem(self.pattern)
        if problem:
            raise DataFileError(f"{where}: pattern name {_shown_name(self.pattern)} {problem}")
        object.__setattr__(self, "sensory", sensory)
        object.__setattr__(self, "motor", motor)

    @property
    def n_steps(self) -> int:
        return int(self.sensory.shape[0])


@dataclass(frozen=True)
class _Table:
    """The numeric columns a reader asked for, parsed as the file is read (one float64 array
    per file rather than a dict of strings per row: a few bytes of memory per byte of file)."""

    header: list[str]
    values: np.ndarray  # shape (n_rows, n_columns asked for)
    lines: np.ndarray  # shape (n_rows,), the line each row ends on
    label_runs: list[tuple[int, str]]  # (first row, label) of each run of equal labels


def _cell_value(
    text: str, path: Path, line: int, column: str, blank_is_nan: bool, finite: bool
) -> float:
    if blank_is_nan and not text.strip():
        return math.nan
    try:
        value = float(text)
    except ValueError:
        raise DataFileError(
            f"{path}: line {line}, column {column!r}: {text[:40]!r} is not a number"
        ) from None
    if finite and not math.isfinite(value):
        raise DataFileError(
            f"{path}: line {line}, column {column!r}: {text[:40]!r} is not a finite number"
        )
    return value


def _shown(name: str) -> str:
    # A quoted header cell may hold a line break: show such names escaped so the message stays
    # on one line (found by fuzzing).
    return name if name.isprintable() else repr(name)


def _check_header(path: Path, header: list[str], required: SequenceABC[str]) -> None:
    seen: set[str] = set()
    for name in header:
        # An empty header cell (a spreadsheet's trailing comma) names no column; any other name
        # appearing twice would make one of its columns silently win.
        if name and name in seen:
            raise DataFileError(
                f"{path}: column {_shown(name)[:40]} appears more than once in the header"
            )
        seen.add(name)
    missing = [name for name in required if name not in seen]
    if missing:
        shown = ", ".join(_shown(name) for name in header)
        raise DataFileError(
            f"{path}: missing column(s) {', '.join(missing)} (header has {shown[:200]})"
        )


def _read_table(
    path: Path,
    required: SequenceABC[str],
    numeric: SequenceABC[str],
    blank_is_nan: bool = False,
    label_column: str | None = None,
) -> _Table:
    """Read a CSV file into the float columns ``numeric`` (the step column must be finite,
    others too unless ``blank_is_nan``); ``label_column``, if the file has it, as runs."""
    # utf-8-sig: a byte-order mark (spreadsheet programs write one) is not part of the header.
    handle = open_regular_file(
        path, DataFileError, "a CSV file", MAX_TEXT_FILE_BYTES, newline="", encoding="utf-8-sig"
    )
    values = array.array("d")
    lines = array.array("q")
    label_runs: list[tuple[int, str]] = []
    try:
        with handle:
            reader = csv.reader(bounded_lines(handle, path, DataFileError))
            header = next((row for row in reader if row), None)
            if not header:
                raise DataFileError(
                    f"{path}: empty file, expected a CSV header with columns {', '.join(required)}"
                )
            header = [name.strip() for name in header]
            _check_header(path, header, required)
            where = [header.index(name) for name in numeric]
            finite = [not blank_is_nan or name == STEP_COLUMN for name in numeric]
            label_at = header.index(label_column) if label_column in header else None
            n_rows = 0
            for row in reader:
                if not row:  # a blank line
                    continue
                line = reader.line_num
                if len(row) != len(header):
                    raise DataFileError(f"{path}: line {line}: expected {len(header)} fields")
                values.extend(
                    [
                        _cell_value(row[j], path, line, name, blank_is_nan and not fin, fin)
                        for j, name, fin in zip(where, numeric, finite, strict=True)
                    ]
                )
                lines.append(line)
                if label_at is not None:
                    label = row[label_at].strip()
                    if not label:
                        raise DataFileError(f"{path}: line {line}: empty {label_column!r} value")
                    if not label_runs or label_runs[-1][1] != label:
                        label_runs.append((n_rows, label))
                n_rows += 1
    except UnicodeDecodeError:
        raise DataFileError(f"{path}: not a text CSV file (cannot decode as UTF-8)") from None
    except csv.Error as error:
        raise DataFileError(f"{path}: malformed CSV: {error}") from None
    except OSError as error:
        raise DataFileError(f"{path}: cannot read: {error.strerror or error}") from None
    table = np.frombuffer(values, dtype=np.float64).reshape(-1, len(numeric))
    return _Table(header, table, np.frombuffer(lines, dtype=np.int64), label_runs)


def _check_steps(path: Path, table: _Table) -> None:
    steps = table.values[:, 0]
    # Compare neighbours rather than take differences: those overflow for huge step numbers.
    decreasing = steps[1:] <= steps[:-1]
    if np.any(decreasing):
        bad = int(table.lines[int(np.argmax(decreasing)) + 1])
        raise DataFileError(f"{path}: line {bad}: column 'step' must increase row by row")


def pattern_from_filename(path: str | os.PathLike[str]) -> str:
    """``wave_1.csv`` → ``wave``: the file stem without a trailing ``_N`` or ``-N``."""
    stem = Path(path).stem
    return re.sub(r"[-_]\d+$", "", stem) or stem


def read_sequences(path: str | os.PathLike[str]) -> list[Sequence]:
    """Read one sequence CSV; a ``pattern`` column may split it into several sequences."""
    path = Path(path)
    columns = (STEP_COLUMN, *SENSORY_NAMES, *MOTOR_NAMES)
    table = _read_table(path, columns, columns, label_column=PATTERN_COLUMN)
    n_rows = len(table.values)
    if n_rows < 2:
        raise DataFileError(f"{path}: needs at least 2 rows of data, has {n_rows}")
    _check_steps(path, table)
    sensory = table.values[:, 1 : 1 + SENSORY_SIZE]
    motor = table.values[:, 1 + SENSORY_SIZE :]
    if PATTERN_COLUMN not in table.header:
        return [Sequence(sensory, motor, pattern_from_filename(path), str(path))]
    sequences = []
    ends = [start for start, _ in table.label_runs[1:]] + [n_rows]
    for (start, label), end in zip(table.label_runs, ends, strict=True):
        where = f"{path} (lines {table.lines[start]}-{table.lines[end - 1]})"
        sequences.append(Sequence(sensory[start:end], motor[start:end], label, where))
    return sequences


def read_sequence_files(paths: SequenceABC[str | os.PathLike[str]]) -> list[Sequence]:
    """Read sequence CSVs from files and directories (every ``*.csv`` in a directory, sorted)."""
    files: list[Path] = []
    for item in paths:
        item = Path(item)
        if item.is_dir():
            found = sorted(item.glob("*.csv"))
            if not found:
                raise DataFileError(f"{item}: directory holds no .csv files")
            files.extend(found)
        else:
            files.append(item)
    if not files:
        raise DataFileError("no sequence files given")
    sequences: list[Sequence] = []
    for file in files:
        sequences.extend(read_sequences(file))
    return sequences


def write_sequence(
    path: str | os.PathLike[str], sequence: Sequence, with_pattern_column: bool = True
) -> None:
    """Write one sequence as CSV (atomically)."""
    header = [STEP_COLUMN, *SENSORY_NAMES, *MOTOR_NAMES]
    if with_pattern_column:
        header.append(PATTERN_COLUMN)
    with atomic_write(path, "w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        for t in range(sequence.n_steps):
            row = [
                t,
                *(f"{v:.6f}" for v in sequence.sensory[t]),
                *(f"{v:.6f}" for v in sequence.motor[t]),
            ]
            if with_pattern_column:
                row.append(sequence.pattern)
            writer.writerow(row)


def read_sensory_stream(path: str | os.PathLike[str]) -> np.ndarray:
    """Read a sensory stream CSV (``step lhy lhz rhy rhz``), shape (n_steps, 4).

    A value that is not a finite number — an empty cell, ``nan``, ``inf`` or ``-inf`` — means
    the hand was not seen at that step and is returned as NaN, as :meth:`MirrorSystem.step
    <rnnpb.model.MirrorSystem.step>` treats any non-finite value (the network runs on its own
    prediction there). Finite values outside [0, 1] are kept; the mirror system clips them to
    the view plane. Text that is not a number is an error.
    """
    path = Path(path)
    columns = (STEP_COLUMN, *SENSORY_NAMES)
    table = _read_table(path, columns, columns, blank_is_nan=True)
    if not len(table.values):
        raise DataFileError(f"{path}: has a header but no rows of data")
    _check_steps(path, table)
    values = np.array(table.values[:, 1:])
    values[~np.isfinite(values)] = np.nan
    return values


def write_sensory_stream(path: str | os.PathLike[str], sensory: np.ndarray) -> None:
    """Write a sensory stream CSV (atomically); NaN is written as an empty cell."""
    sensory = np.asarray(sensory, dtype=np.float64)
    if sensory.ndim != 2 or sensory.shape[1] != SENSORY_SIZE:
        raise DataFileError(
            f"{path}: sensory stream must have shape (n_steps, {SENSORY_SIZE}), got {sensory.shape}"
        )
    with atomic_write(path, "w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow([STEP_COLUMN, *SENSORY_NAMES])
        for t, row in enumerate(sensory):
            writer.writerow([t, *("" if math.isnan(v) else f"{v:.6f}" for v in row)])
