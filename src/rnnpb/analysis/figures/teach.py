"""The teaching study's figure: one teaching run's timeline (``rnnpb study teach``)."""

from __future__ import annotations

import itertools
import os
from collections.abc import Mapping
from collections.abc import Sequence as SequenceABC
from typing import Any

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure

from rnnpb.analysis.figures._common import (
    _caption,
    _segments,
    save,
)

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


def _strip(ax, values: SequenceABC[str], colors: Mapping[str, Any], name: str) -> None:
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
    recognised_colors: dict[str, Any] = {"": "#f0f0f0"}
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
