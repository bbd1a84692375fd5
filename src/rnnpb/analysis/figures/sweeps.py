"""A sweep's figure: every run's value and the median's interval (``rnnpb sweep``)."""

from __future__ import annotations

import os
from collections.abc import Sequence as SequenceABC
from typing import Protocol

import numpy as np
from matplotlib.figure import Figure

from rnnpb.analysis.figures._common import (
    save,
)


class IntervalLike(Protocol):
    """A statistic and its confidence interval (:class:`rnnpb.analysis.statistics.Interval`)."""

    value: float
    low: float
    high: float
    n: int


def plot_distributions(
    panels: dict[str, dict[str, tuple[SequenceABC[float], IntervalLike]]],
    path: str | os.PathLike[str],
    limits: dict[str, float] | None = None,
) -> None:
    """One panel per measure; in each, one column per setting: every run's value (dots,
    jittered) and the median with its 95 % interval (bar). ``panels[measure][setting] =
    (values, interval)``; ``limits`` draws the paper's limit of a measure as a dashed line."""
    limits = limits or {}
    n = max(len(panels), 1)
    cols = min(n, 3)
    rows = int(np.ceil(n / cols))
    fig = Figure(figsize=(4.2 * cols, 3.2 * rows))
    axes = fig.subplots(rows, cols, squeeze=False).ravel()
    rng = np.random.default_rng(0)
    for ax, (measure, settings) in zip(axes, panels.items(), strict=False):
        for i, (values, interval) in enumerate(settings.values()):
            values = np.asarray([v for v in values if np.isfinite(v)], dtype=np.float64)
            ax.scatter(
                i + rng.uniform(-0.15, 0.15, len(values)), values, s=8, alpha=0.4, color="#1f77b4"
            )
            if interval.n:
                ax.errorbar(
                    [i + 0.3],
                    [interval.value],
                    yerr=[[interval.value - interval.low], [interval.high - interval.value]],
                    fmt="o",
                    color="black",
                    capsize=4,
                )
        if measure in limits:
            ax.axhline(limits[measure], color="#d62728", ls="--", lw=1, label="paper's limit")
            ax.legend(fontsize=7, loc="upper right")
        ax.set_xticks(range(len(settings)))
        ax.set_xticklabels(list(settings), rotation=20, fontsize=7)
        ax.set_title(measure, fontsize=9)
        ax.grid(alpha=0.3)
    for ax in axes[len(panels) :]:
        ax.set_visible(False)
    fig.suptitle("every run (dots) and the median with its 95 % bootstrap interval")
    save(fig, path)
