"""How the PB is regressed on-line (:mod:`rnnpb.model.online`): the settings and their presets.

``OnlineConfig.paper()`` is the paper's regression (section 2.3); ``OnlineConfig()`` the best
measured (docs/model.md), ``OnlineConfig.ungated()`` the same without the surprise gate.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import asdict, dataclass, field, fields, replace
from typing import Any, Literal

from rnnpb.errors import ConfigError
from rnnpb.model.parametric_bias import PBUpdateConfig
from rnnpb.model.recognition import RecognitionConfig


@dataclass(frozen=True)
class OnlineConfig:
    """How the PB is regressed on-line.

    ``OnlineConfig.paper()``: L = 30, 100 iterations, l = 20, the onset state carried over and
    not optimised. ``OnlineConfig()`` (the default) is the best measured with models learned
    by the paper's algorithm (docs/model.md): the onset state optimised with the PB, l = 4
    without the low-pass term, restarts — before each regression, the last ``restart_span``
    steps of the PB profile are also tried at each learned pattern's PB, and the regression
    starts from the profile that fits best — phase restarts (below) and the surprise gate,
    which lets the PB settle once the predictions are good. ``OnlineConfig.ungated()`` is the
    default without the gate, the better choice for models learned with
    ``TrainConfig.fast()``.
    """

    window: int = 30  # L
    iterations: int = 100
    pb: PBUpdateConfig = field(
        default_factory=lambda: PBUpdateConfig(
            learning_rate=1.0, momentum=0.9, k_bp=1.0, k_nb=0.0, integration_length=4
        )
    )
    optimize_onset: bool = True
    onset_learning_rate: float = 0.5
    restart_span: int = 6
    motor_input: Literal["closed_loop", "recorded"] = "closed_loop"
    # The surprise gate (0 turns it off): before each regression, the RMS sensory error of the
    # window's last ``gate_steps`` predictions scales the error term of eq. 1 by
    # (error / surprise_gate) ** gate_power, clipped to [gate_floor, 1]: the PB moves at its
    # full rate while the predictions are poor and all but stops once they are good.
    surprise_gate: float = 0.035
    gate_power: float = 4.0
    gate_floor: float = 0.01
    gate_steps: int = 4
    # Phase restarts (0 turns them off): before each regression, the network is also started
    # ``phase_restarts + 1`` steps back from each of a set of states on the learned patterns'
    # cycles (with that pattern's PB); where one predicts the last ``phase_restarts``
    # observations better than the window does, by the factor ``phase_restart_ratio``, and the
    # window's own prediction error there is above ``phase_restart_level`` (RMS), the window
    # starts over from that state.
    phase_restarts: int = 3
    phase_restart_ratio: float = 0.5
    phase_restart_level: float = 0.02
    # The safety guard (docs/safety.md; acts only when the mirror system has a safety map):
    # "barrier" adds barrier_weight * softplus(risk logit - logit(risk_level)) per window step
    # to the error of eq. 1 (rnnpb.model.meta); "projection" moves each regressed PB down the
    # risk gradient (at most projection_steps steps of projection_rate in rho) until its risk
    # is below risk_level; "off" ignores the map. The default, the barrier on the newest
    # step (barrier_span 1; 0: the whole window), keeps the PB out of the learned region on
    # 10^4-step adversarial runs where the projection let it in, for about 0.2 ms a step
    # (docs/safety.md measures the choices); it acts only where a map is given.
    safety_guard: Literal["off", "barrier", "projection"] = "barrier"
    barrier_weight: float = 0.05
    barrier_span: int = 1
    risk_level: float = 0.2
    projection_steps: int = 10
    projection_rate: float = 0.3

    def __post_init__(self) -> None:
        for item in fields(self):
            value = getattr(self, item.name)
            if item.name in ("pb", "motor_input", "safety_guard"):  # checked below
                continue
            if item.name == "optimize_onset":
                if not isinstance(value, bool):
                    raise ConfigError(f"optimize_onset must be True or False, got {value!r:.40}")
                continue
            # Checked before any comparison: NaN passes every `<` test below, and a bool or a
            # string is no setting.
            if isinstance(value, bool) or not isinstance(value, numbers.Real):
                raise ConfigError(f"{item.name} must be a number, got {value!r:.40}")
            if item.type in ("int", int) and not isinstance(value, numbers.Integral):
                raise ConfigError(f"{item.name} must be a whole number, got {value!r:.40}")
            try:
                finite = math.isfinite(value)
            except OverflowError:  # an integer beyond float range
                finite = False
            if not finite:
                raise ConfigError(f"{item.name} must be finite, got {value!r:.40}")
        if self.window < 2:
            raise ConfigError(f"regression window must be >= 2 steps, got {self.window}")
        if self.iterations < 0:
            raise ConfigError(f"iterations must be >= 0, got {self.iterations}")
        if self.onset_learning_rate < 0:
            raise ConfigError("onset_learning_rate must be >= 0")
        if not 0 <= self.restart_span <= self.window:
            raise ConfigError(f"restart_span must be in [0, window], got {self.restart_span}")
        if self.surprise_gate < 0:
            raise ConfigError(f"surprise_gate must be >= 0, got {self.surprise_gate}")
        if self.gate_power <= 0:
            raise ConfigError(f"gate_power must be > 0, got {self.gate_power}")
        if not 0 < self.gate_floor <= 1:
            raise ConfigError(f"gate_floor must be in (0, 1], got {self.gate_floor}")
        if self.gate_steps < 1:
            raise ConfigError(f"gate_steps must be >= 1, got {self.gate_steps}")
        if not 0 <= self.phase_restarts < self.window:
            raise ConfigError(f"phase_restarts must be in [0, window), got {self.phase_restarts}")
        if not 0 < self.phase_restart_ratio <= 1:
            raise ConfigError("phase_restart_ratio must be in (0, 1]")
        if self.phase_restart_level < 0:
            raise ConfigError("phase_restart_level must be >= 0")
        if self.safety_guard not in ("off", "barrier", "projection"):
            raise ConfigError(
                f"safety_guard must be 'off', 'barrier' or 'projection', got {self.safety_guard!r}"
            )
        if not 0 <= self.barrier_span <= self.window:
            raise ConfigError(f"barrier_span must be in [0, window], got {self.barrier_span}")
        if self.barrier_weight < 0:
            raise ConfigError(f"barrier_weight must be >= 0, got {self.barrier_weight}")
        if not 0 < self.risk_level < 1:
            raise ConfigError(f"risk_level must be in (0, 1), got {self.risk_level}")
        if self.projection_steps < 0 or self.projection_rate < 0:
            raise ConfigError("projection_steps and projection_rate must be >= 0")
        if self.motor_input not in ("closed_loop", "recorded"):
            raise ConfigError(
                f"motor_input must be 'closed_loop' or 'recorded', got {self.motor_input!r}"
            )

    @classmethod
    def paper(cls, **changes: Any) -> OnlineConfig:
        """The paper's regression: L = 30, 100 iterations, l = 20, no onset optimisation, no
        safety guard (the paper proposes the meta-level, section 4.1, but did not run it)."""
        base = cls(
            pb=PBUpdateConfig(
                learning_rate=0.5, momentum=0.9, k_bp=1.0, k_nb=0.2, integration_length=20
            ),
            optimize_onset=False,
            restart_span=0,
            surprise_gate=0.0,
            phase_restarts=0,
            safety_guard="off",
        )
        return replace(base, **changes)

    @classmethod
    def ungated(cls, **changes: Any) -> OnlineConfig:
        """The default without the surprise gate: the PB keeps fitting every step. Models
        learned with ``TrainConfig.fast()`` lock on and switch faster with it, though their
        PB never settles (docs/model.md)."""
        return replace(cls(surprise_gate=0.0), **changes)

    @classmethod
    def preset(cls, name: str) -> OnlineConfig:
        """The preset called ``name``: one of :data:`ONLINE_PRESETS`."""
        if name not in ONLINE_PRESETS:
            raise ConfigError(
                f"unknown on-line regression {name!r}; choose one of {', '.join(ONLINE_PRESETS)}"
            )
        return {"default": cls, "paper": cls.paper, "ungated": cls.ungated}[name]()

    @classmethod
    def for_model(cls, model: Any) -> OnlineChoice:
        """The regression that suits ``model``: see :func:`suggested_online_config`."""
        return suggested_online_config(model)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> OnlineConfig:
        data = dict(data)
        data["pb"] = PBUpdateConfig(**data["pb"])
        return cls(**data)


#: The on-line regression presets by name, as ``--online`` takes them.
ONLINE_PRESETS: tuple[str, ...] = ("default", "paper", "ungated")


@dataclass(frozen=True)
class OnlineChoice:
    """Which on-line regression and which recognition settings go with a model, and why.

    Attributes
    ----------
    name : str
        One of :data:`ONLINE_PRESETS`.
    config : OnlineConfig
    reason : str
        One line for the user: what in the model decided it.
    recognition : RecognitionConfig
        The recognition settings chosen for models learned as this one was
        (``RecognitionConfig()`` for the paper's algorithm, ``RecognitionConfig.fast()`` for
        the fast preset: docs/model.md, "Recognition and novelty").
    """

    name: str
    config: OnlineConfig
    reason: str
    recognition: RecognitionConfig = field(default_factory=RecognitionConfig)


def suggested_online_config(model: Any) -> OnlineChoice:
    """The on-line regression that suits a model's recorded learning.

    A model learned with ``TrainConfig.fast()`` (Adam, noise on the inputs) locks on and
    switches best without the surprise gate (``OnlineConfig.ungated()``); one learned by the
    paper's algorithm (momentum descent), or one whose learning is not recorded, takes the
    default (docs/model.md, "On-line regression"). The recognition settings follow the same
    way: the fast preset's models give other evidence levels (docs/model.md, "Recognition and
    novelty"). The model's ``meta["train_config"]`` is
    what it records of its learning (:class:`rnnpb.model.TrainConfig` as a dict).

    Parameters
    ----------
    model : TrainedModel
        Anything with a ``meta`` dict.
    """
    meta = getattr(model, "meta", None) or {}
    learned = meta.get("train_config") if isinstance(meta, dict) else None
    # A model that kept its hands as taught is recognised with them, one that did not (a file
    # of format 1 or 2) by the network's evidence alone, each with the settings chosen for it.
    taught = getattr(model, "taught_sensory", None) is not None
    paper = RecognitionConfig() if taught else RecognitionConfig.untaught()
    if not isinstance(learned, dict):
        return OnlineChoice(
            "default", OnlineConfig(), "the model does not record how it was learned", paper
        )
    optimizer = learned.get("optimizer")
    if optimizer == "adam":
        return OnlineChoice(
            "ungated",
            OnlineConfig.ungated(),
            "the model was learned with Adam, the fast preset",
            RecognitionConfig.fast() if taught else RecognitionConfig.untaught(fast=True),
        )
    return OnlineChoice(
        "default",
        OnlineConfig(),
        f"the model was learned with {optimizer} descent, the paper's algorithm",
        paper,
    )
