"""Figures (the only place matplotlib is imported). Each function writes one PNG.

The figures are drawn with matplotlib's object API (:class:`matplotlib.figure.Figure`), not
pyplot: no backend is chosen or needed, importing this module changes nothing, and a notebook
keeps its inline plots.
"""

from __future__ import annotations

import itertools
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


def save(
    fig: Figure, path: str | os.PathLike[str], dpi: int = 110, bbox_inches: str | None = "tight"
) -> None:
    """Write ``fig`` as a PNG, atomically."""
    with atomic_write(path, "wb") as handle:
        fig.savefig(handle, format="png", dpi=dpi, bbox_inches=bbox_inches)


def _shade(ax, spans, color="#eeeeee", label=None):
    for i, (start, end) in enumerate(spans):
        ax.axvspan(start - 0.5, end - 0.5, color=color, zorder=0, label=label if i == 0 else None)


def _segments(labels: SequenceABC[str]) -> list[tuple[int, int, str]]:
    out, start = [], 0
    for t in range(1, len(labels) + 1):
        if t == len(labels) or labels[t] != labels[start]:
            out.append((start, t, labels[start]))
            start = t
    return out


#: A PB change larger than this in one step (any unit) is marked as a jump: the on-line
#: regression restarted from a learned pattern's PB or from a state on a learned cycle. Between
#: restarts the PB moves by less than about 0.08 a step (measured on the demo's sessions).
PB_JUMP = 0.15
JUMP_MARK = dict(marker="v", color="k", ms=5, ls="none")


def _pb_matrix(session: dict[str, np.ndarray]) -> np.ndarray:
    """The session's PB columns as one array, shape (T, P)."""
    columns = []
    while pb_column(len(columns)) in session:
        columns.append(np.asarray(session[pb_column(len(columns))], dtype=np.float64))
    return np.stack(columns, axis=1) if columns else np.zeros((len(session[STEP_COLUMN]), 0))


def pb_jumps(pb: np.ndarray, threshold: float = PB_JUMP) -> np.ndarray:
    """Indices of the steps where the PB (T, P) moved by more than ``threshold`` in some unit
    since the step before (the first step is never one)."""
    if len(pb) < 2:
        return np.zeros(0, dtype=int)
    change = np.nanmax(np.abs(np.diff(pb, axis=0)), axis=1, initial=0.0)
    return np.flatnonzero(change > threshold) + 1


def nearest_patterns(pb: np.ndarray, pattern_pb: dict[str, np.ndarray]) -> list[str]:
    """Per step, the learned pattern whose PB is nearest the PB (T, P) (Euclidean)."""
    names = list(pattern_pb)
    learned = np.stack([np.asarray(pattern_pb[n], dtype=np.float64) for n in names])
    distance = np.linalg.norm(pb[:, None, :] - learned[None, :, :], axis=2)
    return [names[i] for i in np.argmin(distance, axis=1)]


def _spans_text(spans: SequenceABC[tuple[int, int]], limit: int = 4) -> str:
    parts = [f"{a}" if b - a == 1 else f"{a}–{b - 1}" for a, b in spans[:limit]]
    return ", ".join(parts) + (", …" if len(spans) > limit else "")


def _runs(flags: np.ndarray, steps: np.ndarray, minimum: int = 1) -> list[tuple[int, int]]:
    """(first step, end step) of each run of True in ``flags`` at least ``minimum`` long."""
    out, start = [], None
    for t, flag in enumerate([*flags, False]):
        if flag and start is None:
            start = t
        elif not flag and start is not None:
            if t - start >= minimum:
                out.append((int(steps[start]), int(steps[t - 1]) + 1))
            start = None
    return out


def _caption(fig: Figure, text: str) -> None:
    """What the reader sees, under the figure (kept by the tight bounding box)."""
    fig.text(0.01, -0.01, text, ha="left", va="top", fontsize=8, wrap=True, color="#333333")


def plot_session(
    session: dict[str, np.ndarray],
    path: str | os.PathLike[str],
    title: str = "",
    joint_limits: np.ndarray | None = None,
    marks: SequenceABC[tuple[int, str]] = (),
    pattern_pb: dict[str, np.ndarray] | None = None,
    caption: str | None = None,
) -> None:
    """The paper's Figure 5/6 layout: target hands, predicted hands, robot joints, PB.

    Jumps of the PB (more than :data:`PB_JUMP` in one step: the regression's restarts) are
    marked ▼. With ``pattern_pb`` (the learned PB of each pattern) a strip under the PB names
    the learned pattern whose PB is nearest at each step, hatched where that is not the
    pattern the user performs. Under the figure a caption says what the reader sees (with
    the counts measured on this session); ``caption`` adds a sentence of the caller's.
    """
    steps = session[STEP_COLUMN]
    pb = _pb_matrix(session)
    fig = Figure(figsize=(10, 9.6 if pattern_pb else 9))
    axes = fig.subplots(4, 1, sharex=True, gridspec_kw={"height_ratios": [1, 1, 1.2, 1]})
    labels = list(session.get(TRUTH_PATTERN_COLUMN, []))
    if labels and any(labels):
        for ax in axes:
            for start, end, label in _segments(labels):
                if label == "pause":
                    _shade(ax, [(start, end)], "#fde2c8")
        for start, end, label in _segments(labels):
            axes[0].text(
                (start + end) / 2,
                1.02,
                "pause" if label == "pause" else f"pattern {label}",
                ha="center",
                va="bottom",
                fontsize=8,
                transform=axes[0].get_xaxis_transform(),
            )
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
    axes[2].set_ylabel(
        "robot joints\n(normalized)" if joint_limits is not None else "robot joints (rad)"
    )
    axes[2].legend(loc="upper right", ncol=6, fontsize=7, framealpha=0.8)
    for k in range(pb.shape[1]):
        axes[3].plot(steps, pb[:, k], color=PB_COLORS[k % len(PB_COLORS)], label=f"PB{k}")
    jumps = pb_jumps(pb)
    if len(jumps):
        axes[3].plot(
            steps[jumps], np.full(len(jumps), 1.01), label="PB jump", clip_on=False, **JUMP_MARK
        )
    axes[3].set_ylim(-0.05, 1.05)
    axes[3].set_ylabel("parametric bias")
    sentences = [
        "Top to bottom: the user's hands as the robot sees them, the network's "
        "prediction of them made one step before, the robot's joints, and the "
        "parametric bias (PB)."
    ]
    if labels and any(label == "pause" for label in labels):
        sentences.append("Shaded: the user pauses (holds still).")
    if marks:
        sentences.append("Dashed lines: " + ", ".join(sorted({t for _, t in marks})) + ".")
    if len(jumps):
        sentences.append(
            f"▼ marks {len(jumps)} jump(s) of the PB by more than {PB_JUMP:g} in one step "
            f"(steps {_spans_text([(int(steps[j]), int(steps[j]) + 1) for j in jumps], 6)}):"
            " the on-line regression restarting from a learned pattern's PB or from a state "
            "on a learned cycle, as it does to find the user's pattern and phase again "
            "(docs/model.md)."
        )
    else:
        sentences.append(f"The PB never jumps by more than {PB_JUMP:g} in one step.")
    if pattern_pb and len(pb):
        nearest = nearest_patterns(np.nan_to_num(pb, nan=0.5), pattern_pb)
        _nearest_strip(axes[3], steps, nearest, labels)
        if labels and any(labels):
            performed = np.array([lab not in ("", "pause") for lab in labels])
            other = performed & np.array([n != lab for n, lab in zip(nearest, labels, strict=True)])
            spans = _runs(other, steps)
            if spans:
                sentences.append(
                    f"The strip under the PB names the learned pattern whose PB is nearest; "
                    f"hatched ({int(other.sum())} of {int(performed.sum())} steps with a "
                    f"pattern performed, steps {_spans_text(spans)}) where it is another "
                    "than the user's: there the PB lies nearer that pattern's learned value. "
                    "The PB need not sit at the learned value for the network to generate "
                    "the pattern: the predictions and joints above show whether the "
                    "movement followed."
                )
            else:
                sentences.append(
                    "The strip under the PB names the learned pattern whose PB "
                    "is nearest: always the one the user performs."
                )
        axes[3].set_ylim(-0.3, 1.05)
    axes[3].legend(loc="upper right", ncol=5, fontsize=7, framealpha=0.8)
    for step, text in marks:
        for ax in axes:
            ax.axvline(step, color="k", lw=0.8, ls="--")
        axes[0].text(
            step, 1.12, text, fontsize=8, ha="center", transform=axes[0].get_xaxis_transform()
        )
    axes[3].set_xlabel("step (0.4 s each)")
    if title:
        fig.suptitle(title, y=1.0)
    fig.align_ylabels(axes)
    if caption:
        sentences.append(caption)
    _caption(fig, " ".join(sentences))
    save(fig, path)


def _nearest_strip(ax, steps: np.ndarray, nearest: list[str], performed: list[str]) -> None:
    """Under the PB (y in [-0.27, -0.12]): the nearest learned pattern per step, named where
    its run is long enough, hatched at the steps where it is not the pattern performed."""
    names = sorted(set(nearest))
    cmap = colormaps["Pastel1"]
    for start, end, name in _segments(nearest):
        ax.broken_barh(
            [(steps[start] - 0.5, end - start)],
            (-0.27, 0.15),
            facecolors=cmap(names.index(name) % 9),
            lw=0.0,
        )
        if end - start >= 6:
            ax.text(
                (steps[start] + steps[end - 1]) / 2,
                -0.195,
                name,
                ha="center",
                va="center",
                fontsize=7,
            )
    if performed:
        other = np.array(
            [p not in ("", "pause", n) for n, p in zip(nearest, performed, strict=True)]
        )
        for start, end in _runs(other, np.arange(len(steps))):
            ax.broken_barh(
                [(steps[start] - 0.5, end - start)],
                (-0.27, 0.15),
                facecolors="none",
                edgecolor="#c00000",
                hatch="////",
                lw=0.0,
            )
    ax.text(
        0.0,
        -0.195,
        "nearest ",
        ha="right",
        va="center",
        fontsize=7,
        transform=ax.get_yaxis_transform(),
    )


def plot_switch_zoom(
    session: dict[str, np.ndarray],
    windows: SequenceABC[tuple[int, int]],
    path: str | os.PathLike[str],
    joint_limits: np.ndarray | None = None,
    switches: SequenceABC[int] = (),
) -> None:
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
        pb = _pb_matrix(session)
        for k in range(pb.shape[1]):
            ax[3].plot(
                steps[part], pb[part, k], color=PB_COLORS[k % len(PB_COLORS)], label=f"PB{k}"
            )
        jumps = [j for j in pb_jumps(pb) if part[j]]
        if jumps:
            ax[3].plot(
                steps[jumps],
                np.full(len(jumps), 1.01),
                clip_on=False,
                label="PB jump" if col == len(windows) - 1 else None,
                **JUMP_MARK,
            )
        ax[3].set_ylim(-0.05, 1.05)
        for switch in switches:
            if start <= switch < end:
                for a in ax:
                    a.axvline(switch, color="k", ls="--", lw=0.8)
        ax[0].set_title(f"steps {start}–{end - 1}")
        ax[3].set_xlabel("step")
    for row, label in enumerate(
        (
            "user hands\n(seen)",
            "user hands\n(predicted)",
            "robot joints\n(normalized)",
            "parametric bias",
        )
    ):
        axes[row, 0].set_ylabel(label)
    axes[0, -1].legend(fontsize=7, loc="upper right", ncol=2)
    axes[2, -1].legend(fontsize=7, loc="upper right", ncol=3)
    axes[3, -1].legend(fontsize=7, loc="upper right", ncol=3)
    fig.suptitle("Switching: the dashed line is the user's switch", y=1.0)
    _caption(
        fig,
        "Each column: from 10 steps before a switch of the user's pattern (dashed) "
        "to 30 steps after it. Rows: the hands seen, the hands predicted one step "
        "before, the robot's joints, the PB. ▼ marks a jump of the PB by more than "
        f"{PB_JUMP:g} in one step: the on-line regression restarting from a learned "
        "pattern's PB or a state on a learned cycle, which is how it catches the new "
        "pattern within a few steps (docs/model.md).",
    )
    save(fig, path)


def plot_novel_responses(
    runs: SequenceABC[NovelRun], path: str | os.PathLike[str], joint_limits: np.ndarray
) -> None:
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
            axes[0, col].plot((motor[show, j] - lo) / (hi - lo), color=cmap(k), label=name.upper())
        for k in range(run.pb.shape[1]):
            axes[1, col].plot(run.pb[show, k], color=PB_COLORS[k], label=f"PB{k}")
        shown = f"x{run.amplitude:g}" if run.user_draw is None else f"by hand, draw {run.user_draw}"
        axes[0, col].set_title(
            f"case {run.case}: set {run.learning_set}, novel pattern {run.novel_pattern} ({shown})",
            fontsize=9,
        )
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


def context_plane(
    attractors: dict[str, ClosedLoopRun],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The plane of Figure 9: the first two principal components of the context over the
    learned attractors.

    The context units that vary most move together (their plane shows each attractor as a
    thin ellipse on the diagonal); the principal components separate the common swing from
    what differs, and so show each attractor's shape.

    Returns
    -------
    mean : array, shape (C,)
    axes : array, shape (2, C)
        The two components, unit vectors, each signed so that its largest entry is positive.
    explained : array, shape (2,)
        The share of the context's variance over the attractors each explains.
    """
    stacked = np.concatenate([a.context for a in attractors.values()])
    mean = stacked.mean(axis=0)
    _, singular, vt = np.linalg.svd(stacked - mean, full_matrices=False)
    components = np.zeros((2, stacked.shape[1]))
    components[: len(vt[:2])] = vt[:2]
    largest = components[np.arange(2), np.argmax(np.abs(components), axis=1)]
    components *= np.where(largest < 0, -1.0, 1.0)[:, None]
    singular = np.pad(singular[:2], (0, max(0, 2 - len(singular))))
    total = float(((stacked - mean) ** 2).sum())
    return mean, components, singular**2 / max(total, 1e-300)


def plot_attractors(
    rows: SequenceABC[tuple[NovelRun, dict[str, ClosedLoopRun]]],
    path: str | os.PathLike[str],
    transient: int,
) -> None:
    """The paper's Figure 9: per row, the open-loop attractor while a novel pattern is
    repeated (left) and the closed-loop attractors of the learned patterns (right), in the
    plane of the context's first two principal components over that row's learned
    attractors (:func:`context_plane`), on axes shared along the row."""
    n_cols = 1 + max(len(attractors) for _, attractors in rows)
    fig = Figure(figsize=(2.7 * n_cols, 3.0 * len(rows) + 0.6), layout="constrained")
    axes = fig.subplots(len(rows), n_cols, squeeze=False)
    for r, (run, attractors) in enumerate(rows):
        mean, plane, explained = context_plane(attractors)
        ctx = (run.context[transient:] - mean) @ plane.T
        ax = axes[r, 0]
        ax.plot(ctx[:, 0], ctx[:, 1], lw=0.6, color="#d62728")
        ax.set_title(
            f"interaction: novel {run.novel_pattern}\n(set {run.learning_set}, case {run.case})",
            fontsize=8,
        )
        shown = [ctx]
        for c, (name, attractor) in enumerate(attractors.items(), start=1):
            a = axes[r, c]
            xy = (attractor.context - mean) @ plane.T
            shown.append(xy)
            a.plot(xy[:, 0], xy[:, 1], lw=0.6, color="#1f77b4")
            a.set_title(f"closed loop: pattern {name}", fontsize=8)
        points = np.concatenate(shown)
        low, high = np.nanmin(points, axis=0), np.nanmax(points, axis=0)
        pad = 0.06 * np.maximum(high - low, 1e-6)
        for a in axes[r]:
            a.set_xlim(low[0] - pad[0], high[0] + pad[0])
            a.set_ylim(low[1] - pad[1], high[1] + pad[1])
            a.tick_params(labelsize=6)
            a.set_xlabel(f"context PC1 ({explained[0]:.0%} of variance)", fontsize=7)
        for a in axes[r, len(attractors) + 1 :]:
            a.set_visible(False)
        axes[r, 0].set_ylabel(f"context PC2 ({explained[1]:.0%})", fontsize=8)
    _caption(
        fig,
        "Each row, one novel pattern: left (red), the context while the user "
        "repeats the novel pattern and the PB is regressed on-line, after the "
        f"transient of {transient} steps; right (blue), the closed-loop attractor of "
        "each learned pattern, the network running on its own from that pattern's PB. "
        "Axes: the context's first two principal components over the row's learned "
        "attractors, the same along a row, so that shapes and sizes compare. Case 1: "
        "the robot's movement settles on a learned pattern's cycle; case 2: on a new "
        "cycle of its own; case 3: on no cycle (the paper's section 3.3).",
    )
    save(fig, path)


def plot_training(
    histories: dict[str, SequenceABC[tuple[int, float]]],
    path: str | os.PathLike[str],
    target: float = TRAIN_ERROR_TARGET,
) -> None:
    """Mean squared error during learning, one line per model."""
    fig = Figure(figsize=(7, 4))
    ax = fig.subplots()
    cmap = colormaps["tab10"]
    groups = list(dict.fromkeys(label.split(" (")[0] for label in histories))
    for label, history in histories.items():
        history = np.asarray(history, dtype=np.float64)
        history = history[history[:, 0] > 0]  # the starting error has no place on a log axis
        # One colour per learning set; the paper's algorithm dashed.
        ax.plot(
            history[:, 0],
            history[:, 1],
            label=label,
            color=cmap(groups.index(label.split(" (")[0]) % 10),
            ls="--" if "paper" in label else "-",
        )
    ax.axhline(target, color="k", ls="--", lw=0.8, label=f"paper's final error {target:g}")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("iteration")
    ax.set_ylabel("mean squared error\n(mean over the 12 outputs)")
    ax.legend(fontsize=7)
    save(fig, path)


def plot_switch_matrix(
    matrices: dict[str, dict[str, int | None]], path: str | os.PathLike[str], limit: int = 15
) -> None:
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
            frames = [renderer.render(seq.motor[t], "front").astype(np.float64) for t in picks[:-1]]
            # The darkest value per pixel keeps each pose's arm visible: a motion trace.
            images.append(np.min(frames, axis=0).astype(np.uint8))
    return images


def plot_patterns(
    sequences: SequenceABC, path: str | os.PathLike[str], render: bool = True
) -> None:
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

    firsts = [
        next(s for s in sequences if s.pattern == p)
        for p in PATTERNS
        if any(s.pattern == p for s in sequences)
    ]
    n_rows = 4 if render else 3
    fig = Figure(figsize=(4.0 * len(firsts), 3.1 * n_rows))
    axes = fig.subplots(
        n_rows,
        len(firsts),
        squeeze=False,
        gridspec_kw={"height_ratios": [1.25, 1, 1.15] + ([1.3] * render)},
    )
    images = _robot_images(firsts, 480, 400) if render else []
    for col, seq in enumerate(firsts):
        ax = axes[0, col]
        yz = seq.sensory.reshape(-1, 2, 2)
        for hand, name in ((0, "left"), (1, "right")):
            y, z = yz[:, hand, 0], yz[:, hand, 1]
            ax.plot(
                y, z, "-", color=_HAND_COLOURS[name], lw=1.0, alpha=0.8, label=f"user's {name} hand"
            )
            for t in range(0, min(len(y) - 1, 13), 3):
                ax.annotate(
                    "",
                    xy=(y[t + 1], z[t + 1]),
                    xytext=(y[t], z[t]),
                    arrowprops={"arrowstyle": "->", "color": _HAND_COLOURS[name], "lw": 1.6},
                )
            ax.plot(y[0], z[0], "o", color=_HAND_COLOURS[name], ms=5)
        ax.set_xlim(0, 1)
        ax.set_ylim(0.3, 1)
        ax.set_aspect("equal")
        ax.set_xlabel("Y (robot's view, to its right)")
        ax.set_ylabel("Z (up)")
        ax.set_title(f"pattern {seq.pattern}: {PATTERN_DESCRIPTIONS[seq.pattern]}", fontsize=11)
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
            ax.plot(
                seq.motor[:, j],
                "-" if j < 4 else "--",
                color=cmap(j % 4),
                lw=1.2,
                label=name.upper(),
            )
        ax.set_xlabel("step (0.4 s)")
        ax.set_ylabel("robot joints (rad)")
        if col == 0:
            ax.legend(loc="upper left", ncol=4, fontsize=7)

        if render:
            ax = axes[3, col]
            ax.imshow(images[col][40:, 60:-60])
            ax.set_axis_off()
            ax.set_title("robot, three phases overlaid", fontsize=9)
    fig.suptitle(
        "Synthetic demonstrations of the four movement patterns (cf. Ito & Tani 2004, "
        "Fig. 4): top, the user's hands as the robot sees them; middle, the robot's "
        "joint angles (solid: left arm, dashed: right)",
        fontsize=11,
    )
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    save(fig, path, dpi=90, bbox_inches=None)


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


# --- mutual interaction (docs/dyad.md) -------------------------------------------------------
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


TEACHING_COLORS = {
    # novelty
    "familiar": "#2ca02c",
    "novel": "#d62728",
    "unstructured": "#ff7f0e",
    "still": "#7f7f7f",
    "": "#f0f0f0",
    # the cutter
    "watching": "#f0f0f0",
    "recording": "#9467bd",
    "kept": "#17becf",
}


def _strip(ax, values: SequenceABC[str], colors: dict[str, str], name: str) -> None:
    """One row of categories over the steps, a coloured span per run of one value."""
    for start, end, value in _segments([str(v) for v in values]):
        ax.axvspan(start - 0.5, end - 0.5, color=colors[value], lw=0)
        if end - start >= 14 and value not in ("", "watching"):
            ax.text((start + end) / 2 - 0.5, 0.5, value, ha="center", va="center", fontsize=7)
    ax.set_yticks([0.5], [name], fontsize=8)
    ax.set_ylim(0, 1)


def plot_teaching_timeline(
    timeline: dict,
    path: str | os.PathLike[str],
    title: str,
    dt: float,
    lock_threshold: float,
) -> None:
    """One teaching run, step by step (``rnnpb study teach``): what the user does, the
    detector's novelty, the pattern recognised, the episode cutter's state, the robot's motor
    error against the imitating joints, and where the episode was kept, the consolidation ran
    and the new model was swapped in.

    ``timeline`` holds per step ``movement``, ``novelty``, ``recognised`` (names, "" for
    none), ``cutter`` and ``motor_error`` (T,), and ``kept`` (list of (first, last, step)),
    ``consolidations`` (list of (step, text)), ``swaps`` (list of steps), ``unstructured``
    (the movements that are not structured), and optionally ``taught`` (a newly learned
    pattern's name → the movement it was taught from, whose colour it takes).
    """
    movement = list(timeline["movement"])
    steps = np.arange(len(movement))
    names = list(dict.fromkeys(movement))
    cmap = colormaps["tab10"]
    movement_colors = {
        m: ("#c7c7c7" if m in timeline["unstructured"] else cmap(i % 10))
        for i, m in enumerate(names)
    }
    recognised = [r or "" for r in timeline["recognised"]]
    recognised_colors = {"": "#f0f0f0"}
    taught = timeline.get("taught", {})
    spare = itertools.count(len(names))  # colours after the movements' for the others
    for name in dict.fromkeys(recognised):
        if name:
            recognised_colors[name] = movement_colors.get(
                name, movement_colors.get(taught.get(name, ""), cmap(next(spare) % 10))
            )
    for name in recognised_colors:
        movement_colors.setdefault(name, recognised_colors[name])
    fig = Figure(figsize=(11, 5.2))
    axes = fig.subplots(
        5, 1, sharex=True, gridspec_kw={"height_ratios": [1, 1, 1, 1, 2.4], "hspace": 0.08}
    )
    _strip(axes[0], movement, movement_colors, "user does")
    _strip(axes[1], timeline["novelty"], TEACHING_COLORS, "novelty")
    _strip(axes[2], recognised, recognised_colors, "recognised")
    _strip(axes[3], timeline["cutter"], TEACHING_COLORS, "cutter")
    ax = axes[4]
    ax.plot(steps, timeline["motor_error"], color="k", lw=0.8, label="motor error")
    ax.axhline(lock_threshold, color="#d62728", lw=0.7, ls="--", label="lock threshold")
    ax.set_ylabel("motor error", fontsize=8)
    ax.set_yscale("log")
    for first, last, _kept_at in timeline["kept"]:
        for a in axes[:4]:
            a.axvline(first - 0.5, color="#17becf", lw=0.8)
            a.axvline(last + 0.5, color="#17becf", lw=0.8)
        ax.axvspan(first - 0.5, last + 0.5, color="#17becf", alpha=0.15, lw=0)
        ax.text(
            first,
            0.98,
            "episode kept",
            transform=ax.get_xaxis_transform(),
            va="top",
            fontsize=7,
            color="#0f7f8f",
        )
    for step, text in timeline["consolidations"]:
        for a in axes:
            a.axvline(step - 0.5, color="#1f77b4", lw=1.4)
        ax.text(
            step + 1,
            0.80,
            text,
            transform=ax.get_xaxis_transform(),
            va="top",
            fontsize=7,
            color="#1f77b4",
        )
    for step in timeline["swaps"]:
        for a in axes:
            a.axvline(step - 0.5, color="#e377c2", lw=1.2, ls=":")
        ax.text(
            step + 1,
            0.62,
            "new model swapped in",
            transform=ax.get_xaxis_transform(),
            va="top",
            fontsize=7,
            color="#b0409a",
        )
    ax.legend(loc="lower right", fontsize=7)
    ax.set_xlabel(f"step (dt {dt:g} s)")
    ax.set_xlim(-0.5, len(movement) - 0.5)
    seconds = axes[0].secondary_xaxis("top", functions=(lambda s: s * dt, lambda t: t / dt))
    seconds.set_xlabel("interaction time (s)", fontsize=7)
    seconds.tick_params(labelsize=7)
    axes[0].set_title(title, fontsize=10)
    _caption(
        fig,
        "Rows: the scripted user's movement, the novelty detector's word, the pattern "
        "recognised, the episode cutter. Below: the robot's motor error against the joints that "
        "imitate the user (log scale; locked on below the dashed line). Cyan: the steps of the "
        "kept episode; blue: the consolidation (run as fast as possible the loop waits for it "
        "between two steps); pink dotted: the new model swapped in.",
    )
    save(fig, path)
