"""The paper's experiments (section 3) over the library, and the report that shows them."""

from rnnpb.experiments.paper import (
    ExperimentConfig,
    follows_every_pattern,
    learned_attractors,
    novel_response,
    run_scenario,
    switching,
    switching_sequence,
    synchronization,
)
from rnnpb.experiments.report import run_demo, write_report

__all__ = [
    "ExperimentConfig",
    "follows_every_pattern",
    "learned_attractors",
    "novel_response",
    "run_demo",
    "run_scenario",
    "switching",
    "switching_sequence",
    "synchronization",
    "write_report",
]
