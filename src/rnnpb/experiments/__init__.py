"""The paper's experiments (section 3) over the library, and the report that shows them.

:mod:`~rnnpb.experiments.paper` holds the experiments and their result objects,
:mod:`~rnnpb.experiments.jobs` what the demo runs and its jobs, one per learned model,
:mod:`~rnnpb.experiments.summary` the measures over all jobs and the targets they meet,
:mod:`~rnnpb.experiments.demo` the demo, :mod:`~rnnpb.experiments.report` its report, and
:mod:`~rnnpb.experiments.reporting` what every report shares (tables, figures, versions,
writing ``report.md`` and ``results.json``).

The names below are imported when first used, so that importing a part of this package (a
study's options for the command line, say) does not load JAX.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from rnnpb.experiments.demo import run_demo
    from rnnpb.experiments.jobs import (
        ExperimentConfig,
        LargerSetRun,
        LearningSetResult,
        larger_set_job,
        learning_set_job,
    )
    from rnnpb.experiments.paper import (
        Attractor,
        Draw,
        FollowsEveryPattern,
        NovelResponse,
        Run,
        Switching,
        SwitchingSequence,
        Synchronization,
        follows_every_pattern,
        learned_attractors,
        novel_response,
        run_scenario,
        switching,
        switching_sequence,
        synchronization,
    )
    from rnnpb.experiments.report import (
        describe_configuration,
        missing_cases_explanation,
        report_lines,
        write_report,
    )
    from rnnpb.experiments.summary import (
        DemoResults,
        DrawsSummary,
        DrawSummary,
        Summary,
        Target,
        draws_summary,
        summarize,
        targets,
    )

# name -> the module of this package that defines it
_EXPORTS: dict[str, str] = {
    "Attractor": "paper",
    "Draw": "paper",
    "ExperimentConfig": "jobs",
    "FollowsEveryPattern": "paper",
    "LargerSetRun": "jobs",
    "LearningSetResult": "jobs",
    "NovelResponse": "paper",
    "Run": "paper",
    "Switching": "paper",
    "SwitchingSequence": "paper",
    "Synchronization": "paper",
    "follows_every_pattern": "paper",
    "larger_set_job": "jobs",
    "learned_attractors": "paper",
    "learning_set_job": "jobs",
    "novel_response": "paper",
    "run_scenario": "paper",
    "switching": "paper",
    "switching_sequence": "paper",
    "synchronization": "paper",
    "describe_configuration": "report",
    "missing_cases_explanation": "report",
    "report_lines": "report",
    "run_demo": "demo",
    "write_report": "report",
    "DemoResults": "summary",
    "DrawsSummary": "summary",
    "DrawSummary": "summary",
    "Summary": "summary",
    "Target": "summary",
    "draws_summary": "summary",
    "summarize": "summary",
    "targets": "summary",
}


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_EXPORTS})


__all__ = [
    "Attractor",
    "DemoResults",
    "Draw",
    "DrawSummary",
    "DrawsSummary",
    "ExperimentConfig",
    "FollowsEveryPattern",
    "LargerSetRun",
    "LearningSetResult",
    "NovelResponse",
    "Run",
    "Summary",
    "Switching",
    "SwitchingSequence",
    "Synchronization",
    "Target",
    "describe_configuration",
    "draws_summary",
    "follows_every_pattern",
    "larger_set_job",
    "learned_attractors",
    "learning_set_job",
    "missing_cases_explanation",
    "novel_response",
    "report_lines",
    "run_demo",
    "run_scenario",
    "summarize",
    "switching",
    "switching_sequence",
    "synchronization",
    "targets",
    "write_report",
]
