"""The interaction phase as a running system: sources, the loop, session recordings."""

from rnnpb.interaction.loop import InteractionLoop, LoopConfig, LoopSummary, StepRecord
from rnnpb.interaction.recorder import SessionRecorder, read_session, session_columns
from rnnpb.interaction.source import Observation, UserSource
from rnnpb.interaction.sources import (
    ArraySensorySource,
    CsvSensorySource,
    FrameStepSource,
    open_source,
    parse_scenario,
)

__all__ = [
    "ArraySensorySource",
    "CsvSensorySource",
    "FrameStepSource",
    "InteractionLoop",
    "LoopConfig",
    "LoopSummary",
    "Observation",
    "SessionRecorder",
    "StepRecord",
    "UserSource",
    "open_source",
    "parse_scenario",
    "read_session",
    "session_columns",
]
