"""The incremental study's scenario: which patterns are added to which models, and how.

For each learning set the left-out pattern is added to the set's model by each method of
:func:`rnnpb.model.consolidation.consolidate` (:func:`add_patterns`: the one place the study
consolidates); a chain starts from a few patterns and adds the others one at a time by
rehearsal, ending with a new shape of the demonstrator; new shapes are added to the larger
set's model (the paper's four patterns).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from pathlib import Path

from rnnpb.errors import ConfigError
from rnnpb.experiments.scenarios.study_models import study_models
from rnnpb.model import OnlineConfig, TrainConfig, TrainedModel
from rnnpb.model.consolidation import CONSOLIDATION_METHODS, consolidate, consolidation_config


@dataclass(frozen=True)
class IncrementalConfig:
    """What the study runs.

    ``models``: a directory with ``set1.npz`` … ``set4.npz`` and the larger set's model (the
    demo's) to start from; None: learn the starting models with ``start_train``
    (:func:`starting_model`). ``chain_start``, ``chain_added``: the
    chain's first patterns and those it adds one at a time, ending with a new shape of the
    demonstrator beyond the paper's four (:data:`rnnpb.demonstrator.NEW_SHAPES`).
    """

    quick: bool = False
    models: str | None = None
    learning_sets: tuple[str, ...] = ("1", "2", "3", "4")
    methods: tuple[str, ...] = CONSOLIDATION_METHODS
    start_train: TrainConfig = field(default_factory=TrainConfig.paper)
    # None: the consolidation policy's learning for the model (consolidation_config).
    consolidation_train: TrainConfig | None = None
    # From scratch: 20,000 of the paper's iterations, enough for four patterns to be followed
    # in less time than the first learning's 50,000 (docs/experiments.md).
    scratch_train: TrainConfig | None = field(
        default_factory=lambda: TrainConfig.paper(iterations=20_000)
    )
    online: OnlineConfig = field(default_factory=OnlineConfig)
    chain_start: tuple[str, ...] = ("1", "2")
    chain_added: tuple[str, ...] = ("3", "4", "figure-eight")
    # New shapes of the demonstrator beyond the paper's four, each added by rehearsal to the
    # larger set's model (the four patterns: `full.npz` or `full_seed0.npz` of ``models``).
    larger_set_shapes: tuple[str, ...] = ("figure-eight", "diagonal", "one-arm", "asymmetric")
    data_seed: int = 0
    new_data_seed: int = 0
    scenario_seed: int = 100
    attractor_steps: int = 400
    attractor_transient: int = 200
    # The demo's 75 steps before the pause: recognition reads the PB at its end, and the
    # gated regression's PB needs them to settle. Switching is judged within 15 steps: 30 of
    # each pattern (the demo's: 50) still show "never" beyond it.
    sync_before: int = 75
    switch_steps_each: int = 30
    workers: int = 2

    def __post_init__(self) -> None:
        unknown = [m for m in self.methods if m not in CONSOLIDATION_METHODS]
        if unknown:
            raise ConfigError(f"unknown consolidation method(s) {unknown}")
        if not self.methods or not self.learning_sets:
            raise ConfigError("the study needs at least one method and one learning set")
        if len(self.chain_start) < 1:
            raise ConfigError("the chain needs at least one first pattern")

    @classmethod
    def quick_run(cls, seed: int = 0) -> IncrementalConfig:
        """Small fast-preset models of the study's own, one learning set, short runs."""
        fast = TrainConfig.fast(iterations=800, seed=seed)
        return cls(
            quick=True,
            learning_sets=("1",),
            start_train=fast,
            consolidation_train=TrainConfig.fast(iterations=200, seed=seed),
            scratch_train=fast,
            online=OnlineConfig.ungated(),
            chain_start=("1",),
            chain_added=("2",),
            larger_set_shapes=("figure-eight",),
            data_seed=seed,
            new_data_seed=seed,
            attractor_steps=200,
            attractor_transient=100,
            sync_before=24,
            switch_steps_each=20,
            workers=1,
        )


def demonstrations(patterns, seed: int):
    """The demonstrator's demonstrations of ``patterns``, draw ``seed``."""
    from rnnpb.demonstrator import pattern_dataset

    return pattern_dataset(seed, tuple(patterns))


def starting_model(set_name: str, config: IncrementalConfig, out: Path) -> str:
    """The path of learning set ``set_name``'s starting model: ``config.models``'s, or learned
    with ``start_train`` into ``out`` (the larger set is ``"full"``)."""

    def learning(_name: str) -> TrainConfig:
        return config.start_train

    return study_models((set_name,), config.models, out, learning, config.data_seed)[set_name]


def add_patterns(
    model: TrainedModel,
    new,
    method: str,
    config: IncrementalConfig,
    parent: str,
    replay_data=None,
) -> tuple[TrainedModel, float]:
    """``model`` with the demonstrations ``new`` added by ``method`` under the consolidation
    policy (:func:`rnnpb.model.consolidation.consolidation_config`), learning with the study's
    ``scratch_train`` (scratch) or ``consolidation_train`` (the others) where it names one, and
    the CPU seconds it took."""
    learning = config.scratch_train if method == "scratch" else config.consolidation_train
    policy = consolidation_config(model, "add", method=method)  # type: ignore[arg-type]
    policy = replace(policy, train=learning) if learning is not None else policy
    cpu = time.process_time()
    grown = consolidate(model, new, policy, replay_data=replay_data, parent=parent)
    return grown, time.process_time() - cpu
