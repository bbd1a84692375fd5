"""The novelty study's figures (``rnnpb study novelty``)."""

from __future__ import annotations

import os
from collections.abc import Sequence as SequenceABC

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure

from rnnpb.analysis.figures._common import (
    save,
)

NOVELTY_STATES_SHOWN = ("familiar", "novel", "unstructured", "still", "undecided")


def plot_confusion(
    matrices: dict[str, dict[str, dict[str, int]]], path: str | os.PathLike[str]
) -> None:
    """The novelty states said (columns) per true kind of movement (rows), as shares of the
    row's steps, one panel per learning set (``rnnpb study novelty``)."""
    # At most four panels a row, each wide enough that its row labels stay clear of the
    # panel to its left (seven in one row overlapped).
    columns = min(len(matrices), 4)
    rows = -(-len(matrices) // columns)
    fig = Figure(figsize=(4.2 * columns, 3.6 * rows), layout="constrained")
    axes = fig.subplots(rows, columns, squeeze=False).ravel()
    for ax in axes[len(matrices) :]:
        ax.set_axis_off()
    for ax, (set_name, matrix) in zip(axes, matrices.items(), strict=False):
        kinds = list(matrix)
        grid = np.array(
            [[matrix[k].get(s, 0) for s in NOVELTY_STATES_SHOWN] for k in kinds], dtype=float
        )
        shares = grid / np.maximum(grid.sum(axis=1, keepdims=True), 1)
        ax.imshow(shares, cmap=colormaps["Blues"], vmin=0, vmax=1)
        for (a, b), value in np.ndenumerate(shares):
            ax.text(
                b,
                a,
                f"{100 * value:.0f}",
                ha="center",
                va="center",
                fontsize=8,
                color="white" if value > 0.6 else "black",
            )
        ax.set_xticks(
            range(len(NOVELTY_STATES_SHOWN)),
            NOVELTY_STATES_SHOWN,
            rotation=45,
            ha="right",
            fontsize=8,
        )
        ax.set_yticks(range(len(kinds)), kinds, fontsize=8)
        ax.set_title(f"learning set {set_name}", fontsize=9)
    fig.suptitle("Novelty state said (%) per true movement")
    save(fig, path)


def plot_delays(
    delays: dict[str, SequenceABC[int | None]], path: str | os.PathLike[str], period: int = 12
) -> None:
    """Steps from a novel movement's start until it is called ``novel``, per learning set
    (never: drawn past the axis end)."""
    fig = Figure(figsize=(6.0, 3.2))
    ax = fig.subplots()
    never = 6 * period
    for i, values in enumerate(delays.values()):
        shown = [never if v is None else v for v in values]
        ax.scatter(shown, np.full(len(shown), i) + np.linspace(-0.2, 0.2, len(shown)), s=12)
    ax.axvline(3 * period, color="tab:red", linestyle="--", label="3 cycles")
    ax.set_yticks(range(len(delays)), [f"set {n}" for n in delays])
    ax.set_xlabel(f"steps until called novel (cycle = {period} steps; {never} = never)")
    ax.legend(fontsize=8)
    save(fig, path)


def plot_roc(
    curves: dict[str, SequenceABC[tuple[float, float]]], path: str | os.PathLike[str]
) -> None:
    """ROC of the novelty score (novel movements against learned ones), per learning set."""
    fig = Figure(figsize=(3.6, 3.4))
    ax = fig.subplots()
    for set_name, points in curves.items():
        xy = np.array(sorted(points))
        if len(xy):
            ax.plot(xy[:, 0], xy[:, 1], label=f"set {set_name}")
    ax.plot([0, 1], [0, 1], color="#aaaaaa", linestyle=":")
    ax.set_xlabel("learned steps called novel (false positive rate)")
    ax.set_ylabel("novel steps called novel")
    ax.legend(fontsize=8)
    save(fig, path)
