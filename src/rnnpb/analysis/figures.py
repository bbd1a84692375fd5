"""Figures (the only place matplotlib is imported). Each function writes one PNG."""

from __future__ import annotations

import os
from collections.abc import Sequence as SequenceABC

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from rnnpb._atomic import atomic_write  # noqa: E402
from rnnpb.vectors import MOTOR_NAMES, SENSORY_NAMES  # noqa: E402

SENSORY_COLORS = ("#d62728", "#ff9896", "#1f77b4", "#aec7e8")
PB_COLORS = ("#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22")
# The paper plots 6 of the 8 joints: shoulder pitch, roll and elbow of both arms.
PLOTTED_JOINTS = ("lshp", "lshr", "lelp", "rshp", "rshr", "relp")


def save(fig: plt.Figure, path: str | os.PathLike[str]) -> None:
    with atomic_write(path, "wb") as handle:
        fig.savefig(handle, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)


def _shade(ax, spans, color="#eeeeee", label=None):
    for i, (start, end) in enumerate(spans):
        ax.axvspan(start - 0.5, end - 0.5, color=color, zorder=0,
                   label=label if i == 0 else None)


def _segments(labels: SequenceABC[str]) -> list[tuple[int, int, str]]:
    out, start = [], 0
    for t in range(1, len(labels) + 1):
        if t == len(labels) or labels[t] != labels[start]:
            out.append((start, t, labels[start]))
            start = t
    return out


def plot_session(session: dict[str, np.ndarray], path: str | os.PathLike[str], title: str = "",
                 joint_limits: np.ndarray | None = None,
                 marks: SequenceABC[tuple[int, str]] = ()) -> None:
    """The paper's Figure 5/6 layout: target hands, predicted hands, robot joints, PB."""
    steps = session["step"]
    fig, axes = plt.subplots(4, 1, figsize=(10, 9), sharex=True,
                             gridspec_kw={"height_ratios": [1, 1, 1.2, 1]})
    labels = list(session.get("truth_pattern", []))
    if labels and any(labels):
        for ax in axes:
            for start, end, label in _segments(labels):
                if label == "pause":
                    _shade(ax, [(start, end)], "#fde2c8")
        for start, end, label in _segments(labels):
            axes[0].text((start + end) / 2, 1.02, "pause" if label == "pause" else
                         f"pattern {label}", ha="center", va="bottom", fontsize=8,
                         transform=axes[0].get_xaxis_transform())
    for name, color in zip(SENSORY_NAMES, SENSORY_COLORS, strict=True):
        axes[0].plot(steps, session[name], color=color, label=name.upper())
        axes[1].plot(steps, session["pred_" + name], color=color, label=name.upper())
    axes[0].set_ylabel("user hands\n(seen)")
    axes[1].set_ylabel("user hands\n(predicted)")
    for ax in axes[:2]:
        ax.set_ylim(-0.05, 1.05)
        ax.legend(loc="upper right", ncol=4, fontsize=7, framealpha=0.8)
    cmap = plt.get_cmap("tab10")
    for k, name in enumerate(PLOTTED_JOINTS):
        values = session[name]
        if joint_limits is not None:
            j = MOTOR_NAMES.index(name)
            lo, hi = joint_limits[j]
            values = (values - lo) / (hi - lo)
        axes[2].plot(steps, values, color=cmap(k), label=name.upper())
    axes[2].set_ylabel("robot joints\n(normalized)" if joint_limits is not None
                       else "robot joints (rad)")
    axes[2].legend(loc="upper right", ncol=6, fontsize=7, framealpha=0.8)
    k = 0
    while f"pb{k}" in session:
        axes[3].plot(steps, session[f"pb{k}"], color=PB_COLORS[k % len(PB_COLORS)],
                     label=f"PB{k}")
        k += 1
    axes[3].set_ylim(-0.05, 1.05)
    axes[3].set_ylabel("parametric bias")
    axes[3].legend(loc="upper right", ncol=4, fontsize=7, framealpha=0.8)
    for step, text in marks:
        for ax in axes:
            ax.axvline(step, color="k", lw=0.8, ls="--")
        axes[0].text(step, 1.12, text, fontsize=8, ha="center",
                     transform=axes[0].get_xaxis_transform())
    axes[3].set_xlabel("step (0.4 s each)")
    if title:
        fig.suptitle(title, y=1.0)
    fig.align_ylabels(axes)
    save(fig, path)
