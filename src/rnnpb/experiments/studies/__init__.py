"""The studies beyond the paper's section 3: ``rnnpb study NAME [--quick] --out DIR``.

A study is one module of this package that defines

- ``NAME`` (the word on the command line) and ``SUMMARY`` (one line for ``--help``),
- ``run(out: Path, options: StudyOptions) -> StudyOutcome``, which writes ``out/report.md``
  (figures embedded from ``out/figures/``) and ``out/results.json`` (every measure, with the
  config, seeds and versions: :func:`rnnpb.experiments.reporting.write_outputs`), each atomically.

and is listed in :data:`STUDY_MODULES`. Only studies that exist are listed: the command offers
what runs. A study with an exam (:mod:`rnnpb.experiments.exams`) also defines

- ``judge_results(results: dict, exam: Exam) -> dict[str, Target]``: its targets judged by the
  exam's definitions from a finished ``results.json``,

and runs on the exam's draws when ``options.exam`` is given (``rnnpb study NAME --exam``).
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass, field
from types import ModuleType
from typing import TYPE_CHECKING

from rnnpb.errors import ConfigError

if TYPE_CHECKING:  # the command line lists the studies without loading JAX
    from rnnpb.experiments.exams import Exam
    from rnnpb.experiments.summary import Target

# name -> module; the order is the order of `rnnpb study --help`.
STUDY_MODULES: dict[str, str] = {
    "novelty": "rnnpb.experiments.studies.novelty",
    "incremental": "rnnpb.experiments.studies.incremental",
    "safety": "rnnpb.experiments.studies.safety",
    "dyad": "rnnpb.experiments.studies.dyad",
    "teach": "rnnpb.experiments.studies.teach",
    "people": "rnnpb.experiments.studies.people",
    "routines": "rnnpb.experiments.studies.routines",
}


def demo_model_names(learning_set: str) -> tuple[str, ...]:
    """The file names, in order of preference, under which ``rnnpb demo``'s models directory
    holds a learning set's model: ``setK.npz``; the larger set (``"full"``) ``full.npz`` or
    its first seed's ``full_seed0.npz``."""
    return ("full.npz", "full_seed0.npz") if learning_set == "full" else (f"set{learning_set}.npz",)


@dataclass(frozen=True)
class StudyOptions:
    """What every study takes. ``quick``: the short form (the one the tests run); ``workers``:
    parallel worker processes; ``seed``: the first seed of the study's draws; ``models``: a
    directory of learned models to start from (None: the study learns those it needs);
    ``exam``: run on the exam's draws instead of ``seed``'s (the full form only); ``data``: a
    directory of recordings the study reads (the people study's motion capture)."""

    quick: bool = False
    workers: int = 2
    seed: int = 0
    models: str | None = None
    exam: Exam | None = None
    data: str | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.workers, int) or isinstance(self.workers, bool) or self.workers < 1:
            raise ConfigError(f"workers must be a whole number >= 1, got {self.workers!r}")
        if not isinstance(self.seed, int) or isinstance(self.seed, bool) or self.seed < 0:
            raise ConfigError(f"seed must be a whole number >= 0, got {self.seed!r}")
        if self.exam is not None and self.quick:
            raise ConfigError("an exam runs the full form: --exam and --quick exclude each other")


@dataclass(frozen=True)
class StudyOutcome:
    """What a study tells the command line once its files are written: its targets (met or
    not, and by how much) and how long it ran."""

    runtime_s: float
    targets: dict[str, Target] = field(default_factory=dict)


def study_names() -> tuple[str, ...]:
    return tuple(STUDY_MODULES)


def takes_exam(study: ModuleType) -> bool:
    """Whether ``study`` (a study's module) runs and judges an exam."""
    return callable(getattr(study, "judge_results", None))


def load_study(name: str) -> ModuleType:
    """The module of study ``name``; a clear error for a name no study has."""
    if name not in STUDY_MODULES:
        known = ", ".join(STUDY_MODULES) or "none yet"
        raise ConfigError(f"no study {name!r} (studies: {known})")
    return importlib.import_module(STUDY_MODULES[name])


__all__ = [
    "STUDY_MODULES",
    "StudyOptions",
    "StudyOutcome",
    "load_study",
    "study_names",
    "takes_exam",
]
