"""The RNNPB: network, learning, generation and on-line PB regression.

Pure functions and their configs, with no I/O or clocks, except where a module says why in its
docstring: model files (``io.py``, as archives: ``archive.py``), the training driver's
checkpoints and clock (``training.py``) and the clock of consolidation's history
(``consolidation.py``).
The float64 ``ReferenceMirrorSystem`` (``mirror.py``) is the twin the float32 step is held to.
"""

from rnnpb.model.batched import BatchedMirror, run_streams
from rnnpb.model.consolidation import (
    CONSOLIDATION_METHODS,
    ConsolidationConfig,
    ConsolidationPolicy,
    consolidate,
    consolidation_config,
    consolidation_policy,
    rehearse,
)
from rnnpb.model.generation import Generated, generate
from rnnpb.model.io import HistoryEntry, TrainedModel
from rnnpb.model.learning import TrainConfig
from rnnpb.model.mirror import MIRROR_SYSTEMS, MirrorSystem, ReferenceMirrorSystem, StepResult
from rnnpb.model.network import (
    NetworkConfig,
    Params,
    closed_loop,
    init_params,
    mixed_loop,
    open_loop,
    step,
)
from rnnpb.model.online_config import OnlineConfig
from rnnpb.model.parametric_bias import pb_update
from rnnpb.model.routines import RoutineFollower, RoutineModel, TwoLevelMirror, learn_routines
from rnnpb.model.training import TrainingProgress, train, train_seeds

__all__ = [
    "CONSOLIDATION_METHODS",
    "MIRROR_SYSTEMS",
    "BatchedMirror",
    "ConsolidationConfig",
    "ConsolidationPolicy",
    "Generated",
    "HistoryEntry",
    "MirrorSystem",
    "NetworkConfig",
    "OnlineConfig",
    "Params",
    "ReferenceMirrorSystem",
    "RoutineFollower",
    "RoutineModel",
    "StepResult",
    "TrainConfig",
    "TrainedModel",
    "TrainingProgress",
    "TwoLevelMirror",
    "closed_loop",
    "consolidate",
    "consolidation_config",
    "consolidation_policy",
    "generate",
    "init_params",
    "learn_routines",
    "mixed_loop",
    "open_loop",
    "pb_update",
    "rehearse",
    "run_streams",
    "step",
    "train",
    "train_seeds",
]
