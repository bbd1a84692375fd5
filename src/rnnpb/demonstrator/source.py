"""The synthetic demonstrator as a :class:`~rnnpb.sources.UserSource`."""

from __future__ import annotations

from rnnpb.errors import ConfigError
from rnnpb.sources import Observation, UserSource

from ._scenarios import Scenario


class ScenarioSource(UserSource):
    """Plays a :class:`Scenario` one step per :meth:`read`, with its ground truth.

    Each observation carries ``truth`` with ``step``, ``pattern`` (or ``"pause"``), ``pause``,
    ``novel``, ``switch``, ``phase``, ``hands`` (2, 3) and ``motor`` (8,). ``read`` returns
    None after the last step, or starts over when ``loop`` is True.
    """

    def __init__(self, scenario: Scenario, loop: bool = False) -> None:
        self.scenario = scenario
        self.loop = bool(loop)
        self._step = 0
        self._open = False

    def connect(self) -> None:
        self._step = 0
        self._open = True

    def read(self) -> Observation | None:
        if not self._open:
            raise ConfigError("ScenarioSource: read() before connect()")
        if self._step >= self.scenario.n_steps:
            if not self.loop:
                return None
            self._step = 0
        t = self._step
        self._step += 1
        return Observation(sensory=self.scenario.sensory[t].copy(), truth=self.scenario.truth(t))

    def close(self) -> None:
        self._open = False

    def __len__(self) -> int:
        return self.scenario.n_steps
