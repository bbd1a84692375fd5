"""The progress bar of long commands: tqdm on stderr, only on a terminal."""

from __future__ import annotations

import sys
from typing import Any


def progress_bar(
    total: int | None = None,
    *,
    unit: str = "it",
    desc: str = "",
    disable: bool = False,
    **options: Any,
):
    """A tqdm bar on stderr, or one that shows nothing when ``disable`` is set or stderr is
    not a terminal (a log file or a pipe gets no carriage-return clutter). Usable as a context
    manager; ``update``, ``set_postfix`` and ``close`` work either way."""
    from tqdm.auto import tqdm

    quiet = disable or not _is_terminal(sys.stderr)
    return tqdm(
        total=total,
        unit=unit,
        desc=desc,
        disable=quiet,
        file=sys.stderr,
        dynamic_ncols=True,
        leave=False,
        **options,
    )


def _is_terminal(stream: Any) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # replaced or closed stream
        return False
