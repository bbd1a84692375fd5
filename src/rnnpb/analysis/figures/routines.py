"""The routines study's figure (``rnnpb study routines``)."""

from __future__ import annotations

import os
from collections.abc import Sequence as SequenceABC

import numpy as np
from matplotlib.figure import Figure

from rnnpb.analysis.figures._common import PB_COLORS, save


def plot_two_levels(
    lower_pb: np.ndarray,
    higher_pb: np.ndarray,
    switches: SequenceABC[int],
    routine: SequenceABC[str | None],
    path: str | os.PathLike[str],
    title: str = "",
) -> None:
    """The two levels' PBs over one routine: the lower PB (T, P) above, the higher PB (T, Q)
    below with the routine recognised each step written along it; the user's switches as
    dashed lines."""
    fig = Figure(figsize=(8, 4.6))
    top, bottom = fig.subplots(2, 1, sharex=True)
    steps = np.arange(len(lower_pb))
    for i in range(lower_pb.shape[1]):
        top.plot(
            steps, lower_pb[:, i], color=PB_COLORS[i % len(PB_COLORS)], lw=1.2, label=f"PB {i + 1}"
        )
    for i in range(higher_pb.shape[1]):
        bottom.plot(
            steps,
            higher_pb[:, i],
            color=PB_COLORS[i % len(PB_COLORS)],
            lw=1.2,
            ls="-" if i == 0 else ":",
            label=f"PB {i + 1}",
        )
    for ax in (top, bottom):
        for s in switches:
            ax.axvline(s - 0.5, color="k", ls="--", lw=0.8)
        ax.set_ylim(-0.05, 1.05)
    said = [r or "-" for r in routine]
    for t in range(0, len(said), 6):
        bottom.text(t, 1.0, said[t], fontsize=7, va="top")
    top.legend(loc="upper right", fontsize=7, ncol=lower_pb.shape[1], frameon=False)
    bottom.legend(loc="center right", fontsize=7, frameon=False)
    top.set_ylabel("lower PB")
    bottom.set_ylabel("higher PB\n(routine said)")
    bottom.set_xlabel("step")
    title = title or "The two levels over a routine"
    fig.suptitle(f"{title} (dashed: the person switches)", y=0.99)
    save(fig, path)
