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


def plot_switch_zoom(session: dict[str, np.ndarray], windows: SequenceABC[tuple[int, int]],
                     path: str | os.PathLike[str], joint_limits: np.ndarray | None = None,
                     switches: SequenceABC[int] = ()) -> None:
    """The paper's Figure 7: enlargements of the switching periods (one column each)."""
    fig, axes = plt.subplots(4, len(windows), figsize=(5 * len(windows), 8), sharey="row",
                             squeeze=False)
    steps = session["step"]
    cmap = plt.get_cmap("tab10")
    for col, (start, end) in enumerate(windows):
        part = (steps >= start) & (steps < end)
        ax = axes[:, col]
        for name, color in zip(SENSORY_NAMES, SENSORY_COLORS, strict=True):
            ax[0].plot(steps[part], session[name][part], color=color, label=name.upper())
            ax[1].plot(steps[part], session["pred_" + name][part], color=color)
        for k, name in enumerate(PLOTTED_JOINTS):
            values = session[name]
            if joint_limits is not None:
                lo, hi = joint_limits[MOTOR_NAMES.index(name)]
                values = (values - lo) / (hi - lo)
            ax[2].plot(steps[part], values[part], color=cmap(k), label=name.upper())
        k = 0
        while f"pb{k}" in session:
            ax[3].plot(steps[part], session[f"pb{k}"][part], color=PB_COLORS[k],
                       label=f"PB{k}")
            k += 1
        for switch in switches:
            if start <= switch < end:
                for a in ax:
                    a.axvline(switch, color="k", ls="--", lw=0.8)
        ax[0].set_title(f"steps {start}–{end - 1}")
        ax[3].set_xlabel("step")
    for row, label in enumerate(("user hands\n(seen)", "user hands\n(predicted)",
                                 "robot joints\n(normalized)", "parametric bias")):
        axes[row, 0].set_ylabel(label)
    axes[0, -1].legend(fontsize=7, loc="upper right", ncol=2)
    axes[2, -1].legend(fontsize=7, loc="upper right", ncol=3)
    axes[3, -1].legend(fontsize=7, loc="upper right", ncol=2)
    fig.suptitle("Switching: the dashed line is the user's switch", y=1.0)
    save(fig, path)


def plot_novel_responses(runs: SequenceABC[dict], path: str | os.PathLike[str],
                         joint_limits: np.ndarray) -> None:
    """The paper's Figure 8: robot joints (top) and PB (bottom) for novel-pattern runs."""
    fig, axes = plt.subplots(2, len(runs), figsize=(5 * len(runs), 5.5), squeeze=False,
                             sharey="row")
    cmap = plt.get_cmap("tab10")
    for col, run in enumerate(runs):
        motor = run["motor"]
        show = slice(0, min(len(motor), 150))
        for k, name in enumerate(PLOTTED_JOINTS):
            j = MOTOR_NAMES.index(name)
            lo, hi = joint_limits[j]
            axes[0, col].plot((motor[show, j] - lo) / (hi - lo), color=cmap(k),
                              label=name.upper())
        for k in range(run["pb"].shape[1]):
            axes[1, col].plot(run["pb"][show, k], color=PB_COLORS[k], label=f"PB{k}")
        axes[0, col].set_title(f"case {run['case']}: set {run['learning_set']}, novel pattern "
                               f"{run['novel_pattern']} (x{run['amplitude']:g})", fontsize=9)
        axes[1, col].set_xlabel("step")
        axes[1, col].set_ylim(-0.05, 1.05)
    axes[0, 0].set_ylabel("robot joints (normalized)")
    axes[1, 0].set_ylabel("parametric bias")
    axes[0, -1].legend(fontsize=7, ncol=3, loc="upper right")
    axes[1, -1].legend(fontsize=7, ncol=2, loc="upper right")
    save(fig, path)


def context_units(attractors: dict[str, dict]) -> tuple[int, int]:
    """The two context units that vary most over the learned attractors (for phase plots)."""
    stacked = np.concatenate([a["context"] for a in attractors.values()])
    order = np.argsort(stacked.var(axis=0))[::-1]
    return int(order[0]), int(order[1])


def plot_attractors(rows: SequenceABC[tuple[dict, dict]], path: str | os.PathLike[str],
                    transient: int) -> None:
    """The paper's Figure 9: per row, the open-loop attractor while a novel pattern is
    repeated (left) and the closed-loop attractors of the learned patterns (right), in the
    plane of two context units."""
    n_cols = 1 + max(len(attractors) for _, attractors in rows)
    fig, axes = plt.subplots(len(rows), n_cols, figsize=(2.7 * n_cols, 3.0 * len(rows)),
                             squeeze=False, layout="constrained")
    for r, (run, attractors) in enumerate(rows):
        i, j = context_units(attractors)
        ctx = run["context"][transient:]
        ax = axes[r, 0]
        ax.plot(ctx[:, i], ctx[:, j], lw=0.6, color="#d62728")
        ax.set_title(f"interaction: novel {run['novel_pattern']}\n(set {run['learning_set']}, "
                     f"case {run['case']})", fontsize=8)
        for c, (name, attractor) in enumerate(attractors.items(), start=1):
            a = axes[r, c]
            a.plot(attractor["context"][:, i], attractor["context"][:, j], lw=0.6,
                   color="#1f77b4")
            a.set_title(f"closed loop: pattern {name}", fontsize=8)
        for a in axes[r]:
            a.set_xlim(0, 1)
            a.set_ylim(0, 1)
            a.set_aspect("equal")
            a.tick_params(labelsize=6)
        axes[r, 0].set_ylabel(f"context {j}", fontsize=8)
        for a in axes[r]:
            a.set_xlabel(f"context {i}", fontsize=7)
    save(fig, path)


def plot_training(histories: dict[str, SequenceABC[tuple[int, float]]],
                  path: str | os.PathLike[str], target: float = 3e-4) -> None:
    """Mean squared error during learning, one line per model."""
    fig, ax = plt.subplots(figsize=(7, 4))
    cmap = plt.get_cmap("tab10")
    groups = list(dict.fromkeys(label.split(" (")[0] for label in histories))
    for label, history in histories.items():
        history = np.asarray(history, dtype=np.float64)
        history = history[history[:, 0] > 0]  # the starting error has no place on a log axis
        # One colour per learning set; the paper's algorithm dashed.
        ax.plot(history[:, 0], history[:, 1], label=label,
                color=cmap(groups.index(label.split(" (")[0]) % 10),
                ls="--" if "paper" in label else "-")
    ax.axhline(target, color="k", ls="--", lw=0.8, label=f"paper's final error {target:g}")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("iteration")
    ax.set_ylabel("mean squared error\n(mean over the 12 outputs)")
    ax.legend(fontsize=7)
    save(fig, path)


def plot_switch_matrix(matrices: dict[str, dict[str, int | None]], path: str | os.PathLike[str],
                       limit: int = 15) -> None:
    """Steps from the user's switch until the robot follows, per learning set and pair."""
    fig, axes = plt.subplots(1, len(matrices), figsize=(3.2 * len(matrices), 3.2),
                             squeeze=False)
    for ax, (set_name, pairs) in zip(axes[0], matrices.items(), strict=True):
        patterns = sorted({p for pair in pairs for p in pair.split("->")})
        grid = np.full((len(patterns), len(patterns)), np.nan)
        for pair, steps in pairs.items():
            a, b = pair.split("->")
            grid[patterns.index(a), patterns.index(b)] = np.nan if steps is None else steps
        shown = np.where(np.isnan(grid), limit * 2, grid)
        cmap = plt.get_cmap("RdYlGn_r").copy()
        cmap.set_bad("#dddddd")  # a pattern to itself: no switch
        diagonal = np.eye(len(patterns), dtype=bool)
        ax.imshow(np.ma.masked_array(shown, diagonal), cmap=cmap, vmin=0, vmax=limit * 2)
        for (a, b), value in np.ndenumerate(grid):
            if a != b:
                text = "never" if np.isnan(value) else f"{int(value)}"
                ax.text(b, a, text, ha="center", va="center", fontsize=9)
        ax.set_xticks(range(len(patterns)), patterns)
        ax.set_yticks(range(len(patterns)), patterns)
        ax.set_xlabel("to pattern")
        ax.set_ylabel("from pattern")
        ax.set_title(f"learning set {set_name}")
    fig.suptitle(f"Steps until the robot follows a switch (target <= {limit})", y=1.02)
    save(fig, path)
