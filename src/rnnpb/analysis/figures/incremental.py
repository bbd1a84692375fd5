"""The incremental study's figure (``rnnpb study incremental``)."""

from __future__ import annotations

import os
from collections.abc import Sequence as SequenceABC

from matplotlib.figure import Figure

from rnnpb.analysis.figures._common import (
    save,
)


def plot_forgetting(
    errors: dict[str, dict[str, SequenceABC[float]]], path: str | os.PathLike[str], limit: float
) -> None:
    """Forgetting per consolidation method: how far each old pattern's closed-loop cycle
    moved from the starting model's (RMS, normalized joints), one panel per method, one
    column of points per learning set, the target ``limit`` dashed."""
    fig = Figure(figsize=(2.6 * max(len(errors), 1), 3.2))
    axes = fig.subplots(1, max(len(errors), 1), squeeze=False, sharey=True)
    values = [v for sets in errors.values() for vs in sets.values() for v in vs]
    top = max([limit * 2, *values])
    bottom = min([limit / 50, *(v for v in values if v > 0)])
    for ax, (method, sets) in zip(axes[0], errors.items(), strict=False):
        for k, values in enumerate(sets.values()):
            ax.plot([k] * len(values), values, "o", color="tab:blue", alpha=0.7)
        ax.set_xticks(range(len(sets)), list(sets))
        ax.axhline(limit, color="k", ls="--", lw=0.8)
        ax.set_yscale("log")
        ax.set_ylim(bottom / 1.5, top * 1.5)
        ax.set_title(method)
        ax.set_xlabel("learning set")
    axes[0][0].set_ylabel("old pattern's generation vs before\n(RMS, normalized joints)")
    fig.suptitle(f"Forgetting by method (target <= {limit:g})", y=1.02)
    save(fig, path)
