"""Figures (the only place matplotlib is imported). Each function writes one PNG.

The figures are drawn with matplotlib's object API (:class:`matplotlib.figure.Figure`), not
pyplot: no backend is chosen or needed, importing this module changes nothing, and a notebook
keeps its inline plots.
"""

from __future__ import annotations

import os
from collections.abc import Sequence as SequenceABC
from typing import Protocol

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure

from rnnpb._atomic import atomic_write
from rnnpb.analysis.metrics import TRAIN_ERROR_TARGET
from rnnpb.vectors import (
    MOTOR_NAMES,
    PREDICTED_PREFIX,
    SENSORY_NAMES,
    STEP_COLUMN,
    TRUTH_PATTERN_COLUMN,
    pb_column,
)

SENSORY_COLORS = ("#d62728", "#ff9896", "#1f77b4", "#aec7e8")
PB_COLORS = ("#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22")
# The paper plots 6 of the 8 joints: shoulder pitch, roll and elbow of both arms.
PLOTTED_JOINTS = ("lshp", "lshr", "lelp", "rshp", "rshr", "relp")


class NovelRun(Protocol):
    """What Figures 8 and 9 read of a novel-pattern run
    (:class:`rnnpb.experiments.paper.NovelResponse`)."""

    learning_set: str
    novel_pattern: str
    amplitude: float
    user_draw: int | None  # None: one exact cycle repeated; else demonstrated by hand
    case: int
    motor: np.ndarray  # (T, 8) rad
    pb: np.ndarray  # (T, P)
    context: np.ndarray  # (T, C)


class ClosedLoopRun(Protocol):
    """What Figure 9 reads of a learned pattern's closed-loop attractor
    (:class:`rnnpb.experiments.paper.Attractor`)."""

    context: np.ndarray  # (T, C)


def save(fig: Figure, path: str | os.PathLike[str], dpi: int = 110,
         bbox_inches: str | None = "tight") -> None:
    """Write ``fig`` as a PNG, atomically."""
    with atomic_write(path, "wb") as handle:
        fig.savefig(handle, format="png", dpi=dpi, bbox_inches=bbox_inches)


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
    steps = session[STEP_COLUMN]
    fig = Figure(figsize=(10, 9))
    axes = fig.subplots(4, 1, sharex=True, gridspec_kw={"height_ratios": [1, 1, 1.2, 1]})
    labels = list(session.get(TRUTH_PATTERN_COLUMN, []))
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
        axes[1].plot(steps, session[PREDICTED_PREFIX + name], color=color, label=name.upper())
    axes[0].set_ylabel("user hands\n(seen)")
    axes[1].set_ylabel("user hands\n(predicted)")
    for ax in axes[:2]:
        ax.set_ylim(-0.05, 1.05)
        ax.legend(loc="upper right", ncol=4, fontsize=7, framealpha=0.8)
    cmap = colormaps["tab10"]
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
    while pb_column(k) in session:
        axes[3].plot(steps, session[pb_column(k)], color=PB_COLORS[k % len(PB_COLORS)],
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
    fig = Figure(figsize=(5 * len(windows), 8))
    axes = fig.subplots(4, len(windows), sharey="row", squeeze=False)
    steps = session[STEP_COLUMN]
    cmap = colormaps["tab10"]
    for col, (start, end) in enumerate(windows):
        part = (steps >= start) & (steps < end)
        ax = axes[:, col]
        for name, color in zip(SENSORY_NAMES, SENSORY_COLORS, strict=True):
            ax[0].plot(steps[part], session[name][part], color=color, label=name.upper())
            ax[1].plot(steps[part], session[PREDICTED_PREFIX + name][part], color=color)
        for k, name in enumerate(PLOTTED_JOINTS):
            values = session[name]
            if joint_limits is not None:
                lo, hi = joint_limits[MOTOR_NAMES.index(name)]
                values = (values - lo) / (hi - lo)
            ax[2].plot(steps[part], values[part], color=cmap(k), label=name.upper())
        k = 0
        while pb_column(k) in session:
            ax[3].plot(steps[part], session[pb_column(k)][part], color=PB_COLORS[k],
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


def plot_novel_responses(runs: SequenceABC[NovelRun], path: str | os.PathLike[str],
                         joint_limits: np.ndarray) -> None:
    """The paper's Figure 8: robot joints (top) and PB (bottom) for novel-pattern runs."""
    fig = Figure(figsize=(5 * len(runs), 5.5))
    axes = fig.subplots(2, len(runs), squeeze=False, sharey="row")
    cmap = colormaps["tab10"]
    for col, run in enumerate(runs):
        motor = run.motor
        show = slice(0, min(len(motor), 150))
        for k, name in enumerate(PLOTTED_JOINTS):
            j = MOTOR_NAMES.index(name)
            lo, hi = joint_limits[j]
            axes[0, col].plot((motor[show, j] - lo) / (hi - lo), color=cmap(k),
                              label=name.upper())
        for k in range(run.pb.shape[1]):
            axes[1, col].plot(run.pb[show, k], color=PB_COLORS[k], label=f"PB{k}")
        shown = (f"x{run.amplitude:g}" if run.user_draw is None
                 else f"by hand, draw {run.user_draw}")
        axes[0, col].set_title(f"case {run.case}: set {run.learning_set}, novel pattern "
                               f"{run.novel_pattern} ({shown})", fontsize=9)
        axes[1, col].set_xlabel("step")
        axes[1, col].set_ylim(-0.05, 1.05)
    axes[0, 0].set_ylabel("robot joints (normalized)")
    axes[1, 0].set_ylabel("parametric bias")
    axes[0, -1].legend(fontsize=7, ncol=3, loc="upper right")
    axes[1, -1].legend(fontsize=7, ncol=2, loc="upper right")
    save(fig, path)


def context_units(attractors: dict[str, ClosedLoopRun]) -> tuple[int, int]:
    """The two context units that vary most over the learned attractors (for phase plots)."""
    stacked = np.concatenate([a.context for a in attractors.values()])
    order = np.argsort(stacked.var(axis=0))[::-1]
    return int(order[0]), int(order[1])


def plot_attractors(rows: SequenceABC[tuple[NovelRun, dict[str, ClosedLoopRun]]],
                    path: str | os.PathLike[str], transient: int) -> None:
    """The paper's Figure 9: per row, the open-loop attractor while a novel pattern is
    repeated (left) and the closed-loop attractors of the learned patterns (right), in the
    plane of two context units."""
    n_cols = 1 + max(len(attractors) for _, attractors in rows)
    fig = Figure(figsize=(2.7 * n_cols, 3.0 * len(rows)), layout="constrained")
    axes = fig.subplots(len(rows), n_cols, squeeze=False)
    for r, (run, attractors) in enumerate(rows):
        i, j = context_units(attractors)
        ctx = run.context[transient:]
        ax = axes[r, 0]
        ax.plot(ctx[:, i], ctx[:, j], lw=0.6, color="#d62728")
        ax.set_title(f"interaction: novel {run.novel_pattern}\n(set {run.learning_set}, "
                     f"case {run.case})", fontsize=8)
        for c, (name, attractor) in enumerate(attractors.items(), start=1):
            a = axes[r, c]
            a.plot(attractor.context[:, i], attractor.context[:, j], lw=0.6,
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
                  path: str | os.PathLike[str], target: float = TRAIN_ERROR_TARGET) -> None:
    """Mean squared error during learning, one line per model."""
    fig = Figure(figsize=(7, 4))
    ax = fig.subplots()
    cmap = colormaps["tab10"]
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
    fig = Figure(figsize=(3.2 * len(matrices), 3.2))
    axes = fig.subplots(1, len(matrices), squeeze=False)
    for ax, (set_name, pairs) in zip(axes[0], matrices.items(), strict=True):
        patterns = sorted({p for pair in pairs for p in pair.split("->")})
        grid = np.full((len(patterns), len(patterns)), np.nan)
        for pair, steps in pairs.items():
            a, b = pair.split("->")
            grid[patterns.index(a), patterns.index(b)] = np.nan if steps is None else steps
        shown = np.where(np.isnan(grid), limit * 2, grid)
        cmap = colormaps["RdYlGn_r"]  # a copy of its own
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


_HAND_COLOURS = {"left": "tab:red", "right": "tab:blue"}


def _robot_images(sequences: SequenceABC, width: int, height: int) -> list[np.ndarray]:
    """Per sequence: the robot at several phases of one cycle, blended into one image."""
    from rnnpb.robot import RobotRenderer

    images = []
    with RobotRenderer(width, height) as renderer:
        for seq in sequences:
            phase = np.asarray(seq.meta["phase"])
            cycle = np.flatnonzero(phase - phase[0] < 2 * np.pi)
            picks = cycle[np.linspace(0, len(cycle) - 1, 4).round().astype(int)]
            frames = [renderer.render(seq.motor[t], "front").astype(np.float64)
                      for t in picks[:-1]]
            # The darkest value per pixel keeps each pose's arm visible: a motion trace.
            images.append(np.min(frames, axis=0).astype(np.uint8))
    return images


def plot_patterns(sequences: SequenceABC, path: str | os.PathLike[str],
                  render: bool = True) -> None:
    """The paper's Figure 4 for the demonstrations: the first sample of each pattern.

    Rows: (1) the user's hands in the robot camera's view plane (the path over the sample,
    arrows showing the direction); (2) the sensory values over time; (3) the robot's joint
    angles over time; (4) the robot at three phases of a cycle, overlaid (if ``render``;
    MuJoCo renders it).

    Parameters
    ----------
    sequences : list of rnnpb.sequences.Sequence
        Demonstrations (``sensory`` (T, 4), ``motor`` (T, 8) rad, ``meta["phase"]`` (T,)).
    """
    from rnnpb.demonstrator import PATTERN_DESCRIPTIONS, PATTERNS

    firsts = [next(s for s in sequences if s.pattern == p) for p in PATTERNS
              if any(s.pattern == p for s in sequences)]
    n_rows = 4 if render else 3
    fig = Figure(figsize=(4.0 * len(firsts), 3.1 * n_rows))
    axes = fig.subplots(n_rows, len(firsts), squeeze=False,
                        gridspec_kw={"height_ratios": [1.25, 1, 1.15] + ([1.3] * render)})
    images = _robot_images(firsts, 480, 400) if render else []
    for col, seq in enumerate(firsts):
        ax = axes[0, col]
        yz = seq.sensory.reshape(-1, 2, 2)
        for hand, name in ((0, "left"), (1, "right")):
            y, z = yz[:, hand, 0], yz[:, hand, 1]
            ax.plot(y, z, "-", color=_HAND_COLOURS[name], lw=1.0, alpha=0.8,
                    label=f"user's {name} hand")
            for t in range(0, min(len(y) - 1, 13), 3):
                ax.annotate("", xy=(y[t + 1], z[t + 1]), xytext=(y[t], z[t]),
                            arrowprops={"arrowstyle": "->", "color": _HAND_COLOURS[name],
                                        "lw": 1.6})
            ax.plot(y[0], z[0], "o", color=_HAND_COLOURS[name], ms=5)
        ax.set_xlim(0, 1)
        ax.set_ylim(0.3, 1)
        ax.set_aspect("equal")
        ax.set_xlabel("Y (robot's view, to its right)")
        ax.set_ylabel("Z (up)")
        ax.set_title(f"pattern {seq.pattern}: {PATTERN_DESCRIPTIONS[seq.pattern]}",
                     fontsize=11)
        if col == 0:
            ax.legend(loc="lower left", fontsize=8)

        ax = axes[1, col]
        styles = ["-", "--", "-", "--"]
        colours = ["tab:red", "tab:red", "tab:blue", "tab:blue"]
        for j, name in enumerate(SENSORY_NAMES):
            ax.plot(seq.sensory[:, j], styles[j], color=colours[j], lw=1.2, label=name.upper())
        ax.set_ylim(0, 1)
        ax.set_xlabel("step (0.4 s)")
        ax.set_ylabel("user hands (normalized)")
        if col == 0:
            ax.legend(loc="lower left", ncol=4, fontsize=7)

        ax = axes[2, col]
        cmap = colormaps["tab10"]
        for j, name in enumerate(MOTOR_NAMES):
            ax.plot(seq.motor[:, j], "-" if j < 4 else "--", color=cmap(j % 4), lw=1.2,
                    label=name.upper())
        ax.set_xlabel("step (0.4 s)")
        ax.set_ylabel("robot joints (rad)")
        if col == 0:
            ax.legend(loc="upper left", ncol=4, fontsize=7)

        if render:
            ax = axes[3, col]
            ax.imshow(images[col][40:, 60:-60])
            ax.set_axis_off()
            ax.set_title("robot, three phases overlaid", fontsize=9)
    fig.suptitle("Synthetic demonstrations of the four movement patterns (cf. Ito & Tani 2004, "
                 "Fig. 4): top, the user's hands as the robot sees them; middle, the robot's "
                 "joint angles (solid: left arm, dashed: right)", fontsize=11)
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    save(fig, path, dpi=90, bbox_inches=None)


class IntervalLike(Protocol):
    """A statistic and its confidence interval (:class:`rnnpb.analysis.statistics.Interval`)."""

    value: float
    low: float
    high: float
    n: int


def plot_distributions(panels: dict[str, dict[str, tuple[SequenceABC[float], IntervalLike]]],
                       path: str | os.PathLike[str],
                       limits: dict[str, float] | None = None) -> None:
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
            ax.scatter(i + rng.uniform(-0.15, 0.15, len(values)), values, s=8, alpha=0.4,
                       color="#1f77b4")
            if interval.n:
                ax.errorbar([i + 0.3], [interval.value],
                            yerr=[[interval.value - interval.low],
                                  [interval.high - interval.value]],
                            fmt="o", color="black", capsize=4)
        if measure in limits:
            ax.axhline(limits[measure], color="#d62728", ls="--", lw=1, label="paper's limit")
            ax.legend(fontsize=7, loc="upper right")
        ax.set_xticks(range(len(settings)))
        ax.set_xticklabels(list(settings), rotation=20, fontsize=7)
        ax.set_title(measure, fontsize=9)
        ax.grid(alpha=0.3)
    for ax in axes[len(panels):]:
        ax.set_visible(False)
    fig.suptitle("every run (dots) and the median with its 95 % bootstrap interval")
    save(fig, path)
