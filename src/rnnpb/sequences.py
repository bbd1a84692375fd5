"""Sequence files: paired user-hand / robot-joint sequences as CSV (docs/design.md).

A sequence file has a header row and one row per step. Columns: ``step``, the sensory values
``lhy lhz rhy rhz`` (normalized to [0, 1]) and the motor values ``lshp … relp`` (radians).
An optional ``pattern`` column names the movement pattern; without it the pattern is taken from
the file name (``wave_1.csv`` and ``wave-2.csv`` are both pattern ``wave``). Extra columns are
ignored. A sensory stream (the input of the interaction phase) needs only ``step`` and the
sensory columns.

Files are read as UTF-8, with or without a byte-order mark, with any line endings. Every problem
with a file raises :class:`rnnpb.errors.DataFileError` naming the file (and the line and column
where there is one); see docs/robustness.md.
"""

from __future__ import annotations

import csv
import math
import os
import re
from collections.abc import Sequence as SequenceABC
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rnnpb._atomic import atomic_write
from rnnpb.errors import DataFileError
from rnnpb.vectors import MOTOR_NAMES, MOTOR_SIZE, SENSORY_NAMES, SENSORY_SIZE, STEP_COLUMN

PATTERN_COLUMN = "pattern"


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
            raise DataFileError(f"{where}: sensory must have shape (n_steps, {SENSORY_SIZE}), "
                                f"got {sensory.shape}")
        if motor.ndim != 2 or motor.shape[1] != MOTOR_SIZE:
            raise DataFileError(f"{where}: motor must have shape (n_steps, {MOTOR_SIZE}), "
                                f"got {motor.shape}")
        if sensory.shape[0] != motor.shape[0]:
            raise DataFileError(f"{where}: sensory has {sensory.shape[0]} steps but motor has "
                                f"{motor.shape[0]}")
        if sensory.shape[0] < 2:
            raise DataFileError(f"{where}: a sequence needs at least 2 steps, got "
                                f"{sensory.shape[0]}")
        if not (np.all(np.isfinite(sensory)) and np.all(np.isfinite(motor))):
            raise DataFileError(f"{where}: contains NaN or infinite values")
        if not self.pattern:
            raise DataFileError(f"{where}: the pattern name is empty")
        object.__setattr__(self, "sensory", sensory)
        object.__setattr__(self, "motor", motor)

    @property
    def n_steps(self) -> int:
        return int(self.sensory.shape[0])


def _parse_float(text: str, path: Path, line: int, column: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise DataFileError(f"{path}: line {line}, column {column!r}: {text!r} is not a "
                            "number") from None
    return value


def _read_rows(path: Path, required: SequenceABC[str]) -> tuple[list[str], list[dict[str, str]]]:
    if not path.exists():
        raise DataFileError(f"{path}: no such file")
    if path.is_dir():
        raise DataFileError(f"{path}: is a directory, expected a CSV file")
    try:
        # utf-8-sig: a byte-order mark (spreadsheet programs write one) is not part of the header.
        with open(path, newline="", encoding="utf-8-sig") as handle:
            reader = csv.DictReader(handle)
            header = reader.fieldnames
            if not header:
                raise DataFileError(f"{path}: empty file, expected a CSV header with columns "
                                    f"{', '.join(required)}")
            header = [name.strip() for name in header]
            reader.fieldnames = header
            missing = [name for name in required if name not in header]
            if missing:
                # A quoted header cell may hold a line break: show such names escaped so the
                # message stays on one line (found by fuzzing).
                shown = ", ".join(name if name.isprintable() else repr(name) for name in header)
                raise DataFileError(f"{path}: missing column(s) {', '.join(missing)} "
                                    f"(header has {shown[:200]})")
            rows = []
            for row in reader:
                # DictReader puts surplus fields under None and fills missing ones with None.
                if None in row or None in row.values():
                    raise DataFileError(f"{path}: line {reader.line_num}: expected "
                                        f"{len(header)} fields")
                rows.append(row)
    except UnicodeDecodeError:
        raise DataFileError(f"{path}: not a text CSV file (cannot decode as UTF-8)") from None
    except csv.Error as error:
        raise DataFileError(f"{path}: malformed CSV: {error}") from None
    except OSError as error:
        raise DataFileError(f"{path}: cannot read: {error.strerror or error}") from None
    return header, rows


def _matrix(path: Path, rows: list[dict[str, str]], columns: SequenceABC[str],
            allow_nan: bool = False) -> np.ndarray:
    out = np.empty((len(rows), len(columns)))
    for i, row in enumerate(rows):
        for j, name in enumerate(columns):
            value = _parse_float(row[name], path, i + 2, name)
            if not allow_nan and not math.isfinite(value):
                raise DataFileError(f"{path}: line {i + 2}, column {name!r}: {row[name]!r} is not "
                                    "a finite number")
            out[i, j] = value
    return out


def _check_steps(path: Path, rows: list[dict[str, str]]) -> None:
    steps = _matrix(path, rows, [STEP_COLUMN])[:, 0]
    # Compare neighbours rather than take differences: those overflow for huge step numbers.
    decreasing = steps[1:] <= steps[:-1]
    if np.any(decreasing):
        bad = int(np.argmax(decreasing)) + 3
        raise DataFileError(f"{path}: line {bad}: column 'step' must increase row by row")


def pattern_from_filename(path: str | os.PathLike[str]) -> str:
    """``wave_1.csv`` → ``wave``: the file stem without a trailing ``_N`` or ``-N``."""
    stem = Path(path).stem
    return re.sub(r"[-_]\d+$", "", stem) or stem


def read_sequences(path: str | os.PathLike[str]) -> list[Sequence]:
    """Read one sequence CSV; a ``pattern`` column may split it into several sequences."""
    path = Path(path)
    header, rows = _read_rows(path, (STEP_COLUMN, *SENSORY_NAMES, *MOTOR_NAMES))
    if len(rows) < 2:
        raise DataFileError(f"{path}: needs at least 2 rows of data, has {len(rows)}")
    _check_steps(path, rows)
    sensory = _matrix(path, rows, SENSORY_NAMES)
    motor = _matrix(path, rows, MOTOR_NAMES)
    if PATTERN_COLUMN not in header:
        return [Sequence(sensory, motor, pattern_from_filename(path), str(path))]
    labels = [row[PATTERN_COLUMN].strip() for row in rows]
    if any(not label for label in labels):
        line = labels.index("") + 2
        raise DataFileError(f"{path}: line {line}: empty 'pattern' value")
    sequences, start = [], 0
    for i in range(1, len(labels) + 1):
        if i == len(labels) or labels[i] != labels[start]:
            where = f"{path} (rows {start + 2}-{i + 1})"
            sequences.append(Sequence(sensory[start:i], motor[start:i], labels[start], where))
            start = i
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


def write_sequence(path: str | os.PathLike[str], sequence: Sequence,
                   with_pattern_column: bool = True) -> None:
    """Write one sequence as CSV (atomically)."""
    header = [STEP_COLUMN, *SENSORY_NAMES, *MOTOR_NAMES]
    if with_pattern_column:
        header.append(PATTERN_COLUMN)
    with atomic_write(path, "w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        for t in range(sequence.n_steps):
            row = [t, *(f"{v:.6f}" for v in sequence.sensory[t]),
                   *(f"{v:.6f}" for v in sequence.motor[t])]
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
    _, rows = _read_rows(path, (STEP_COLUMN, *SENSORY_NAMES))
    if not rows:
        raise DataFileError(f"{path}: has a header but no rows of data")
    _check_steps(path, rows)
    for row in rows:
        for name in SENSORY_NAMES:
            if row[name].strip() == "":
                row[name] = "nan"
    values = _matrix(path, rows, SENSORY_NAMES, allow_nan=True)
    values[~np.isfinite(values)] = np.nan
    return values


def write_sensory_stream(path: str | os.PathLike[str], sensory: np.ndarray) -> None:
    """Write a sensory stream CSV (atomically); NaN is written as an empty cell."""
    sensory = np.asarray(sensory, dtype=np.float64)
    if sensory.ndim != 2 or sensory.shape[1] != SENSORY_SIZE:
        raise DataFileError(f"{path}: sensory stream must have shape (n_steps, {SENSORY_SIZE}), "
                            f"got {sensory.shape}")
    with atomic_write(path, "w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow([STEP_COLUMN, *SENSORY_NAMES])
        for t, row in enumerate(sensory):
            writer.writerow([t, *("" if math.isnan(v) else f"{v:.6f}" for v in row)])
