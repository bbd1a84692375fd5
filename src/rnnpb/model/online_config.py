"""How the PB is regressed on-line (:mod:`rnnpb.model.online`): the settings and their presets.

``OnlineConfig.paper()`` is the paper's regression (section 2.3); ``OnlineConfig()`` the one
chosen for models learned by the paper's algorithm, ``OnlineConfig.ungated()`` the one chosen
for the fast preset's (the same without the surprise gate). The settings a user changes are
the constructor's; every other value is read from the learning preset
(:mod:`rnnpb.presets`, section ``[online]``) and changed only by ``with_tuning``.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping
from dataclasses import InitVar, asdict, dataclass, field, fields, replace
from functools import cache
from typing import Any, Literal

from rnnpb.errors import ConfigError
from rnnpb.model._tuned import (
    Tuning,
    section_values,
    settle,
    tuning_of,
    user_names,
    with_values,
)
from rnnpb.model._tuned import with_tuning as _with_tuning
from rnnpb.model.io import learning_preset
from rnnpb.model.parametric_bias import PBUpdateConfig
from rnnpb.model.recognition import PRESET_DT, RecognitionConfig
from rnnpb.presets import Overrides, Preset, load_preset

_DEFAULT = section_values("paper", "online")
_USER = ("window", "iterations", "safety_guard")


@cache
def _default_tuning() -> Tuning:
    return _preset_tuning("paper", "online")


def _preset_tuning(preset: Preset | str, section: str) -> Tuning:
    preset = load_preset(preset) if isinstance(preset, str) else preset
    values = section_values(preset, section)
    return Tuning(preset.name, {k: v for k, v in values.items() if k not in _USER})


TUNED_MOVEMENT = 0.04
"""The RMS change of a seen value from one step to the next (view units) on which the surprise
gate's and the phase restarts' levels were tuned: the demonstrator's four patterns move 0.031 to
0.040 a step (median over their cycles), its new shapes up to 0.053. A movement that moves
further a step has its levels raised in proportion (:func:`rnnpb.model.online.level_scale`)."""


@dataclass(frozen=True)
class OnlineConfig:
    """How the PB is regressed on-line.

    Settings a user changes
    -----------------------
    window : int
        L, the steps regressed (paper: 30).
    iterations : int
        Iterations of the regression per step (paper: about 100).
    safety_guard : {"barrier", "projection", "off"}
        How the safety map (docs/safety.md) keeps the PB out of the learned unsafe region;
        it acts only where the mirror system has a map.

    Every other field is tuned: read from the learning preset's ``[online]`` section (its
    evidence beside it), shown read-only, changed by :meth:`with_tuning`. What they do:

    ``pb`` — the PB update's coefficients (eqs. 1–2). ``optimize_onset``,
    ``onset_learning_rate`` — the window's onset state regressed with the PB. ``restart_span``
    — before each regression, the last ``restart_span`` steps of the PB profile are also tried
    at each learned pattern's PB, and the regression starts from the profile that fits best.
    ``motor_input`` — the window's motor inputs regenerated (``closed_loop``) or as sent
    (``recorded``). The surprise gate (``surprise_gate`` 0 turns it off): before each
    regression, the RMS sensory error of the window's last ``gate_steps`` predictions scales
    the error term of eq. 1 by (error / surprise_gate) ** gate_power, clipped to
    [gate_floor, 1]. Phase restarts (``phase_restarts`` 0 turns them off): the network is also
    started ``phase_restarts + 1`` steps back from states on the learned cycles; where one
    predicts the last ``phase_restarts`` observations better than the window by the factor
    ``phase_restart_ratio``, and the window is off by more than ``phase_restart_level``
    there, the window starts over from that state. Both levels were tuned on the
    demonstrator, whose hands move about :data:`TUNED_MOVEMENT` a step: where the hands move
    further in the same steps (a person's own tempo, a large movement), each level grows in
    proportion, so that an error is judged against the movement it is made on. The guard:
    ``"barrier"`` adds ``barrier_weight * softplus(risk logit - logit(risk_level))`` per step
    of the window's
    newest ``barrier_span`` steps (0: all) to the error of eq. 1; ``"projection"`` moves each
    regressed PB down the risk gradient (at most ``projection_steps`` steps of
    ``projection_rate`` in rho) until its risk is below ``risk_level``.
    """

    window: int = _DEFAULT["window"]  # L
    iterations: int = _DEFAULT["iterations"]
    pb: PBUpdateConfig = field(init=False, repr=False)
    optimize_onset: bool = field(init=False, repr=False)
    onset_learning_rate: float = field(init=False, repr=False)
    restart_span: int = field(init=False, repr=False)
    motor_input: Literal["closed_loop", "recorded"] = field(init=False, repr=False)
    surprise_gate: float = field(init=False, repr=False)
    gate_power: float = field(init=False, repr=False)
    gate_floor: float = field(init=False, repr=False)
    gate_steps: int = field(init=False, repr=False)
    phase_restarts: int = field(init=False, repr=False)
    phase_restart_ratio: float = field(init=False, repr=False)
    phase_restart_level: float = field(init=False, repr=False)
    safety_guard: Literal["off", "barrier", "projection"] = _DEFAULT["safety_guard"]
    barrier_weight: float = field(init=False, repr=False)
    barrier_span: int = field(init=False, repr=False)
    risk_level: float = field(init=False, repr=False)
    projection_steps: int = field(init=False, repr=False)
    projection_rate: float = field(init=False, repr=False)
    _tuning: InitVar[Mapping[str, Any] | None] = None

    def __post_init__(self, _tuning: Mapping[str, Any] | None) -> None:
        settle(self, _tuning, _default_tuning(), PBUpdateConfig)
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

    @property
    def tuning(self) -> Tuning:
        """The tuned values and the preset they were read from."""
        return tuning_of(self)

    def with_tuning(self, **changes: Any) -> OnlineConfig:
        """This config with tuned values changed, for research: e.g.
        ``OnlineConfig().with_tuning(surprise_gate=0.0, pb={"k_nb": 0.1})``."""
        return _with_tuning(self, changes)

    def at_step(self, dt: float) -> OnlineConfig:
        """This regression for a model that plays at ``dt`` seconds a step. The presets count
        its effort, ``iterations``, per step of the paper's 0.4 s; at another step it is kept
        per second (25 iterations a 0.1 s step, at least 1): the PB relaxes toward what the
        window says at the same pace in seconds, not four times as fast — it would follow
        each new step's evidence and jump — and a second of interaction costs what it costs
        at 0.4 s. The window, the restarts and the gate count steps of a movement's cycle and
        stay: a person at their own tempo at 0.1 s makes as many steps a cycle as the paper's
        slow demonstrator at 0.4 s."""
        if not dt > 0:
            raise ConfigError(f"dt must be > 0, got {dt}")
        iterations = max(1, round(self.iterations * dt / PRESET_DT))
        if iterations == self.iterations:
            return self
        return replace(self, iterations=iterations, _tuning=tuning_of(self))

    def overridden(self, overrides: Overrides | None) -> OnlineConfig:
        """This regression with a ``--config`` file's ``[online]`` values over it, taken as
        given (after :meth:`at_step`: at the model's step), whichever preset it came from."""
        return self if overrides is None else with_values(self, overrides.values("online"))

    @classmethod
    def from_preset(cls, preset: Preset | str, section: str = "online") -> OnlineConfig:
        """The regression a preset's ``section`` describes (``[online]``, or the paper
        preset's ``[paper_online]``)."""
        values = section_values(preset, section)
        tuning = _preset_tuning(preset, section)
        return cls(**{k: values[k] for k in _USER}, _tuning=tuning)

    @classmethod
    def paper(cls, **changes: Any) -> OnlineConfig:
        """The paper's regression: L = 30, 100 iterations, l = 20, no onset optimisation, no
        restarts, gate or safety guard (the paper proposes the meta-level, section 4.1, but
        did not run it). ``changes``: settings a user changes."""
        return replace(_paper_online(), **changes)

    @classmethod
    def ungated(cls, **changes: Any) -> OnlineConfig:
        """The regression chosen for the fast preset's models: the default without the
        surprise gate, so the PB keeps fitting every step. ``changes``: settings."""
        return replace(_ungated(), **changes)

    @classmethod
    def preset(cls, name: str) -> OnlineConfig:
        """The preset called ``name``: one of :data:`ONLINE_PRESETS`."""
        if name not in ONLINE_PRESETS:
            raise ConfigError(
                f"unknown on-line regression {name!r}; choose one of {', '.join(ONLINE_PRESETS)}"
            )
        return {"default": cls, "paper": cls.paper, "ungated": cls.ungated}[name]()

    @classmethod
    def for_model(cls, model: Any, overrides: Overrides | None = None) -> OnlineChoice:
        """The regression that suits ``model``: see :func:`suggested_online_config`."""
        return suggested_online_config(model, overrides)

    def to_dict(self) -> dict[str, Any]:
        """Every value, settings and tuned, as one flat record (``pb`` a dict)."""
        return asdict(self)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> OnlineConfig:
        """A config from :meth:`to_dict`'s record."""
        data = dict(data)
        user = {k: data.pop(k) for k in user_names(cls) if k in data}
        return cls(**user, _tuning=data)


@cache
def _paper_online() -> OnlineConfig:
    return OnlineConfig.from_preset("paper", "paper_online")


@cache
def _ungated() -> OnlineConfig:
    return OnlineConfig.from_preset("fast")


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


def suggested_online_config(model: Any, overrides: Overrides | None = None) -> OnlineChoice:
    """The on-line regression that suits a model's learning preset.

    A model learned with the fast preset (Adam, noise on the inputs) takes the fast preset's
    regression, ``OnlineConfig.ungated()``; one learned by the paper's algorithm, or one that
    records no learning, the paper preset's, ``OnlineConfig()`` (docs/model.md, "On-line
    interaction"). The recognition settings come from the same preset, those for models
    without taught hands where the model kept none, with a person's durations and the
    regression's effort kept in seconds at the model's step (:meth:`RecognitionConfig.at_step`,
    :meth:`OnlineConfig.at_step`). The preset is the one the model records
    (:func:`rnnpb.model.io.learning_preset`; a file from before presets were recorded is
    read by its recorded optimizer). A ``--config`` file's tables (``overrides``) go over
    both as given, in the model's steps: ``[online]``, and ``[recognition]`` or
    ``[recognition_untaught]`` as the model kept its taught hands or not.

    Parameters
    ----------
    model : TrainedModel
        Anything with a ``meta`` dict (and ``taught_sensory``).
    overrides : Overrides, optional
    """
    meta = getattr(model, "meta", None)
    learned = learning_preset(meta if isinstance(meta, dict) else {})
    # A model that kept its hands as taught is recognised with them, one that did not (a file
    # of format 1 or 2) by the network's evidence alone, each with the settings chosen for it.
    taught = getattr(model, "taught_sensory", None) is not None
    name = learned[0] if learned is not None else "paper"
    # The durations a preset counts in the paper's steps are kept in seconds at the model's.
    dt = getattr(model, "dt", PRESET_DT)
    recognition = RecognitionConfig.for_preset(name, taught=taught).at_step(dt)
    if overrides is not None:
        section = "recognition" if taught else "recognition_untaught"
        recognition = with_values(recognition, overrides.values(section))
    if learned is None:
        reason = "the model does not record how it was learned"
    elif name == "fast":
        reason = "the model was learned with Adam, the fast preset"
    else:
        reason = "the model was learned with momentum descent, the paper's algorithm"
    if name == "fast":
        ungated = OnlineConfig.ungated().at_step(dt).overridden(overrides)
        return OnlineChoice("ungated", ungated, reason, recognition)
    return OnlineChoice(
        "default", OnlineConfig().at_step(dt).overridden(overrides), reason, recognition
    )
