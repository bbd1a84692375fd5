"""The mirror system on the host: :class:`MirrorSystem` keeps the on-line state between steps
and speaks raw units (hands in [0, 1], NaN where not seen; joint angles in radians).

Each :meth:`MirrorSystem.step` is one call of the compiled step,
:func:`rnnpb.model.online.step_sessions`, in float32; its outputs come back as one row. The
reference :class:`ReferenceMirrorSystem` is the same step in float64, its drop-in twin: same
constructor, same :class:`StepResult`; :data:`MIRROR_SYSTEMS` names both.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import cast

import numpy as np
from numpy.typing import ArrayLike

from rnnpb.errors import ConfigError
from rnnpb.model.io import TrainedModel
from rnnpb.model.meta import MetaLevel, MetaParams, regime_of
from rnnpb.model.native import NativeRegression, native_regression
from rnnpb.model.network import logit_numpy
from rnnpb.model.online import (
    OnlineState,
    StepOutputs,
    initial_state,
    meta_arrays,
    network_arrays,
    output_layout,
    phase_candidates,
    restart_candidates,
    settings_for,
    step_sessions,
)
from rnnpb.model.online_config import OnlineConfig, suggested_online_config
from rnnpb.model.recognition import (
    RecognitionConfig,
    RecognitionState,
    initial_recognition_state,
    recognise,
    taught_distances,
    taught_stretches,
)


@dataclass(frozen=True)
class StepResult:
    """What the mirror system returns each step (raw units).

    Attributes
    ----------
    motor : array, shape (8,)
        The motor command for the current step, radians, within the joint limits.
    predicted_hands : array, shape (4,)
        The predicted hands for the next step, ``lhy lhz rhy rhz`` in [0, 1].
    pb : array, shape (4,)
        The current parametric bias.
    prediction_error : float
        Mean squared error between this step's observed hands and what the network predicted
        for them one step before (NaN on the first step or when no hand was seen).
    window_error : float
        Mean squared sensory error over the regression window after the regression.
    seen : array of bool, shape (4,)
        Which sensory values were observed (False where the input was NaN).
    held : bool
        The regression failed numerically this step and the last good state was kept.
    context : array, shape (C,)
        The context units after the current step (for phase-space analysis).
    recognised : str or None
        The learned pattern the user performs, or None (:mod:`rnnpb.model.recognition`).
    confidence : float
        How sure ``recognised`` is, in [0, 1] (for None: that no learned pattern fits).
    novelty : str
        ``familiar``, ``novel``, ``unstructured``, ``still``, or ``""`` (no evidence yet).
    repeating : int
        On a step called ``novel`` by the structure test: how many of the latest steps it
        found repeating (:class:`rnnpb.model.recognition.Recognition`); else 0.
    pattern_confidence : dict of str to float
        Each learned pattern's share of the evidence, in [0, 1].
    pattern_errors : array, shape (K,)
        The evidence: for each learned pattern (in the model's order), the window's mean
        squared sensory error over its last predictions with that pattern's PB
        (:func:`rnnpb.model.online.pattern_errors`; NaN when the step was held).
    regime : str
        What drives the motion (:data:`rnnpb.model.meta.REGIMES`): ``following`` the seen
        movement, or PB-driven: ``lost``, ``still``, ``novel``, ``unstructured``.
    inhibited : str
        Why the generated command was not sent (the meta-level recognised the PB as unsafe
        while following; ``motor`` is then the command before), ``""`` when it was sent.
    generated : array, shape (8,), or None
        The command the network generated, radians, when it was inhibited.
    """

    motor: np.ndarray
    predicted_hands: np.ndarray
    pb: np.ndarray
    prediction_error: float
    window_error: float
    seen: np.ndarray
    held: bool = False
    context: np.ndarray | None = None
    recognised: str | None = None
    confidence: float = 0.0
    novelty: str = ""
    pattern_confidence: dict[str, float] = field(default_factory=dict)
    pattern_errors: np.ndarray | None = None
    repeating: int = 0
    regime: str = ""
    inhibited: str = ""
    generated: np.ndarray | None = None


def normalized_hands(values: object, sensory_size: int) -> tuple[np.ndarray, np.ndarray]:
    """Check a step's observed hands; return them normalized (clipped to [0, 1], 0 where not
    seen), shape (S,), and which were seen (finite), shape (S,)."""
    try:
        u = np.asarray(values, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError, OverflowError):
        # OverflowError: a Python integer beyond float64's range (10**309).
        raise ConfigError(
            f"observed hands must be {sensory_size} numbers (lhy lhz rhy rhz), got {values!r:.80}"
        ) from None
    if u.shape != (sensory_size,):
        # np.asarray took ``values`` above: it is array-like.
        raise ConfigError(
            f"observed hands must have {sensory_size} values "
            f"(lhy lhz rhy rhz), got {np.shape(cast(ArrayLike, values))}"
        )
    seen = np.isfinite(u)
    return np.where(seen, np.clip(u, 0.0, 1.0), 0.0), seen


def one_step_prediction_error(
    predicted: np.ndarray | None, u: np.ndarray, seen: np.ndarray
) -> float:
    """Mean squared error of the previous step's prediction of the seen hands (NaN if there
    was none or nothing was seen)."""
    if predicted is None or not seen.any():
        return math.nan
    return float(np.mean((predicted[seen] - u[seen]) ** 2))


_LARGEST = float(np.finfo(np.float64).max)


def motor_command(model: TrainedModel, motor: np.ndarray) -> np.ndarray:
    """A normalized motor output (M,) as joint angles (M,), radians, within the model's motor
    bounds and always finite.

    The bounds are the model's normalization of the joints; the model never sees the robot,
    so the joint limits reach it through them (loading a model checks them against the robot's
    limits). A non-finite output (which a held step never hands back, but a caller's model
    might) goes to the middle of the range; the command is formed as a weighted mean of the
    two bounds, which cannot overflow, and clipped to them.
    """
    s = model.network.sensory_size
    lower = np.asarray(model.lower, dtype=np.float64)[s:]
    upper = np.asarray(model.upper, dtype=np.float64)[s:]
    if not (np.isfinite(lower).all() and np.isfinite(upper).all()):
        # Only a model built by hand gets here: a model file's bounds are finite.
        lower = np.clip(np.where(np.isnan(lower), 0.0, lower), -_LARGEST, _LARGEST)
        upper = np.clip(np.where(np.isnan(upper), 0.0, upper), -_LARGEST, _LARGEST)
    upper = np.maximum(upper, lower)
    m = np.asarray(motor, dtype=np.float64)
    m = np.clip(np.where(np.isfinite(m), m, 0.5), 0.0, 1.0)
    return np.clip(lower * (1.0 - m) + upper * m, lower, upper)


class MirrorSystem:
    """On-line recognition and generation with a trained RNNPB (weights frozen).

    Each step also says what it sees (``recognised``, ``confidence``, ``novelty``:
    :mod:`rnnpb.model.recognition`, with the settings ``recognition``).

    >>> mirror = MirrorSystem(model)                       # doctest: +SKIP
    >>> result = mirror.step([0.4, 0.6, 0.6, 0.6])         # doctest: +SKIP
    >>> result.motor, result.pb, result.predicted_hands    # doctest: +SKIP
    """

    dtype: type = np.float32
    """The precision the step computes in: float32; float64 for :class:`ReferenceMirrorSystem`."""

    def __init__(
        self,
        model: TrainedModel,
        config: OnlineConfig | None = None,
        meta: MetaParams | None = None,
        recognition: RecognitionConfig | None = None,
        steering: str = "always",
        inhibition: bool = False,
        native: bool = True,
    ) -> None:
        """``meta``: the risk network of a safety map (``rnnpb.safety.SafetyMap.meta``); the
        regression uses it as ``config.safety_guard`` says. Without it the guard is off.
        ``recognition``: the settings of what each step says it sees (when None, the ones
        chosen for models learned as ``model`` was: ``OnlineConfig.for_model(model)``).
        ``steering`` and ``inhibition``: where the guard acts and whether a recognised
        unsafe PB's command is held while following (:class:`rnnpb.model.meta.MetaLevel`;
        only with ``meta``). The defaults keep the guard at every step and never inhibit;
        ``rnnpb.safety.online_safety`` gives the meta-level's (``"pb_driven"``, True).
        ``native``: the regression's loop in native code where it can run
        (:mod:`rnnpb.model.native`, float32 only); False keeps it in the compiled step, the
        loop the native one is held to."""
        self.model = model
        self.config = config or OnlineConfig()
        self.recognition = recognition or suggested_online_config(model).recognition
        self.patterns = tuple(model.pattern_pb)
        self._learned_pb = np.array([model.pattern_pb[name] for name in self.patterns])
        self._taught = taught_stretches(model.taught_hands or {}, self.patterns, self.recognition)
        net, dtype = model.network, self.dtype
        self._layout = output_layout(
            net.sensory_size, net.motor_size, net.pb_size, net.context_size, len(self.patterns)
        )
        self._recognition = initial_recognition_state(
            net.sensory_size, net.pb_size, self.recognition
        )
        self._net = network_arrays(model.params, net.sensory_size, net.motor_size, dtype)
        self._settings = settings_for(self.config, dtype, self.recognition.recognition_steps)
        self._state = initial_state(model, self.config, dtype=dtype)
        # The last prediction of the hands: the next step's prediction error is measured
        # against it.
        self._predicted: np.ndarray | None = None
        none = np.zeros((0, net.pb_size), dtype)
        self._candidates = none
        if self.config.restart_span > 0:
            self._candidates = restart_candidates(model).astype(dtype)
        self._phase_candidates = np.zeros((0, net.pb_size + net.motor_size + net.context_size))
        if self.config.phase_restarts > 0:
            self._phase_candidates = phase_candidates(model)
        self._phase_candidates = self._phase_candidates.astype(dtype)
        self._pattern_rho = restart_candidates(model).astype(dtype)
        self._meta = meta_arrays(meta, net.pb_size, dtype)
        self._guarded = meta is not None
        self._native: NativeRegression | None = None
        if native and dtype == np.float32:
            self._native = native_regression(model.params, net, self.config, meta)
        self.meta_level = (
            None if meta is None else MetaLevel(meta, self.config.risk_level, steering, inhibition)
        )
        self.steps = 0

    def learned_shape(self, values: np.ndarray) -> str | None:
        """The learned pattern whose taught hands one cycle of a movement, ``values`` (T, S),
        has the shape of — the cycle resampled to the detector's ``template_steps`` and matched
        as the detector matches (:func:`rnnpb.model.recognition.taught_distances`), within
        ``template_level`` — or None (also for a model without taught hands)."""
        values = np.asarray(values, dtype=np.float64)
        if self._taught is None or len(values) < 2 or not np.isfinite(values).all():
            return None
        points = self.recognition.template_steps
        at = np.linspace(0, len(values) - 1, points)
        window = np.stack(
            [np.interp(at, np.arange(len(values)), values[:, j]) for j in range(values.shape[1])],
            axis=1,
        )
        distances = taught_distances(window, self._taught)
        best = int(np.argmin(distances))
        return self.patterns[best] if distances[best] < self.recognition.template_level else None

    def reset(self, initial_pb: np.ndarray | None = None) -> None:
        """Forget the window: the next step starts a new interaction."""
        self._state = initial_state(self.model, self.config, initial_pb, self.dtype)
        self._predicted = None
        self._recognition = initial_recognition_state(
            self.model.network.sensory_size, self.model.network.pb_size, self.recognition
        )
        if self.meta_level is not None:
            self.meta_level.reset()
        self.steps = 0

    def continue_from(self, other: MirrorSystem) -> bool:
        """Take over ``other``'s interaction (a new version of the model swapped in while the
        robot runs): its window of what was seen and sent, its PB and onset, and its
        recognition when the patterns are the same. The next step then regresses the new
        network over the same past, so the robot's command goes on from where it was instead
        of starting from an empty window (a jump of up to 60 degrees in one step). ``False``,
        and a fresh start, when the two differ in window or network shape."""
        mine, theirs = self._state, other._state
        same_shape = (
            all(np.shape(a) == np.shape(b) for a, b in zip(mine, theirs, strict=True))
            and self.model.network == other.model.network
        )
        if not same_shape:
            self.reset()
            return False
        # A copy: each steps on from here with its own state.
        self._state = OnlineState(
            *(np.array(part, dtype=a.dtype) for part, a in zip(theirs, mine, strict=True))
        )
        self._predicted = None if other._predicted is None else other._predicted.copy()
        fresh = initial_recognition_state(
            self.model.network.sensory_size, self.model.network.pb_size, self.recognition
        )
        seen = other._recognition  # host arrays, never changed in place: shared safely
        if self.recognition != other.recognition:
            self._recognition = fresh
        elif self.patterns == other.patterns:
            self._recognition = seen
        else:  # the movement seen so far stays; what was said of the old patterns goes
            self._recognition = fresh._replace(
                observed=seen.observed,
                pb=seen.pb,
                still_run=seen.still_run,
                moving_run=seen.moving_run,
                still=seen.still,
            )
        self.steps = other.steps
        return True

    @property
    def pb(self) -> np.ndarray:
        """The current PB, shape (P,)."""
        n = int(self._state.n[0])
        return 1.0 / (1.0 + np.exp(-self._state.rho[0, max(n - 1, 0)].astype(np.float64)))

    @property
    def pb_profile(self) -> np.ndarray:
        """The PB over the filled part of the window, shape (n, P)."""
        n = int(self._state.n[0])
        return 1.0 / (1.0 + np.exp(-self._state.rho[0, :n].astype(np.float64)))

    def _candidates_with(self, prior_pb: np.ndarray | None) -> np.ndarray:
        """The restarts' PBs, with ``prior_pb`` (checked) as one more."""
        candidates = self._candidates
        if prior_pb is not None and len(candidates):
            prior = np.clip(np.asarray(prior_pb, dtype=np.float64).reshape(-1), 0.0, 1.0)
            if prior.shape != (self.model.network.pb_size,) or not np.isfinite(prior).all():
                raise ConfigError(
                    f"prior PB must be {self.model.network.pb_size} finite values, got "
                    f"{np.shape(prior_pb)}"
                )
            candidates = np.concatenate([candidates, logit_numpy(prior)[None].astype(self.dtype)])
        return candidates

    def step(self, observed_hands: np.ndarray, prior_pb: np.ndarray | None = None) -> StepResult:
        """Observe the user's hands for this step; regress the PB; return the motor command.

        Parameters
        ----------
        observed_hands : array, shape (4,)
            ``lhy lhz rhy rhz`` in [0, 1]. NaN marks a value that was not seen (a lost
            tracker): the network uses its own prediction there. Values outside [0, 1] are
            clipped to it (the view plane ends there).
        prior_pb : array, shape (P,), optional
            A PB expected from above (a routine's prediction, :mod:`rnnpb.model.routines`):
            tried as one more restart for the recent end of the window, beside the learned
            patterns' PBs; the window's evidence decides whether it is taken. Without it (or
            with ``restart_span`` 0) the step is exactly the plain one.
        """
        candidates = self._candidates_with(prior_pb)
        u, seen = normalized_hands(observed_hands, self.model.network.sensory_size)
        steers = self.meta_level is None or self.meta_level.steers()
        out = np.empty((1, self._layout.pattern_errors.stop), self.dtype)
        step_sessions(
            self._net,
            self._meta,
            self._state,
            u[None].astype(self.dtype),
            seen[None],
            np.array([self._guarded and steers]),
            candidates,
            self._phase_candidates,
            self._pattern_rho,
            self._settings,
            out,
            self._native,
        )
        result, self._recognition, self._predicted = self._finish(
            out[0].astype(np.float64), u, seen, self._recognition, self._predicted
        )
        if self.meta_level is not None:
            motor, why = self.meta_level.inhibit(result.regime, result.pb, result.motor)
            if why:
                result = replace(result, motor=motor, inhibited=why, generated=result.motor)
        self.steps += 1
        return result

    def _finish(
        self,
        packed: np.ndarray,
        u: np.ndarray,
        seen: np.ndarray,
        recognition: RecognitionState,
        predicted: np.ndarray | None,
    ) -> tuple[StepResult, RecognitionState, np.ndarray]:
        """The host side of a step, from its packed outputs (one session's row): the
        prediction error, recognition and the result in raw units; returns the result, the
        recognition state and the prediction to measure the next step against."""
        outputs = StepOutputs(*(packed[part] for part in self._layout))
        prediction_error = one_step_prediction_error(predicted, u, seen)
        recognition, seen_now = recognise(
            recognition,
            u,
            seen,
            outputs.pattern_errors,
            outputs.pb,
            self._learned_pb,
            self.patterns,
            self.recognition,
            self._taught,
        )
        result = StepResult(
            motor=motor_command(self.model, outputs.motor),
            predicted_hands=outputs.predicted_sensory,
            pb=outputs.pb,
            prediction_error=prediction_error,
            window_error=float(outputs.window_error[0]),
            seen=seen,
            held=bool(outputs.held[0]),
            context=outputs.context,
            recognised=seen_now.recognised,
            confidence=seen_now.confidence,
            novelty=seen_now.novelty,
            pattern_confidence=seen_now.confidences,
            pattern_errors=outputs.pattern_errors,
            regime=regime_of(seen, seen_now.novelty),
            repeating=seen_now.repeating,
        )
        return result, recognition, outputs.predicted_sensory


class ReferenceMirrorSystem(MirrorSystem):
    """:class:`MirrorSystem` in float64: the same step, the reference the float32 one is held
    to (its drop-in twin: same constructor, same :meth:`step`, :meth:`reset`, :attr:`pb`,
    :attr:`pb_profile` and :attr:`steps`)."""

    dtype = np.float64


#: The mirror system's twins by name, so that a test or the bench swaps one for the other.
MIRROR_SYSTEMS: dict[str, type[MirrorSystem]] = {
    "compiled": MirrorSystem,
    "reference": ReferenceMirrorSystem,
}
