"""The paper's figures (Ito & Tani 2004, Figures 5-9) and the demo's training and switching
figures (``rnnpb demo``)."""

from __future__ import annotations

import os
from collections.abc import Sequence as SequenceABC
from typing import Protocol

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure

from rnnpb.analysis.attractors import ClosedLoopRun, context_plane
from rnnpb.analysis.figures._common import (
    JUMP_MARK,
    PB_COLORS,
    PLOTTED_JOINTS,
    SENSORY_COLORS,
    _caption,
    _runs,
    _segments,
    _shade,
    _spans_text,
    save,
)
from rnnpb.analysis.metrics import TRAIN_ERROR_TARGET
from rnnpb.analysis.pb import PB_JUMP, nearest_patterns, pb_jumps, pb_matrix
from rnnpb.vectors import (
    MOTOR_NAMES,
    PREDICTED_PREFIX,
    SENSORY_NAMES,
    STEP_COLUMN,
    TRUTH_PATTERN_COLUMN,
)


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


def plot_session(
    session: dict[str, np.ndarray],
    path: str | os.PathLike[str],
    title: str = "",
    joint_limits: np.ndarray | None = None,
    marks: SequenceABC[tuple[int, str]] = (),
    pattern_pb: dict[str, np.ndarray] | None = None,
    caption: str | None = None,
    dt: float = 0.4,
) -> None:
    """The paper's Figure 5/6 layout: target hands, predicted hands, robot joints, PB; the
    steps are ``dt`` seconds each (the model's step).

    Jumps of the PB (more than :data:`PB_JUMP` in one step: the regression's restarts) are
    marked ▼. With ``pattern_pb`` (the learned PB of each pattern) a strip under the PB names
    the learned pattern whose PB is nearest at each step, hatched where that is not the
    pattern the user performs. Under the figure a caption says what the reader sees (with
    the counts measured on this session); ``caption`` adds a sentence of the caller's.
    """
    steps = session[STEP_COLUMN]
    pb = pb_matrix(session)
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
    axes[3].set_xlabel(f"step ({dt:g} s each)")
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
        pb = pb_matrix(session)
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
