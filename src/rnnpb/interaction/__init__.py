"""The interaction phase as a running system: the one grammar of source specs, the loop, session
recordings.

The user-source contract and the generic sources live in :mod:`rnnpb.sources`; they are
re-exported here because ``rnnpb.interaction`` was their home before.
"""

from rnnpb.interaction.loop import InteractionLoop, LoopConfig, LoopSummary, StepRecord
from rnnpb.interaction.recorder import SessionRecorder, read_session, session_columns
from rnnpb.interaction.sources import (
    CAMERA_KINDS,
    SOURCE_KINDS,
    SourceSpec,
    open_source,
    parse_scenario,
    parse_source_spec,
)
from rnnpb.sources import (
    ArraySensorySource,
    CsvSensorySource,
    FrameStepSource,
    Observation,
    UserSource,
)

__all__ = [
    "CAMERA_KINDS",
    "SOURCE_KINDS",
    "ArraySensorySource",
    "CsvSensorySource",
    "FrameStepSource",
    "InteractionLoop",
    "LoopConfig",
    "LoopSummary",
    "Observation",
    "SessionRecorder",
    "SourceSpec",
    "StepRecord",
    "UserSource",
    "open_source",
    "parse_scenario",
    "parse_source_spec",
    "read_session",
    "session_columns",
]
