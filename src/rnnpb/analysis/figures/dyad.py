"""The dyad study's figures: two agents imitating each other (``rnnpb study dyad``,
docs/dyad.md)."""

from __future__ import annotations

import os
from collections.abc import Sequence as SequenceABC

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure

from rnnpb.analysis.figures._common import (
    PB_COLORS,
    SENSORY_COLORS,
    _shade,
    save,
)
from rnnpb.vectors import (
    SENSORY_NAMES,
)


def plot_dyad(
    run: dict[str, np.ndarray],
    coherent: np.ndarray,
    path: str | os.PathLike[str],
    title: str = "",
    names: tuple[str, str] = ("A", "B"),
    shifts: SequenceABC[tuple[int, str]] = (),
) -> None:
    """A two-agent run like the paper's figures: each agent's hands (``x_shown``) and PB
    (``x_pb``), coherent steps shaded, pattern shifts marked with their leader."""
    fig = Figure(figsize=(9, 7))
    axes = fig.subplots(4, 1, sharex=True)
    spans, start = [], None
    for t, c in enumerate(list(coherent) + [False]):
        if c and start is None:
            start = t
        elif not c and start is not None:
            spans.append((start, t))
            start = None
    for i, (side, name) in enumerate(zip(("a", "b"), names, strict=False)):
        ax_hands, ax_pb = axes[2 * i], axes[2 * i + 1]
        for j, label in enumerate(SENSORY_NAMES):
            ax_hands.plot(run[f"{side}_shown"][:, j], color=SENSORY_COLORS[j], lw=0.9, label=label)
        ax_hands.set_ylabel(f"{name}: hands")
        pb = run[f"{side}_pb"]
        if np.isfinite(pb).any():
            for j in range(pb.shape[1]):
                ax_pb.plot(pb[:, j], color=PB_COLORS[j % len(PB_COLORS)], lw=0.9, label=f"pb{j}")
            ax_pb.set_ylim(-0.05, 1.05)
        ax_pb.set_ylabel(f"{name}: PB")
        for ax in (ax_hands, ax_pb):
            _shade(ax, spans, color="#dff0d8", label="coherent" if ax is axes[0] else None)
            for step, leader in shifts:
                ax.axvline(step, color="k", lw=0.7, ls="--")
                if ax is axes[0]:
                    ax.annotate(
                        f"led by {leader or '?'}",
                        (step, 1.0),
                        fontsize=7,
                        xycoords=("data", "axes fraction"),
                        va="bottom",
                    )
    axes[0].legend(fontsize=7, ncol=5, loc="upper right")
    axes[1].legend(fontsize=7, ncol=4, loc="upper right")
    axes[-1].set_xlabel("step")
    if title:
        fig.suptitle(title)
    save(fig, path)


def plot_phase_diagram(
    rates: SequenceABC[float],
    panels: dict[str, dict[str, np.ndarray]],
    path: str | os.PathLike[str],
) -> None:
    """Heat maps over agent A's (rows) and B's (columns) adaptation: one row of panels per
    setting (``panels[label][measure]``, each (len(rates), len(rates)))."""
    measures = ("coherent share", "shifts per 200 steps", "leader index")
    limits = {"coherent share": (0, 1), "shifts per 200 steps": (0, None), "leader index": (-1, 1)}
    fig = Figure(figsize=(11, 3.4 * len(panels)), layout="constrained")
    axes = np.atleast_2d(fig.subplots(len(panels), len(measures)))
    for row, (label, values) in zip(axes, panels.items(), strict=False):
        for ax, measure in zip(row, measures, strict=False):
            grid = np.asarray(values[measure], dtype=np.float64)
            low, high = limits[measure]
            image = ax.imshow(
                grid,
                origin="lower",
                vmin=low,
                vmax=high if high is not None else max(1.0, np.nanmax(grid)),
                cmap="coolwarm" if measure == "leader index" else "viridis",
            )
            for (i, j), v in np.ndenumerate(grid):
                ax.text(
                    j,
                    i,
                    "no shift" if not np.isfinite(v) else f"{v:.2f}",
                    ha="center",
                    va="center",
                    fontsize=7,
                    color="w" if np.isfinite(v) else "k",
                )
            ax.set_xticks(range(len(rates)), [f"{r:g}" for r in rates])
            ax.set_yticks(range(len(rates)), [f"{r:g}" for r in rates])
            ax.set_xlabel("B's adaptation")
            ax.set_ylabel("A's adaptation")
            ax.set_title(f"{measure}\n({label})", fontsize=8)
            fig.colorbar(image, ax=ax, shrink=0.8)
    save(fig, path)


def plot_patterns_found(
    curves: dict[str, np.ndarray], dt: float, total: int, path: str | os.PathLike[str]
) -> None:
    """Patterns found over simulated time, one line per run (``curves[label]`` (n,))."""
    fig = Figure(figsize=(7, 3.5))
    ax = fig.subplots()
    cmap = colormaps["tab10"]
    for i, (label, found) in enumerate(curves.items()):
        minutes = np.arange(len(found)) * dt / 60.0
        ax.step(minutes, found, where="post", color=cmap(i % 10), lw=1, label=label)
    ax.axhline(total, color="k", ls="--", lw=0.8, label="all learned patterns")
    ax.set_xlabel("simulated minutes")
    ax.set_ylabel("patterns found")
    ax.set_ylim(-0.1, total + 0.3)
    if len(curves) <= 12:
        ax.legend(fontsize=6, ncol=2)
    save(fig, path)
