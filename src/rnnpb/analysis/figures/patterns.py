"""The demonstrations' figure (the paper's Figure 4): ``rnnpb demo`` and ``rnnpb data``."""

from __future__ import annotations

import os
from collections.abc import Sequence as SequenceABC

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure

from rnnpb.analysis.figures._common import (
    save,
)
from rnnpb.vectors import (
    MOTOR_NAMES,
    SENSORY_NAMES,
)

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
