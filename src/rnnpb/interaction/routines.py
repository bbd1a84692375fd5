"""The routine level in the interaction loop: :class:`RoutineMirror` stands where the loop
expects a :class:`~rnnpb.model.MirrorSystem` and runs both levels
(:class:`rnnpb.model.routines.TwoLevelMirror`); the recording's ``routine`` and
``anticipated`` columns come from it (:data:`ROUTINE_COLUMNS`)."""

from __future__ import annotations

from typing import Any

import numpy as np

from rnnpb.model import OnlineConfig, StepResult, TrainedModel
from rnnpb.model.meta import MetaParams
from rnnpb.model.recognition import RecognitionConfig
from rnnpb.model.routines import RoutineModel, TwoLevelMirror, TwoLevelStep

ROUTINE_COLUMNS = ("routine", "anticipated")
"""Per step: the routine recognised (empty: none) and the movement it says comes next."""


class RoutineMirror:
    """Both levels behind the mirror system's ``step``: returns the lower level's
    :class:`StepResult`; :attr:`last` holds the step of both levels."""

    def __init__(
        self,
        model: TrainedModel,
        routines: RoutineModel,
        config: OnlineConfig | None = None,
        meta: MetaParams | None = None,
        recognition: RecognitionConfig | None = None,
        **options: Any,
    ) -> None:
        """``options``: the lower mirror system's meta-level ``steering`` and ``inhibition``."""
        self.model = model
        self.two_levels = TwoLevelMirror(
            model, routines, config, meta=meta, recognition=recognition, **options
        )
        self.mirror = self.two_levels.mirror
        self.last: TwoLevelStep | None = None

    @property
    def config(self) -> OnlineConfig:
        return self.mirror.config

    @property
    def recognition(self) -> RecognitionConfig:
        return self.mirror.recognition

    def step(self, observed_hands: np.ndarray) -> StepResult:
        self.last = self.two_levels.step(observed_hands)
        return self.last.lower

    def columns(self, record: object = None) -> list[str]:
        """The ``routine`` and ``anticipated`` values of the last step."""
        if self.last is None:
            return ["", ""]
        return [self.last.higher.routine or "", self.last.anticipated or ""]
