"""The safety study's figure: the map of PB space (``rnnpb study safety``, docs/safety.md)."""

from __future__ import annotations

import os
from collections.abc import Sequence as SequenceABC

import numpy as np
from matplotlib.figure import Figure

from rnnpb.analysis.figures._common import (
    save,
)


def plot_pb_safety_map(
    slices: SequenceABC[tuple[str, np.ndarray, np.ndarray]],
    learned: dict[str, np.ndarray],
    dims: tuple[int, int],
    path: str | os.PathLike[str],
) -> None:
    """The safety map of PB space (docs/safety.md): per slice, the learned risk (top) and the
    familiarity (bottom) over PB dimensions ``dims`` in [0, 1]², the other PB values fixed as
    the slice's title says; the learned PBs marked.

    ``slices``: (title, risk (G, G), familiarity (G, G)), rows along ``dims[1]``, columns
    along ``dims[0]``.
    """
    n = len(slices)
    fig = Figure(figsize=(3.2 * n, 6.0))
    axes = fig.subplots(2, n, squeeze=False)
    for j, (title, risk, familiar) in enumerate(slices):
        for i, (values, label, cmap) in enumerate(
            ((risk, "risk", "Reds"), (familiar, "familiarity", "Blues"))
        ):
            ax = axes[i, j]
            image = ax.imshow(
                values,
                origin="lower",
                extent=(0, 1, 0, 1),
                vmin=0,
                vmax=1,
                cmap=cmap,
                aspect="equal",
            )
            for name, pb in learned.items():
                ax.plot(pb[dims[0]], pb[dims[1]], "k*", ms=9)
                ax.annotate(
                    name,
                    (pb[dims[0]], pb[dims[1]]),
                    textcoords="offset points",
                    xytext=(4, 4),
                    fontsize=8,
                )
            ax.set_xlabel(f"pb{dims[0]}")
            ax.set_ylabel(f"pb{dims[1]}")
            ax.set_title(f"{label}: {title}", fontsize=8)
            fig.colorbar(image, ax=ax, fraction=0.046)
    fig.tight_layout()
    save(fig, path)
