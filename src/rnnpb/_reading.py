"""Opening the files a user hands rnnpb: regular files only, of bounded size, in bounded lines.

A path may name a FIFO (opening it for reading blocks until a writer comes), a device such as
``/dev/zero`` (endless) or a file of gigabytes without a line break. Each reader therefore
checks what the path is before it opens it, opens it without blocking, and reads it through
:func:`bounded_lines`, so that none of these can hang the process or exhaust its memory. The
limits are documented in docs/robustness.md.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Iterator
from pathlib import Path
from typing import IO

from rnnpb.errors import RnnpbError

MAX_TEXT_FILE_BYTES = 256 * 2**20
"""Largest sequence CSV, sensory stream or session recording read (256 MiB)."""
MAX_LINE_CHARS = 65_536
"""Longest line of a CSV file, its line break included (64 Ki characters)."""


def _size(n_bytes: int) -> str:
    return f"{n_bytes / 2**20:.0f} MiB" if n_bytes >= 2**20 else f"{n_bytes:,} bytes"


def open_regular_file(
    path: Path, error: type[RnnpbError], expected: str, max_bytes: int, mode: str = "r", **kwargs
) -> IO:
    """Open ``path`` for reading if it is a regular file of at most ``max_bytes``.

    Raises ``error`` naming the path for a missing path, a directory, anything that is not a
    regular file (FIFO, device, socket), a file over ``max_bytes`` and a file the system will
    not open. ``expected`` says what the file should be ("a CSV file"), for those messages.
    The file is opened with ``O_NONBLOCK`` and checked again through its descriptor, so a path
    replaced by a FIFO between the check and the open still cannot block.
    """
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise error(f"{path}: no such file") from None
    except OSError as problem:
        raise error(f"{path}: cannot read: {problem.strerror or problem}") from None
    _check_kind(path, info, error, expected, max_bytes)
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except OSError as problem:
        raise error(f"{path}: cannot read: {problem.strerror or problem}") from None
    try:
        _check_kind(path, os.fstat(fd), error, expected, max_bytes)
        return open(fd, mode, **kwargs)
    except BaseException:
        os.close(fd)
        raise


def _check_kind(
    path: Path, info: os.stat_result, error: type[RnnpbError], expected: str, max_bytes: int
) -> None:
    if stat.S_ISDIR(info.st_mode):
        raise error(f"{path}: is a directory, expected {expected}")
    if not stat.S_ISREG(info.st_mode):
        raise error(
            f"{path}: is not a regular file (a FIFO, device or socket), expected {expected}"
        )
    if info.st_size > max_bytes:
        raise error(
            f"{path}: is {_size(info.st_size)}, larger than the {_size(max_bytes)} "
            f"rnnpb reads as {expected}"
        )


def bounded_lines(
    handle: IO[str],
    path: Path,
    error: type[RnnpbError],
    max_chars: int = MAX_LINE_CHARS,
    max_total: int = MAX_TEXT_FILE_BYTES,
) -> Iterator[str]:
    """The lines of a text file opened with ``newline=""``, each at most ``max_chars`` long.

    A longer line, or more than ``max_total`` characters in all (a file that grows while it is
    read), raises ``error`` naming the file and the line, before more of it is held in memory.
    """
    number = total = 0
    while line := handle.readline(max_chars + 1):
        number += 1
        total += len(line)
        if len(line) > max_chars:
            raise error(
                f"{path}: line {number} is longer than {max_chars:,} characters (a CSV "
                "file of rnnpb has short lines)"
            )
        if total > max_total:
            raise error(f"{path}: grew past {_size(max_total)} while being read")
        yield line
