"""Atomic file writes: a file is either the old one or the complete new one, never half."""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO


def _umask() -> int:
    # Linux reports the umask in /proc; os.umask can only read it by setting it, which would
    # briefly change it for every thread of the process.
    with contextlib.suppress(OSError, ValueError):
        with open("/proc/self/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _mode_for(path: Path) -> int:
    """The mode ``path`` should get: an existing file's own, else what the umask gives."""
    with contextlib.suppress(OSError):
        info = os.stat(path)
        if stat.S_ISREG(info.st_mode):
            return stat.S_IMODE(info.st_mode)
    return 0o666 & ~_umask()


@contextlib.contextmanager
def atomic_write(path: str | os.PathLike[str], mode: str = "w", **kwargs) -> Iterator[IO]:
    """Open a temporary file next to ``path``; on success fsync and rename it over ``path``.

    On any exception the temporary file is removed and ``path`` is left untouched. The file gets
    the mode a plain ``open`` would give it (``0o666`` less the umask), or keeps the mode of the
    file it replaces. An :class:`OSError` about the temporary file (a full disk, a folder that
    is not writable, ``path`` being a directory) is raised naming ``path`` instead, since that
    is the file the user asked for.
    """
    path = Path(path)
    tmp: str | None = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        file_mode = _mode_for(path)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
        # mkstemp creates the file 0600 whatever the umask.
        os.fchmod(fd, file_mode)
        with os.fdopen(fd, mode, **kwargs) as handle:
            yield handle
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, path)
    except BaseException as error:
        if tmp is not None:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(tmp)
        if isinstance(error, OSError) and (
            error.filename is None or _is_temporary(error.filename, path)
        ):
            raise type(error)(error.errno, error.strerror or str(error), str(path)) from error
        raise


def _is_temporary(filename: object, path: Path) -> bool:
    name = os.path.basename(os.fsdecode(filename)) if isinstance(filename, (str, bytes)) else ""
    return name.startswith(f".{path.name}.") and name.endswith(".tmp")


def check_writable(path: str | os.PathLike[str], what: str = "output file") -> None:
    """Raise :class:`~rnnpb.errors.ConfigError` now if :func:`atomic_write` could not write
    ``path``: it is a directory, a parent is not one, or its folder refuses a new file.

    For a command that works for a long time before it writes, so that a bad output path is
    reported before the work rather than after it. Nothing is left behind.
    """
    from rnnpb.errors import ConfigError

    path = Path(path)
    if path.is_dir():
        raise ConfigError(f"{path}: is a directory, expected the name of the {what} to write")
    folder = path.parent
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent  # atomic_write creates the missing folders
    if not folder.is_dir():
        raise ConfigError(f"{path}: cannot write the {what} here: {folder} is not a directory")
    try:
        fd, probe = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
    except OSError as error:
        raise ConfigError(
            f"{path}: cannot write the {what} here: {error.strerror or error}"
        ) from None
    os.close(fd)
    os.unlink(probe)
