"""The synthetic user: the paper's four movement patterns with human imperfection, the
training datasets and the scripted interaction scenarios (docs/robot-and-demonstrator.md)."""

from rnnpb.demonstrator._datafiles import write_dataset
from rnnpb.demonstrator._datasets import (
    DEFAULT_SAMPLES,
    DEFAULT_STEPS,
    LEARNING_SETS,
    demonstration,
    learning_set,
    learning_set_patterns,
    novel_pattern,
    pattern_dataset,
    sample_rng,
)
from rnnpb.demonstrator._mapping import MirrorMapping
from rnnpb.demonstrator._scenarios import (
    Scenario,
    held_scenario,
    make_scenario,
    novel_scenario,
    pause_scenario,
    scenario_arrays,
    switch_scenario,
)
from rnnpb.demonstrator._user import (
    PATTERN_ALIASES,
    PATTERN_DESCRIPTIONS,
    PATTERNS,
    PAUSE,
    HandMotion,
    Imperfection,
    PatternConfig,
    UserBody,
    pattern_offsets,
    perform,
    resolve_pattern,
)
from rnnpb.demonstrator.source import ScenarioSource

__all__ = [
    "DEFAULT_SAMPLES",
    "DEFAULT_STEPS",
    "LEARNING_SETS",
    "PATTERN_ALIASES",
    "PATTERN_DESCRIPTIONS",
    "PATTERNS",
    "PAUSE",
    "HandMotion",
    "Imperfection",
    "MirrorMapping",
    "PatternConfig",
    "Scenario",
    "ScenarioSource",
    "UserBody",
    "demonstration",
    "held_scenario",
    "learning_set",
    "learning_set_patterns",
    "make_scenario",
    "novel_pattern",
    "novel_scenario",
    "pattern_dataset",
    "pattern_offsets",
    "pause_scenario",
    "perform",
    "resolve_pattern",
    "sample_rng",
    "scenario_arrays",
    "switch_scenario",
    "write_dataset",
]
