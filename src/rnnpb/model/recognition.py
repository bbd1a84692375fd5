"""Know what you see: on-line recognition with a confidence, and a novelty detector that tells
a new movement from noise (the paper's section 4.1 asks for both).

Every step of the mirror system (:meth:`rnnpb.model.mirror.MirrorSystem.step`) also says

* ``recognised``: which learned pattern the user performs, or None;
* ``confidence``: how sure that answer is, in [0, 1] (for a pattern, its share of the
  evidence; for None, the share of "no learned pattern fits");
* ``novelty``: ``familiar`` (a learned pattern), ``novel`` (a structured, repeating movement no
  learned pattern fits), ``unstructured`` (movement without repeating structure), ``still``
  (the hands at rest), or ``""`` while there is not yet evidence (too few seen steps, every
  hand lost).

How it decides (docs/model.md, "Recognition and novelty"):

1. **Each learned pattern's own dynamics.** In the compiled step, after the regression, the
   window is run again from its regressed onset with each learned pattern's PB in place of
   the regressed profile (:func:`rnnpb.model.online.pattern_errors`): the RMS error ``d_k``
   of its last ``recognition_steps`` sensory predictions, averaged (as mean squares) over the
   last ``evidence_steps`` steps, says how well pattern ``k``'s dynamics predict what was just
   seen. This is stronger evidence than the distance of the
   regressed PB to the learned ones: two learned PBs can lie close together while their
   dynamics differ clearly, and a PB between them predicts nothing well.
2. **The hands as taught.** A model keeps each training sequence's hands
   (:attr:`rnnpb.model.TrainedModel.taught_sensory`). ``m_k`` says how unlike pattern ``k``'s
   taught shape the last ``template_steps`` observations are: the sine of the smallest angle
   between them and any stretch of the pattern's taught hands (every half step, at each of
   ``template_speeds``), each with its mean removed (:func:`taught_distances`). Where the user
   stands and how large the movement is do not count; which hands move, and how together, do:
   one arm of a two-arm pattern is as unlike it as a quarter turn. This is what tells apart
   two patterns whose dynamics the network learned alike.
3. **Confidence.** Each pattern's likelihood is
   ``exp(-d_k² / 2σ² - e_k² / 2τ² - m_k² / 2μ²)`` (σ = ``match_scale``, τ = ``pb_scale``,
   μ = ``template_scale``), where ``e_k`` is the distance of the PB, averaged over the last
   ``pb_steps`` steps, to pattern ``k``'s learned PB: over a few steps the regressed PB is
   steadier than in one. A pattern nobody learned has the likelihood of a fit at
   ``match_level``, ``pb_level`` and ``template_level``. With the taught hands at hand,
   ``d_k`` and ``e_k`` count up to their levels and no further: the network's evidence can
   speak for a pattern, and a pattern shown plainly while the network does not yet predict it
   well (not yet locked on, a user unlike the teacher) is that pattern, not a new movement.
   Each share of the sum is a pattern's confidence; the best pattern is recognised when its
   share is at least ``confidence_level``. A model without taught hands (a file of format 1
   or 2) goes by ``d_k`` and ``e_k`` alone, unclipped.
4. **Structure.** Where no pattern is recognised, the movement is ``novel`` if what is seen
   repeats itself at some period ``k`` in ``lags`` (smallest and largest, steps): the mean
   squared difference between the last cycle (its last ``max(k, structure_steps)`` steps) and
   the one before (the same steps ``k`` earlier), relative to twice the variance of the steps
   compared, is below ``structure_level`` for some ``k``
   (:func:`rnnpb.structure.cycle_differences`). Whole cycles against their own spread: the
   same shape performed at half or twice the speed gives the same value at its own period.
   A cycle repeats at its period; a random walk or jumps between random targets do not repeat
   at any lag. Else it is ``unstructured`` — once every period could be measured (a longer
   one might yet repeat) on this movement: what came before the last pause longer than
   ``hold_steps`` is not compared with it.
5. **Stillness.** The hands are ``still`` when no observed value's spread over the last
   ``still_steps`` observations reaches ``still_level``. Through a short pause
   (``hold_steps``) the last recognised pattern stays recognised: the robot keeps generating
   it, as in the paper's section 3.1. Such a pause is a rest inside the movement (people rest
   between the cycles of a gesture): its steps are left out of the window matched against the
   taught hands, and the taught hands' own rests (:func:`paused_steps`) out of theirs. A new
   movement (``novel``) goes on through a still run no longer than a quarter of its period
   (:func:`turning_steps`): that is where a slow movement turns, not a stop.
6. **Hysteresis.** A new answer replaces the current one only after it has been the step's
   evidence for ``switch_steps`` steps running — ``release_steps`` when a recognised pattern
   would give way to none: the evidence dips for a few steps as a pause begins or ends.

The settings depend on how the model was learned and on what it kept, and are read from the
learning preset (:mod:`rnnpb.presets`): ``RecognitionConfig()`` for models learned by the
paper's algorithm, :meth:`RecognitionConfig.fast` for ``TrainConfig.fast()`` models (their
evidence lies at other levels), and :meth:`RecognitionConfig.untaught` for models of either
kind that kept no taught hands; ``OnlineConfig.for_model`` picks the one that suits a model,
and :class:`rnnpb.model.MirrorSystem` uses it unless told otherwise.

:func:`recognise` is pure (state in, state and answer out) and NumPy only. The float32 step
and its float64 twin compute the same evidence and call the same function, so both give the
same answer for the same observations.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import InitVar, asdict, dataclass, field
from functools import cache
from typing import Any, NamedTuple

import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.model._tuned import Tuning, section_values, settle, tuning_of
from rnnpb.model._tuned import with_tuning as _with_tuning
from rnnpb.presets import Preset

NOVELTY_STATES: tuple[str, ...] = ("familiar", "novel", "unstructured", "still")
"""The words of the novelty state (besides ``""``, no evidence yet), as recordings carry them."""
PRESET_DT = 0.4
"""Seconds per step the presets' durations are counted in: the paper's step."""
DURATIONS = ("still_steps", "hold_steps")
"""The settings that count a duration of the person's, not a part of a movement's cycle: how
long hands must stay put to be still, and how long a rest inside a movement may last. They are
kept in seconds at another step (:meth:`RecognitionConfig.at_step`)."""


@dataclass(frozen=True)
class RecognitionConfig:
    """The detector's settings (the module doc says how each is used). Every one is tuned:
    read from the learning preset's ``[recognition]`` section (``[recognition_untaught]`` for
    a model without taught hands), where its evidence is, and changed only by
    :meth:`with_tuning`. ``RecognitionConfig()`` is the paper preset's, :meth:`fast` the fast
    preset's, :meth:`untaught` either's for models that kept no taught hands."""

    recognition_steps: int = field(
        init=False, repr=False
    )  # predictions each pattern's evidence is on
    evidence_steps: int = field(
        init=False, repr=False
    )  # steps each pattern's evidence is averaged over
    match_scale: float = field(
        init=False, repr=False
    )  # σ of the likelihoods, RMS error, normalized units
    match_level: float = field(
        init=False, repr=False
    )  # RMS error at which "none learned" is as likely
    pb_steps: int = field(init=False, repr=False)  # steps the PB is averaged over
    pb_scale: float = field(
        init=False, repr=False
    )  # σ of the PB's likelihoods (distance to a learned PB)
    pb_level: float = field(
        init=False, repr=False
    )  # PB distance at which "none learned" is as likely
    confidence_level: float = field(init=False, repr=False)
    structure_steps: int = field(init=False, repr=False)  # fewest steps a cycle is compared on
    lags: tuple[int, int] = field(init=False, repr=False)  # shortest and longest period, steps
    structure_level: float = field(init=False, repr=False)
    still_steps: int = field(init=False, repr=False)
    still_level: float = field(
        init=False, repr=False
    )  # largest RMS spread of one value, normalized units
    hold_steps: int = field(init=False, repr=False)
    switch_steps: int = field(init=False, repr=False)
    release_steps: int = field(init=False, repr=False)
    # The hands as taught (3 in the module doc): matched over template_steps, at these speeds.
    template_steps: int = field(init=False, repr=False)
    template_speeds: tuple[float, ...] = field(init=False, repr=False)
    template_scale: float = field(
        init=False, repr=False
    )  # σ of the taught-shape likelihoods (a sine)
    template_level: float = field(
        init=False, repr=False
    )  # taught-shape distance where none is as likely
    _tuning: InitVar[Mapping[str, Any] | None] = None

    def __post_init__(self, _tuning: Mapping[str, Any] | None) -> None:
        settle(self, _tuning, _preset_tuning("paper", "recognition"), None)
        if self.recognition_steps < 1:
            raise ConfigError(f"recognition_steps must be >= 1, got {self.recognition_steps}")
        if self.evidence_steps < 1:
            raise ConfigError(f"evidence_steps must be >= 1, got {self.evidence_steps}")
        if self.match_scale <= 0 or self.match_level <= 0:
            raise ConfigError("match_scale and match_level must be > 0")
        if self.pb_steps < 1 or self.pb_scale <= 0 or self.pb_level <= 0:
            raise ConfigError("pb_steps must be >= 1, pb_scale and pb_level > 0")
        if not 0 < self.confidence_level <= 1:
            raise ConfigError(f"confidence_level must be in (0, 1], got {self.confidence_level}")
        low, high = self.lags
        if not 1 <= low <= high:
            raise ConfigError(f"lags must be 1 <= smallest <= largest, got {self.lags}")
        if self.structure_steps < 2 or self.structure_level <= 0:
            raise ConfigError("structure_steps must be >= 2 and structure_level > 0")
        if self.still_steps < 2 or self.still_level < 0:
            raise ConfigError("still_steps must be >= 2 and still_level >= 0")
        if self.hold_steps < 0 or self.switch_steps < 1 or self.release_steps < 1:
            raise ConfigError("hold_steps must be >= 0, switch_steps and release_steps >= 1")
        if self.template_steps < 2 or not self.template_speeds:
            raise ConfigError("template_steps must be >= 2, with at least one template speed")
        if not all(0.25 <= speed <= 4 for speed in self.template_speeds):
            raise ConfigError(f"template_speeds must lie in [0.25, 4], got {self.template_speeds}")
        if self.template_scale <= 0 or self.template_level <= 0:
            raise ConfigError("template_scale and template_level must be > 0")

    @property
    def tuning(self) -> Tuning:
        """The tuned values and the preset they were read from."""
        return tuning_of(self)

    def with_tuning(self, **changes: Any) -> RecognitionConfig:
        """These settings with some changed, for research: e.g.
        ``RecognitionConfig().with_tuning(switch_steps=2)``."""
        return _with_tuning(self, changes)

    def at_step(self, dt: float) -> RecognitionConfig:
        """These settings for a model that plays at ``dt`` seconds a step: the presets count
        a person's durations (:data:`DURATIONS`: being still, resting inside a movement) in
        steps of the paper's 0.4 s; at another step they are kept in seconds. The rest are
        parts of a movement's cycle and stay in steps: a person moving at their own tempo at
        0.1 s a step makes as many steps a cycle as the paper's slow demonstrator at 0.4 s."""
        if not dt > 0:
            raise ConfigError(f"dt must be > 0, got {dt}")
        factor = PRESET_DT / dt
        if abs(factor - 1.0) < 1e-9:
            return self
        # at a longer step, no fewer than being still can be told by (2 steps)
        return self.with_tuning(
            **{name: max(2, round(getattr(self, name) * factor)) for name in DURATIONS}
        )

    @classmethod
    def from_preset(cls, preset: Preset | str, section: str = "recognition") -> RecognitionConfig:
        """The settings a preset's ``section`` holds (``[recognition]`` or
        ``[recognition_untaught]``)."""
        name = preset if isinstance(preset, str) else preset.name
        values = section_values(preset, section)
        return cls(_tuning=Tuning(name, values))

    @classmethod
    def for_preset(cls, name: str, taught: bool = True) -> RecognitionConfig:
        """The settings chosen for models learned with preset ``name``, with or without the
        hands as taught."""
        return _preset_config(name, "recognition" if taught else "recognition_untaught")

    @classmethod
    def fast(cls) -> RecognitionConfig:
        """The settings chosen for models learned with ``TrainConfig.fast()`` (regressed with
        ``OnlineConfig.ungated()``): their evidence lies at other levels."""
        return cls.for_preset("fast")

    @classmethod
    def untaught(cls, fast: bool = False) -> RecognitionConfig:
        """The settings chosen for a model that kept no hands as taught (a file of format 1
        or 2), which goes by the network's evidence alone; ``fast`` for the fast preset's."""
        return cls.for_preset("fast" if fast else "paper", taught=False)

    @property
    def history(self) -> int:
        """Observed steps the detector keeps."""
        longest = self.lags[1] + max(self.lags[1], self.structure_steps)
        return max(longest, self.still_steps, self.template_steps)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> RecognitionConfig:
        """Settings from :meth:`to_dict`'s record (values it lacks: the paper preset's)."""
        data = dict(data)
        for key in ("lags", "template_speeds"):
            if key in data:
                data[key] = tuple(data[key])
        return cls(_tuning=data)


@cache
def _preset_tuning(preset: str, section: str) -> Tuning:
    return Tuning(preset, section_values(preset, section))


@cache
def _preset_config(preset: str, section: str) -> RecognitionConfig:
    return RecognitionConfig(_tuning=_preset_tuning(preset, section))


class Recognition(NamedTuple):
    """What one step recognises.

    Attributes
    ----------
    recognised : str or None
    confidence : float in [0, 1]
    novelty : str
        One of :data:`NOVELTY_STATES` or ``""``.
    confidences : dict of str to float
        Each learned pattern's share of the evidence (all 0 while there is none).
    distances : dict of str to float
        Each learned pattern's best-fit RMS distance (NaN while there is none).
    structure : float
        How unlike the cycle before it the last cycle is, at its best period (NaN when not
        measured, as while a learned pattern is recognised;
        :func:`rnnpb.structure.cycle_differences`): low repeats.
    repeating : int
        On a step the structure test calls ``novel``: how many of the latest steps it found
        repeating — the last cycle and the one before it (``period + max(period,
        structure_steps)``), the evidence the call rests on. 0 on every other step.
    """

    recognised: str | None
    confidence: float
    novelty: str
    confidences: dict[str, float]
    distances: dict[str, float]
    structure: float
    repeating: int = 0


class RecognitionState(NamedTuple):
    """What the detector carries from step to step (host arrays; never changed in place)."""

    observed: np.ndarray  # (H, S) the last H observations, NaN where not seen; oldest first
    pb: np.ndarray  # (pb_steps, P) the last PBs, NaN before the first; oldest first
    errors: np.ndarray  # (evidence_steps, K) the last pattern errors, NaN where none
    recognised: str | None
    confidence: float
    still_run: int  # steps the hands have been still
    candidate: str | None  # the answer the evidence gives, waiting for switch_steps
    candidate_run: int
    novelty: str
    moving_run: int = 0  # moving steps since the hands were last still longer than hold_steps
    still: np.ndarray | None = None  # (H,) bool: the observation was a step of a pause
    period: int = 0  # steps a cycle of the novel movement seen last takes (0: none)


def initial_recognition_state(
    sensory_size: int, pb_size: int, config: RecognitionConfig
) -> RecognitionState:
    """Nothing seen yet."""
    return RecognitionState(
        np.full((config.history, sensory_size), np.nan),
        np.full((config.pb_steps, pb_size), np.nan),
        np.full((config.evidence_steps, 0), np.nan),  # K is known at the first step
        None,
        0.0,
        0,
        None,
        0,
        "",
    )


TEMPLATE_START_STEP = 0.5
"""Taught steps between two stretches' starts: with a whole step, a movement seen half a step
out of phase with every stretch (a twelfth of a cycle) looked 0.2 unlike its own shape."""


class TaughtStretches(NamedTuple):
    """Every ``template_steps``-long stretch of each learned pattern's taught hands, each
    resampled at every template speed, its mean removed and scaled to unit length
    (:func:`taught_stretches`).

    Attributes
    ----------
    directions : array, shape (K, N, W·S)
        Pattern k's stretches, flattened; rows past its own count repeat its first stretch.
    """

    directions: np.ndarray


def paused_steps(values: np.ndarray, config: RecognitionConfig) -> np.ndarray:
    """(T,) bool: the steps of ``values`` (T, S) the detector calls still — the largest
    spread of one coordinate over the ``still_steps`` observations up to the step is below
    ``still_level`` — as :func:`recognise` decides it step by step."""
    values = np.asarray(values, dtype=np.float64)
    paused = np.zeros(len(values), bool)
    n = config.still_steps
    if len(values) < n:
        return paused
    windows = np.lib.stride_tricks.sliding_window_view(values, n, axis=0)  # (T-n+1, S, n)
    spread = np.sqrt(np.var(windows, axis=-1).max(axis=-1))
    paused[n - 1 :] = spread < config.still_level
    return paused


def taught_stretches(
    taught: dict[str, list[np.ndarray]], names: tuple[str, ...], config: RecognitionConfig
) -> TaughtStretches | None:
    """The taught stretches the detector matches what it sees against, or None when a learned
    pattern has no taught hands (a model saved before they were kept: the detector then goes
    by the network's evidence alone).

    Parameters
    ----------
    taught : dict of str to list of array, shape (T_i, S)
        Each pattern's taught sequences' hands, normalized (NaN after a sequence's end).
    names : tuple of str, length K
        The learned patterns, in the detector's order.
    """
    steps = config.template_steps
    per_pattern = []
    for name in names:
        stretches = []
        for sequence in taught.get(name, []):
            values = np.asarray(sequence, dtype=np.float64)
            values = values[~np.isnan(values).any(axis=1)]  # the padding after its end
            values = values[~paused_steps(values, config)]  # rests: left out as on-line
            length = len(values)
            for speed in config.template_speeds:
                span = speed * (steps - 1)  # the stretch covers this many taught steps
                if length - 1 < span:
                    continue
                starts = np.arange(0.0, length - 1 - span + 1e-9, TEMPLATE_START_STEP)
                times = starts[:, None] + speed * np.arange(steps)[None]  # (n, W)
                low = np.minimum(np.floor(times).astype(int), length - 2)
                weight = (times - low)[..., None]
                stretches.append(values[low] * (1 - weight) + values[low + 1] * weight)
        if not stretches:
            return None
        pattern = np.concatenate(stretches)
        pattern = (pattern - pattern.mean(axis=1, keepdims=True)).reshape(len(pattern), -1)
        size = np.linalg.norm(pattern, axis=1)
        if not (size > 0).any():
            return None  # the pattern was taught without moving: it has no shape
        per_pattern.append(pattern[size > 0] / size[size > 0, None])
    if not per_pattern:
        return None
    count = max(len(p) for p in per_pattern)
    return TaughtStretches(
        np.stack(
            [np.concatenate([p, np.repeat(p[:1], count - len(p), axis=0)]) for p in per_pattern]
        )
    )


def taught_distances(window: np.ndarray, taught: TaughtStretches) -> np.ndarray:
    """How unlike each learned pattern's taught shape the window ``(W, S)`` is, shape (K,), in
    [0, 1]: the sine of the smallest angle between the window and the pattern's taught
    stretches, each with its mean removed (0: the same shape at some size; 1: nothing in
    common). Its size does not count, so a user who moves smaller or larger than the teacher
    matches as well; a movement that is a part of a pattern (one arm of two) does not."""
    seen = (window - window.mean(axis=0, keepdims=True)).ravel()
    length = float(np.linalg.norm(seen))
    if not length > 0:
        return np.ones(len(taught.directions))  # no movement has no shape
    best = np.clip((taught.directions @ (seen / length)).max(axis=1), 0.0, 1.0)
    return np.sqrt(1.0 - best**2)


def _structure(history: np.ndarray, config: RecognitionConfig) -> tuple[float, bool, int]:
    """How unlike the cycle before it the last cycle of the recent observations is, at the
    period in ``config.lags`` where it is least (:func:`rnnpb.structure.cycle_differences`):
    near 0 for a repeating movement, about 1 or more for one that does not repeat (NaN while
    no period can be measured yet); whether every period was measured; and the shortest
    period at which it repeats (where none does: the least unlike; 0 while none is measured).

    Each period ``k`` compares the last ``max(k, structure_steps)`` steps with the same steps
    ``k`` earlier, so it needs that many steps and ``k`` more without a gap (NaN); the
    periods are tried from the shortest up, as far as the history reaches."""
    from rnnpb.structure import cycle_differences

    low, high = config.lags
    lags = np.arange(low, high + 1)
    spans = lags + np.maximum(lags, config.structure_steps)
    gap: np.ndarray = np.asarray(np.isnan(history).any(axis=1), dtype=bool)
    gaps = np.flatnonzero(gap)
    clean = len(history) - 1 - int(gaps[-1]) if len(gaps) else len(history)
    count = int(np.sum(spans <= clean))  # spans grow with the lag
    if count == 0:
        return float("nan"), False, 0
    recent = history[len(history) - clean :]
    differences = cycle_differences(recent, lags[:count], config.structure_steps)
    if np.isnan(differences).all():
        return float("nan"), False, 0
    repeats = np.flatnonzero(differences < config.structure_level)
    shortest = int(repeats[0]) if len(repeats) else int(np.nanargmin(differences))
    return float(np.nanmin(differences)), count == len(lags), int(lags[shortest])


def _this_movement(filled: np.ndarray, paused: np.ndarray, config: RecognitionConfig) -> np.ndarray:
    """The observations with those before the last pause longer than ``hold_steps`` marked
    unseen (NaN): what came before a stop is another movement, and does not say whether this
    one repeats (until this one has lasted long enough to tell, it is undecided)."""
    edges = np.diff(np.concatenate([[0], paused.astype(int), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    long = ends[ends - starts > config.hold_steps]
    if not len(long):
        return filled
    out = filled.copy()
    out[: long[-1]] = np.nan
    return out


def turning_steps(period: int) -> int:
    """Still steps that are a turning point of a movement of ``period`` steps, not a stop: a
    quarter of its cycle (a hand slows into a turn and out of it within the half cycle between
    two swings); 0 for none."""
    return period // 4


def recognise(
    state: RecognitionState,
    u: np.ndarray,
    seen: np.ndarray,
    pattern_errors: np.ndarray,
    pb: np.ndarray,
    learned_pb: np.ndarray,
    names: tuple[str, ...],
    config: RecognitionConfig,
    taught: TaughtStretches | None = None,
) -> tuple[RecognitionState, Recognition]:
    """One step of recognition and novelty detection.

    Parameters
    ----------
    state : RecognitionState
    u : array, shape (S,)
        This step's observed hands, normalized (ignored where ``seen`` is False).
    seen : array of bool, shape (S,)
    pattern_errors : array, shape (K,)
        The step's :func:`rnnpb.model.online.pattern_errors` (mean squared; NaN when the step
        was held).
    pb : array, shape (P,)
        The step's regressed PB.
    learned_pb : array, shape (K, P)
        The learned patterns' PBs.
    names : tuple of str, length K
        The learned patterns, in the order of ``pattern_errors``.
    taught : TaughtStretches, optional
        The learned patterns' taught hands (:func:`taught_stretches`), in the same order;
        without them the detector goes by the network's evidence alone.

    Returns
    -------
    state : RecognitionState
    recognition : Recognition
    """
    observation = np.where(seen, u, np.nan)
    observed = np.concatenate([state.observed[1:], observation[None]])
    pbs = np.concatenate([state.pb[1:], np.asarray(pb, dtype=np.float64)[None]])
    errors = np.asarray(pattern_errors, dtype=np.float64)
    history = state.errors
    if history.shape[1] != len(errors):
        history = np.full((config.evidence_steps, len(errors)), np.nan)
    row = errors if np.all(np.isfinite(errors)) else np.full(len(errors), np.nan)
    history = np.concatenate([history[1:], row[None]])
    state = state._replace(pb=pbs, errors=history)
    none = {name: 0.0 for name in names}
    no_distance = {name: float("nan") for name in names}
    if not seen.any():
        # Nothing seen this step (every hand lost): no evidence, no answer.
        empty = initial_recognition_state(len(u), len(pbs[0]), config)
        empty = empty._replace(observed=observed, pb=pbs)
        return empty, Recognition(None, 0.0, "", none, no_distance, float("nan"))
    # Which observations were steps of a pause, this one not yet known (False).
    paused = np.zeros(len(observed), bool) if state.still is None else state.still
    paused = np.concatenate([paused[1:], [False]])
    state = state._replace(still=paused)
    # Fill unseen values from the last seen ones, so a hand lost for a step does not end the
    # evidence; the steps before the first seen one stay NaN.
    filled = _forward_fill(observed)
    if np.isnan(filled[-config.still_steps :]).any() or not np.all(np.isfinite(errors)):
        waiting = state._replace(observed=observed, novelty="", moving_run=state.moving_run + 1)
        return waiting, Recognition(None, 0.0, "", none, no_distance, float("nan"))

    recent = filled[-config.still_steps :]
    # The largest spread of any one coordinate: one hand moving is movement, though the other
    # rests (averaged over all four values, a one-arm swing looked still at its turning points).
    spread = float(np.sqrt(np.var(recent, axis=0).max()))
    if spread < config.still_level:
        still_run = state.still_run + 1
        if state.novelty == "novel" and still_run <= turning_steps(state.period):
            # The hands rest at a turning point of the new movement (a slow one rests longer
            # than the still window): it is still that movement.
            paused = paused.copy()
            paused[-1] = True
            turning = state._replace(
                observed=observed, still_run=still_run, still=paused, novelty="novel"
            )
            return turning, Recognition(
                None, state.confidence, "novel", none, no_distance, float("nan")
            )
        keep = state.recognised if still_run <= config.hold_steps else None
        confidence = state.confidence if keep is not None else 1.0
        # A pause of at most hold_steps is a rest inside the movement (a person rests between
        # the cycles of a gesture): the moving steps before it still count toward the taught
        # shapes' window, which leaves the paused steps out. A longer pause ends the movement.
        moving = state.moving_run if still_run <= config.hold_steps else 0
        paused = paused.copy()
        paused[-1] = True
        new = RecognitionState(
            observed, pbs, history, keep, confidence, still_run, keep, 0, "still", moving, paused
        )
        return new, Recognition(keep, confidence, "still", none, no_distance, float("nan"))

    # The evidence of the last evidence_steps steps (the steps with evidence), averaged: one
    # step's generated stretch can favour the wrong one of two close patterns by chance.
    d = np.sqrt(np.maximum(history[~np.isnan(history).any(axis=1)].mean(axis=0), 0.0))
    recent_pb = pbs[~np.isnan(pbs).any(axis=1)]
    e = np.linalg.norm(np.asarray(learned_pb) - recent_pb.mean(axis=0)[None], axis=1)
    # The taught shapes are matched on the last template_steps moving observations: the steps
    # of a short pause are left out (the hands at rest, then moving on, is a shape no pattern
    # was taught with), and after a longer pause the window waits for movement alone. Until
    # then the last answer stands (undecided at the start; after a pause, the pattern it held).
    moving_run = state.moving_run + 1
    window = filled[~paused][-config.template_steps :]
    short = len(window) < config.template_steps
    if taught is not None and (
        moving_run < config.template_steps or short or np.isnan(window).any()
    ):
        novelty = "familiar" if state.recognised is not None else ""
        waiting = state._replace(observed=observed, still_run=0, moving_run=moving_run)
        waiting = waiting._replace(novelty=novelty)
        distances = {name: float(x) for name, x in zip(names, d, strict=True)}
        return waiting, Recognition(
            state.recognised,
            state.confidence if state.recognised else 0.0,
            novelty,
            none,
            distances,
            float("nan"),
        )
    m = None if taught is None else taught_distances(window, taught)
    if m is not None:
        # With the taught shapes to go by, the network's and the PB's evidence speak for a
        # pattern up to their levels, and no further against it: a pattern shown plainly
        # while the network does not yet predict it well (not locked on, a user unlike the
        # teacher) is that pattern, not a new movement.
        d_for, e_for = np.minimum(d, config.match_level), np.minimum(e, config.pb_level)
    else:
        d_for, e_for = d, e
    # Log-likelihoods, shifted by their largest so that the exponentials cannot underflow.
    log_l = -0.5 * ((d_for / config.match_scale) ** 2 + (e_for / config.pb_scale) ** 2)
    log_unknown = -0.5 * (
        (config.match_level / config.match_scale) ** 2 + (config.pb_level / config.pb_scale) ** 2
    )
    if m is not None:
        log_l = log_l - 0.5 * (m / config.template_scale) ** 2
        log_unknown -= 0.5 * (config.template_level / config.template_scale) ** 2
    top = max(log_l.max(), log_unknown)
    likelihood, unknown = np.exp(log_l - top), float(np.exp(log_unknown - top))
    total = likelihood.sum() + unknown
    shares = likelihood / total
    best = int(np.argmax(shares))
    # The structure test (a few dozen small array operations) runs only where its answer is
    # used: no pattern recognised, or a new movement's period to keep.
    measured: list[tuple[float, bool, int]] = []

    def structure_test() -> tuple[float, bool, int]:
        if not measured:
            measured.append(_structure(_this_movement(filled, paused, config), config))
        return measured[0]

    if shares[best] >= config.confidence_level:
        answer, confidence, novelty = names[best], float(shares[best]), "familiar"
    else:
        answer, confidence = None, float(unknown / total)
        structure, every_lag, _ = structure_test()
        novelty = "novel" if structure < config.structure_level else "unstructured"
        if np.isnan(structure) or (novelty == "unstructured" and not every_lag):
            novelty = ""  # a longer lag may yet show the movement repeating
    # Hysteresis: a new answer (another pattern, or none) waits for switch_steps steps running;
    # until then the last answer stands.
    candidate = answer
    candidate_run = state.candidate_run + 1 if candidate == state.candidate else 1
    # Settled: there was an answer (a pattern held through a pause counts).
    settled = state.novelty in ("familiar", "novel", "unstructured") or state.recognised is not None
    needed = (
        config.release_steps
        if state.recognised is not None and answer is None
        else config.switch_steps
    )
    if settled and answer != state.recognised and candidate_run < needed:
        answer = state.recognised
        if answer is not None:
            confidence, novelty = float(shares[names.index(answer)]), "familiar"
        else:
            confidence, novelty = float(unknown / total), state.novelty
    period = structure_test()[2] if novelty == "novel" else 0
    repeats = novelty == "novel" and measured[0][0] < config.structure_level
    new = RecognitionState(
        observed,
        pbs,
        history,
        answer,
        confidence,
        0,
        candidate,
        candidate_run,
        novelty,
        moving_run,
        paused,
        period,
    )
    return new, Recognition(
        answer,
        confidence,
        novelty,
        {name: float(c) for name, c in zip(names, shares, strict=True)},
        {name: float(x) for name, x in zip(names, d, strict=True)},
        measured[0][0] if measured else float("nan"),
        period + max(period, config.structure_steps) if repeats else 0,
    )


def _forward_fill(observed: np.ndarray) -> np.ndarray:
    """NaN entries take the column's last finite value before them (NaN if none)."""
    rows = np.where(np.isnan(observed), 0, np.arange(len(observed))[:, None])
    last = np.maximum.accumulate(rows, axis=0)
    return observed[last, np.arange(observed.shape[1])[None]]


def recognition_timeline(answers: list[tuple[str | None, str]]) -> list[dict[str, Any]]:
    """Steps ``(recognised, novelty)`` as runs of the same answer:
    ``[{"first": 0, "last": 11, "recognised": "1" or None, "novelty": "familiar"}, …]``."""
    runs: list[dict[str, Any]] = []
    for step, (recognised, novelty) in enumerate(answers):
        if runs and runs[-1]["recognised"] == recognised and runs[-1]["novelty"] == novelty:
            runs[-1]["last"] = step
        else:
            runs.append({"first": step, "last": step, "recognised": recognised, "novelty": novelty})
    return runs


def describe_answer(recognised: str | None, confidence: float, novelty: str) -> str:
    """One step's answer as a person reads it: ``pattern 2 (93 %)``, ``new movement``,
    ``not sure`` …"""
    if recognised is not None and novelty in ("familiar", "still"):
        return f"pattern {recognised} ({100 * confidence:.0f} %)" + (
            ", hands still" if novelty == "still" else ""
        )
    return {
        "novel": "new movement",
        "unstructured": "no pattern (unstructured)",
        "still": "hands still",
        "": "not sure yet",
    }.get(novelty, "not sure")
