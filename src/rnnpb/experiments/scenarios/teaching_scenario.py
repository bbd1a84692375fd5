"""The teach study's scenario: the scripted user, the study's settings and its starting models.

Per learning set and new shape of the demonstrator (:data:`rnnpb.demonstrator.NEW_SHAPES`) a
scripted user stands in front of the robot and performs, one after another: a learned
pattern; the new shape, for several cycles; another learned pattern; the new shape a second
time (teaching learns a new movement from two performances, as a person shows it); the other
learned patterns; unstructured movement (a random walk, then jerky movement); and the new
shape again, its next performance (:func:`segments`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from rnnpb.errors import ConfigError
from rnnpb.experiments.scenarios.study_models import paper_training, study_models
from rnnpb.interaction.teaching import TeachingConfig
from rnnpb.model import OnlineConfig

UNSTRUCTURED_MOVEMENTS = ("random-walk", "jerky")
PERIOD = 12  # the demonstrator's period, steps (PatternConfig.period_steps)


@dataclass(frozen=True)
class TeachConfig:
    """What the study runs.

    ``models``: the directory of the starting models (:func:`starting_models`; None: learned
    with the paper's algorithm); ``shipped``: teach the shipped fast-preset model of learning
    set 1 instead (the quick form). ``consolidation_iterations``: None keeps
    teaching's policy (the model's preset's ``[teaching]`` ``iterations``:
    :func:`rnnpb.model.consolidation.consolidation_config` with ``purpose="teach"``), so that
    what improves there is what this study measures. The scripted user: ``lead_steps``
    of a learned pattern, ``new_steps`` of the new shape (each of its two first performances),
    ``other_steps`` of each other learned pattern, ``unstructured_steps`` of each unstructured
    movement, ``again_steps`` of the new shape again. ``paced``: the (learning set, shape)
    whose kept episodes are consolidated again during a paced run; ``paced_max_steps`` ends
    that run early (the consolidation is then cancelled: the quick form), else it ends
    ``paced_after_swap`` steps after the swap.
    """

    quick: bool = False
    models: str | None = None
    shipped: bool = False
    learning_sets: tuple[str, ...] = ("1", "2", "3", "4", "full")
    shapes: tuple[str, ...] = ("figure-eight", "diagonal", "one-arm", "asymmetric")
    online: OnlineConfig = field(default_factory=OnlineConfig)
    teaching: TeachingConfig = field(default_factory=TeachingConfig)
    consolidation_iterations: int | None = None
    dt: float = 0.4
    lead_steps: int = 36
    new_steps: int = 96
    other_steps: int = 36
    unstructured_steps: int = 60
    again_steps: int = 48
    scenario_seed: int = 100
    # The paper's measures after learning: the demo's 75 steps before the pause; switching is
    # judged within 15 steps, so 30 of each pattern (the demo's 50) still show "never".
    sync_before: int = 75
    switch_steps_each: int = 30
    switching_pairs: str = "all"  # "all", or "new": the pairs with the new pattern only
    # The paper's measures before and after teaching (the quick form judges the old patterns
    # by their lock-on in the timeline only).
    paper_measures: bool = True
    paced: tuple[str, str] | None = ("1", "figure-eight")
    paced_max_steps: int | None = None
    paced_after_swap: int = 36
    workers: int = 2

    def __post_init__(self) -> None:
        from rnnpb.demonstrator import NEW_SHAPES, learning_set_patterns

        for name in self.learning_sets:
            learning_set_patterns(name)
        unknown = [s for s in self.shapes if s not in NEW_SHAPES]
        if unknown or not self.shapes or not self.learning_sets:
            raise ConfigError(
                f"the study teaches new shapes of the demonstrator ({', '.join(NEW_SHAPES)}) "
                f"to one or more learning sets; got shapes {self.shapes}"
            )
        if self.switching_pairs not in ("all", "new"):
            raise ConfigError(f"switching_pairs must be 'all' or 'new', got {self.switching_pairs}")
        if self.new_steps < 4 * PERIOD or self.again_steps < 2 * PERIOD:
            raise ConfigError("the new shape needs time: new_steps >= 48, again_steps >= 24")

    @classmethod
    def quick_run(cls, seed: int = 0) -> TeachConfig:
        """The shipped model of learning set 1, one shape, the pairs with the new pattern;
        the paced run stops (and cancels its consolidation) after 8 steps."""
        return cls(
            quick=True,
            models=None,
            shipped=True,
            learning_sets=("1",),
            shapes=("figure-eight",),
            online=OnlineConfig.ungated(),
            scenario_seed=100 + seed,
            other_steps=30,
            unstructured_steps=40,
            again_steps=36,
            sync_before=36,
            switch_steps_each=30,
            switching_pairs="new",
            paper_measures=False,
            paced_max_steps=8,
            workers=1,
        )


def segments(
    patterns: tuple[str, ...], shape: str, index: int, config: TeachConfig
) -> list[tuple[str, int]]:
    """What the user performs, (movement, steps) in order, when taught the ``index``-th shape:
    the learned pattern it leads with is another per shape; the shape's two first
    performances have the first of the other learned patterns between them."""
    lead = patterns[index % len(patterns)]
    others = [p for p in patterns if p != lead]
    return [
        (lead, config.lead_steps),
        (shape, config.new_steps),
        (others[0], config.other_steps),
        (shape, config.new_steps),
        *((p, config.other_steps) for p in others[1:]),
        *((m, config.unstructured_steps) for m in UNSTRUCTURED_MOVEMENTS),
        (shape, config.again_steps),
    ]


def source_spec(segments: list[tuple[str, int]]) -> str:
    """The segments as a ``--source`` specification (what the memory records as the source)."""
    return "scenario:steps:" + ",".join(f"{m}*{n}" for m, n in segments)


def starting_models(config: TeachConfig, out: Path, pool=None) -> dict[str, str]:
    """The path of each learning set's starting model: the shipped one, ``config.models``'s,
    or learned into ``out`` with the paper's algorithm as ``rnnpb demo`` learns it (in
    ``pool``'s workers when one is given)."""
    if config.shipped:
        from rnnpb.models import SHIPPED_MODEL

        return {"1": str(SHIPPED_MODEL)}
    return study_models(config.learning_sets, config.models, out, paper_training, pool=pool)
