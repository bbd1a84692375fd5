"""The people study's figure (``rnnpb study people``)."""

from __future__ import annotations

import os
from collections.abc import Sequence as SequenceABC

import numpy as np
from matplotlib.figure import Figure

from rnnpb.analysis.figures._common import save


def plot_following(
    runs: dict[str, dict[str, SequenceABC]],
    movements: SequenceABC[str],
    path: str | os.PathLike[str],
    settle_steps: int,
    dt: float = 0.4,
) -> None:
    """Per performer followed: the movement performed (thick bar) and the pattern the robot
    recognised (dots) over the steps (``dt`` seconds each), the unjudged first
    ``settle_steps`` of each movement shaded, and the steps whose command the safety filter
    changed marked in red."""
    fig = Figure(figsize=(9.0, 1.1 + 1.2 * max(len(runs), 1)), layout="constrained")
    axes = fig.subplots(max(len(runs), 1), 1, squeeze=False, sharex=True)[:, 0]
    rows = {name: k for k, name in enumerate(movements)}
    for ax, (performer, run) in zip(axes, runs.items(), strict=False):
        labels = list(run["labels"])
        steps = np.arange(len(labels))
        ax.scatter(steps, [rows[m] for m in labels], s=14, marker="s", color="#bbbbbb", lw=0)
        recognised = [(t, rows[r]) for t, r in enumerate(run["recognised"]) if r in rows]
        if recognised:
            t, y = zip(*recognised, strict=True)
            ax.scatter(t, y, s=5, color="tab:blue", lw=0)
        for t in range(len(labels)):
            if t == 0 or labels[t] != labels[t - 1]:
                ax.axvspan(t - 0.5, t + settle_steps - 0.5, color="#f2f2f2", zorder=0)
        filtered = [t for t, f in enumerate(run["filtered"]) if f]
        if filtered:
            ax.scatter(filtered, [-0.6] * len(filtered), s=8, color="tab:red", marker="|")
        ax.set_yticks(range(len(movements)), list(movements), fontsize=7)
        ax.set_ylim(-0.9, len(movements) - 0.4)
        # the performer above its panel: a label beside it would run into its neighbours'
        ax.set_title(performer, fontsize=8, loc="left", pad=2)
    axes[-1].set_xlabel(
        f"step, {dt:g} s each (grey: performed; blue: recognised; red: command filtered)"
    )
    fig.suptitle("Another performer's movements, followed")
    save(fig, path)
