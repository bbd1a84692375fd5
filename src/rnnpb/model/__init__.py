"""The RNNPB: network, learning, generation and on-line PB regression (no I/O, no clocks
beyond model files)."""

from rnnpb.model.generation import Generated, generate
from rnnpb.model.io import TrainedModel
from rnnpb.model.network import (
    NetworkConfig,
    Params,
    closed_loop,
    init_params,
    mixed_loop,
    open_loop,
    step,
)
from rnnpb.model.online import MirrorSystem, OnlineConfig, StepResult
from rnnpb.model.parametric_bias import PBUpdateConfig, pb_update
from rnnpb.model.training import TrainConfig, TrainingProgress, train

__all__ = [
    "Generated",
    "MirrorSystem",
    "NetworkConfig",
    "OnlineConfig",
    "PBUpdateConfig",
    "Params",
    "StepResult",
    "TrainConfig",
    "TrainedModel",
    "TrainingProgress",
    "closed_loop",
    "generate",
    "init_params",
    "mixed_loop",
    "open_loop",
    "pb_update",
    "step",
    "train",
]
