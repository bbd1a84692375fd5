"""The settings a run of the interaction uses, with a ``--config`` file's values over them:
one path for ``rnnpb interact`` and the dashboard (``rnnpb serve``).

A run first chooses its settings for the model (:meth:`rnnpb.model.OnlineConfig.for_model`:
the on-line regression and the recognition its learning preset measured; teaching's
:class:`~rnnpb.interaction.episodes.TeachingConfig`; the consolidation policy for teaching,
:func:`rnnpb.model.consolidation.consolidation_config`), then :class:`ConfigTables` puts the
file's tables over them: ``[online]``, ``[recognition]`` (a model with taught hands) or
``[recognition_untaught]``, ``[teaching.cutter]``, and ``[teaching]`` and ``[consolidation]``
for the consolidations teaching runs (docs/model.md, "Settings").
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

from rnnpb.model._tuned import apply_table

if TYPE_CHECKING:
    from rnnpb.interaction.episodes import TeachingConfig
    from rnnpb.model import OnlineConfig, TrainedModel
    from rnnpb.model.online_config import OnlineChoice
    from rnnpb.model.recognition import RecognitionConfig

TEACHING_SECTIONS = ("teaching", "teaching.cutter", "consolidation")
"""The tables of a ``--config`` file only teaching reads."""
CONSOLIDATION_SECTIONS = ("consolidation", "teaching")
"""The tables the consolidation policy for teaching reads."""


@dataclass(frozen=True, eq=False)
class ConfigTables:
    """A checked ``--config`` file's tables for a run of the interaction (no file: none).

    Attributes
    ----------
    tables : mapping of str to dict
        Each table the file names (``"online"``, ``"online.pb"``, ``"teaching.cutter"``, ...)
        to its values, each of the kind the preset's value has
        (:func:`rnnpb.commands._config.read_config` checks them).
    origin : str
        Where they came from (the file's path), for the evidence of a changed value.
    """

    tables: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    origin: str = "--config"

    def online(self, config: OnlineConfig) -> OnlineConfig:
        """``config`` with the ``[online]`` table's values."""
        return apply_table(config, self.tables, "online")

    def recognition_for(self, model: TrainedModel) -> RecognitionConfig:
        """The recognition settings chosen for ``model``, with the ``[recognition]`` table's
        values (``[recognition_untaught]`` for a model that kept no taught hands)."""
        from rnnpb.model import OnlineConfig

        chosen = OnlineConfig.for_model(model).recognition
        taught = model.taught_sensory is not None
        return apply_table(chosen, self.tables, "recognition" if taught else "recognition_untaught")

    def choice_for(self, model: TrainedModel) -> OnlineChoice:
        """:meth:`OnlineConfig.for_model`'s choice for ``model`` with the file's
        ``[online]`` and recognition tables."""
        from rnnpb.model import OnlineConfig

        choice = OnlineConfig.for_model(model)
        return replace(
            choice, config=self.online(choice.config), recognition=self.recognition_for(model)
        )

    def teaching(self, config: TeachingConfig) -> TeachingConfig:
        """``config`` with the ``[teaching.cutter]`` table's values."""
        return apply_table(config, self.tables, "teaching.cutter")

    @property
    def consolidation(self) -> dict[str, dict[str, Any]] | None:
        """The tables for teaching's consolidations (the ``overrides`` of
        :func:`rnnpb.model.consolidation.consolidation_config`), None when the file names
        none; plain dicts, for a worker process."""
        named = {n: dict(self.tables[n]) for n in CONSOLIDATION_SECTIONS if n in self.tables}
        return named or None

    @property
    def teaches(self) -> bool:
        """Whether the file names a table only teaching reads."""
        return any(name in self.tables for name in TEACHING_SECTIONS)
