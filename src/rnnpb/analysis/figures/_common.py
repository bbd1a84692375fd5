"""What every figure shares: the colours, the joints shown, the atomic PNG writer, and the
small helpers that shade spans and write captions."""

from __future__ import annotations

import os
from collections.abc import Sequence as SequenceABC

import numpy as np
from matplotlib.figure import Figure

from rnnpb._atomic import atomic_write

SENSORY_COLORS = ("#d62728", "#ff9896", "#1f77b4", "#aec7e8")
PB_COLORS = ("#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22")
# The paper plots 6 of the 8 joints: shoulder pitch, roll and elbow of both arms.
PLOTTED_JOINTS = ("lshp", "lshr", "lelp", "rshp", "rshr", "relp")

JUMP_MARK = dict(marker="v", color="k", ms=5, ls="none")


def save(
    fig: Figure, path: str | os.PathLike[str], dpi: int = 110, bbox_inches: str | None = "tight"
) -> None:
    """Write ``fig`` as a PNG, atomically."""
    with atomic_write(path, "wb") as handle:
        fig.savefig(handle, format="png", dpi=dpi, bbox_inches=bbox_inches)


def _shade(ax, spans, color="#eeeeee", label=None):
    for i, (start, end) in enumerate(spans):
        ax.axvspan(start - 0.5, end - 0.5, color=color, zorder=0, label=label if i == 0 else None)


def _segments(labels: SequenceABC[str]) -> list[tuple[int, int, str]]:
    out, start = [], 0
    for t in range(1, len(labels) + 1):
        if t == len(labels) or labels[t] != labels[start]:
            out.append((start, t, labels[start]))
            start = t
    return out


def _spans_text(spans: SequenceABC[tuple[int, int]], limit: int = 4) -> str:
    parts = [f"{a}" if b - a == 1 else f"{a}–{b - 1}" for a, b in spans[:limit]]
    return ", ".join(parts) + (", …" if len(spans) > limit else "")


def _runs(flags: np.ndarray, steps: np.ndarray, minimum: int = 1) -> list[tuple[int, int]]:
    """(first step, end step) of each run of True in ``flags`` at least ``minimum`` long."""
    out, start = [], None
    for t, flag in enumerate([*flags, False]):
        if flag and start is None:
            start = t
        elif not flag and start is not None:
            if t - start >= minimum:
                out.append((int(steps[start]), int(steps[t - 1]) + 1))
            start = None
    return out


def _caption(fig: Figure, text: str) -> None:
    """What the reader sees, under the figure (kept by the tight bounding box)."""
    fig.text(0.01, -0.01, text, ha="left", va="top", fontsize=8, wrap=True, color="#333333")
