"""Figures (the only place matplotlib is imported). Each function writes one PNG.

One module per experiment: :mod:`~rnnpb.analysis.figures.paper` (the paper's figures, drawn by
``rnnpb demo``), :mod:`~rnnpb.analysis.figures.patterns` (the demonstrations), one per study
(``novelty``, ``incremental``, ``teach``, ``safety``, ``dyad``, ``people``) and
:mod:`~rnnpb.analysis.figures.sweeps`; what they share is in ``_common``. Every figure is
re-exported here.

The figures are drawn with matplotlib's object API (:class:`matplotlib.figure.Figure`), not
pyplot: no backend is chosen or needed, importing this package changes nothing, and a notebook
keeps its inline plots.
"""

from rnnpb.analysis.attractors import ClosedLoopRun, context_plane, context_units
from rnnpb.analysis.figures._common import (
    JUMP_MARK,
    PB_COLORS,
    PLOTTED_JOINTS,
    SENSORY_COLORS,
    save,
)
from rnnpb.analysis.figures.dyad import plot_dyad, plot_patterns_found, plot_phase_diagram
from rnnpb.analysis.figures.incremental import plot_forgetting
from rnnpb.analysis.figures.novelty import (
    NOVELTY_STATES_SHOWN,
    plot_confusion,
    plot_delays,
    plot_roc,
)
from rnnpb.analysis.figures.paper import (
    NovelRun,
    plot_attractors,
    plot_novel_responses,
    plot_session,
    plot_switch_matrix,
    plot_switch_zoom,
    plot_training,
)
from rnnpb.analysis.figures.patterns import plot_patterns
from rnnpb.analysis.figures.people import plot_following
from rnnpb.analysis.figures.routines import plot_two_levels
from rnnpb.analysis.figures.safety import plot_pb_safety_map
from rnnpb.analysis.figures.sweeps import IntervalLike, plot_distributions
from rnnpb.analysis.figures.teach import TEACHING_COLORS, plot_teaching_timeline
from rnnpb.analysis.pb import PB_JUMP, nearest_patterns, pb_jumps

__all__ = [
    "JUMP_MARK",
    "NOVELTY_STATES_SHOWN",
    "PB_COLORS",
    "PB_JUMP",
    "PLOTTED_JOINTS",
    "SENSORY_COLORS",
    "TEACHING_COLORS",
    "ClosedLoopRun",
    "IntervalLike",
    "NovelRun",
    "context_plane",
    "context_units",
    "nearest_patterns",
    "pb_jumps",
    "plot_attractors",
    "plot_confusion",
    "plot_delays",
    "plot_distributions",
    "plot_dyad",
    "plot_forgetting",
    "plot_novel_responses",
    "plot_following",
    "plot_two_levels",
    "plot_patterns",
    "plot_patterns_found",
    "plot_pb_safety_map",
    "plot_phase_diagram",
    "plot_roc",
    "plot_session",
    "plot_switch_matrix",
    "plot_switch_zoom",
    "plot_teaching_timeline",
    "plot_training",
    "save",
]
