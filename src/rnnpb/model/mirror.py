"""The mirror system on the host: :class:`MirrorSystem` keeps the on-line state between steps
and speaks raw units (hands in [0, 1], NaN where not seen; joint angles in radians).

Each :meth:`MirrorSystem.step` is one call of the compiled :func:`rnnpb.model.online.online_step`
and one transfer back from the device: the step's outputs come back packed into one vector,
whose layout (:class:`PackedLayout`) is computed once from the network's sizes. The NumPy
reference :class:`rnnpb.model.reference.ReferenceMirrorSystem` is its drop-in twin: same
constructor, same :class:`StepResult`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import partial
from typing import NamedTuple, cast

import jax
import jax.numpy as jnp
import numpy as np
from numpy.typing import ArrayLike

from rnnpb import _xla
from rnnpb.errors import ConfigError
from rnnpb.model.io import TrainedModel
from rnnpb.model.meta import MetaLevel, MetaParams, regime_of
from rnnpb.model.native import NativeRegression, native_regression, prepare_block
from rnnpb.model.network import NetworkConfig, Params, logit_numpy
from rnnpb.model.online import (
    OnlineState,
    Regressed,
    StepOutputs,
    conclude,
    initial_state,
    online_step,
    phase_candidates,
    restart_candidates,
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


class PackedLayout(NamedTuple):
    """Where each of :class:`rnnpb.model.online.StepOutputs` sits in the one vector the
    compiled step hands back: the fields in the same order, each a slice of the vector."""

    motor: slice  # (M,)
    predicted_sensory: slice  # (S,)
    pb: slice  # (P,)
    window_error: slice  # (1,)
    held: slice  # (1,) 1.0 when held
    context: slice  # (C,)
    pattern_errors: slice  # (K,)

    @classmethod
    def for_network(cls, network: NetworkConfig, patterns: int = 0) -> PackedLayout:
        """The layout for a network's sizes and ``patterns`` learned patterns (K)."""
        sizes = {
            "motor": network.motor_size,
            "predicted_sensory": network.sensory_size,
            "pb": network.pb_size,
            "window_error": 1,
            "held": 1,
            "context": network.context_size,
            "pattern_errors": patterns,
        }
        parts, start = {}, 0
        for name in cls._fields:
            parts[name] = slice(start, start + sizes[name])
            start += sizes[name]
        return cls(**parts)

    def unpack(self, packed: np.ndarray) -> StepOutputs[np.ndarray]:
        """The packed vector (host side) back into named outputs."""
        return StepOutputs(*(packed[part] for part in self))


def pack(outputs: StepOutputs[jax.Array]) -> jax.Array:
    """The outputs of a step as one float32 vector, in :class:`PackedLayout`'s order."""
    return jnp.concatenate([jnp.reshape(value, (-1,)).astype(jnp.float32) for value in outputs])


@partial(jax.jit, static_argnames=("config", "recognition_steps"))
def _online_step_packed(
    params: Params,
    state: OnlineState,
    u: jax.Array,
    seen: jax.Array,
    config: OnlineConfig,
    candidates: jax.Array | None = None,
    phase_candidates: jax.Array | None = None,
    meta: MetaParams | None = None,
    pattern_rho: jax.Array | None = None,
    recognition_steps: int = 12,
) -> tuple[OnlineState, jax.Array]:
    """:func:`online_step` with its outputs packed into one vector, so that they come back in
    one transfer."""
    state, outputs = online_step(
        params,
        state,
        u,
        seen,
        config,
        candidates,
        phase_candidates,
        meta,
        pattern_rho,
        recognition_steps,
    )
    return state, pack(outputs)


@partial(jax.jit, static_argnames=("config", "recognition_steps"))
def _conclude_packed(
    params: Params,
    previous: OnlineState,
    state: OnlineState,
    regressed: Regressed[jax.Array] | Regressed[np.ndarray],
    config: OnlineConfig,
    meta: MetaParams | None = None,
    pattern_rho: jax.Array | None = None,
    recognition_steps: int = 12,
) -> tuple[OnlineState, jax.Array]:
    """:func:`rnnpb.model.online.conclude` with its outputs packed into one vector: the step
    after a native regression (:mod:`rnnpb.model.native`)."""
    state, outputs = conclude(
        params, previous, state, regressed, config, meta, pattern_rho, recognition_steps
    )
    return state, pack(outputs)


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
        (:mod:`rnnpb.model.native`); False keeps the whole step in compiled JAX, the reference
        the native loop is held to."""
        _xla.warn_if_not_configured()  # once per process, if nobody chose XLA's loop setting
        self.model = model
        self.config = config or OnlineConfig()
        self.recognition = recognition or suggested_online_config(model).recognition
        self.patterns = tuple(model.pattern_pb)
        self._learned_pb = np.array([model.pattern_pb[name] for name in self.patterns])
        self._taught = taught_stretches(model.taught_hands or {}, self.patterns, self.recognition)
        self._layout = PackedLayout.for_network(model.network, len(self.patterns))
        self._pattern_rho = jnp.asarray(restart_candidates(model), jnp.float32)
        self._recognition = initial_recognition_state(
            model.network.sensory_size, model.network.pb_size, self.recognition
        )
        self._params = jax.tree_util.tree_map(lambda a: jnp.asarray(a, jnp.float32), model.params)
        self._state = initial_state(model, self.config)
        # The last prediction of the hands, kept on the host: the next step's prediction error
        # is measured against it without a transfer from the device.
        self._predicted: np.ndarray | None = None
        self._candidates = None
        if self.config.restart_span > 0:
            self._candidates = jnp.asarray(restart_candidates(model), jnp.float32)
        self._phase_candidates = None
        if self.config.phase_restarts > 0:
            self._phase_candidates = jnp.asarray(phase_candidates(model), jnp.float32)
        self._meta = (
            None if meta is None else MetaParams(*(jnp.asarray(a, jnp.float32) for a in meta))
        )
        self.meta_level = (
            None if meta is None else MetaLevel(meta, self.config.risk_level, steering, inhibition)
        )
        # The regression's loop in native code where it can run (rnnpb.model.native); None:
        # the whole step is the compiled JAX one.
        self._native: NativeRegression | None = (
            native_regression(self._params, model.network, self.config, self._meta)
            if native
            else None
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
        self._state = initial_state(self.model, self.config, initial_pb)
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
        self._state = theirs  # immutable device arrays: both may step on from here
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
        n = int(self._state.n)
        return np.asarray(jax.nn.sigmoid(self._state.rho[max(n - 1, 0)]), dtype=np.float64)

    @property
    def pb_profile(self) -> np.ndarray:
        """The PB over the filled part of the window, shape (n, P)."""
        n = int(self._state.n)
        return np.asarray(jax.nn.sigmoid(self._state.rho[:n]), dtype=np.float64)

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
        candidates = self._candidates
        if prior_pb is not None and candidates is not None:
            prior = np.clip(np.asarray(prior_pb, dtype=np.float64).reshape(-1), 0.0, 1.0)
            if prior.shape != (self.model.network.pb_size,) or not np.isfinite(prior).all():
                raise ConfigError(
                    f"prior PB must be {self.model.network.pb_size} finite values, got "
                    f"{np.shape(prior_pb)}"
                )
            candidates = jnp.concatenate(
                [candidates, jnp.asarray(logit_numpy(prior)[None], jnp.float32)]
            )
        u, seen = normalized_hands(observed_hands, self.model.network.sensory_size)
        # NumPy inputs go to the compiled step as they are and all outputs come back in one
        # transfer: at a few milliseconds a step, per-array round trips are worth avoiding.
        meta = self._meta if self.meta_level is None or self.meta_level.steers() else None
        arguments = (self._params, self._state, u.astype(np.float32), seen, self.config)
        if self._native is not None and self._native.applies(meta):
            start, block = prepare_block(*arguments, candidates, self._phase_candidates)
            self._state, packed = _conclude_packed(
                self._params,
                self._state,
                start,
                self._native(block, meta),
                self.config,
                meta,
                self._pattern_rho,
                self.recognition.recognition_steps,
            )
        else:
            self._state, packed = _online_step_packed(
                *arguments,
                candidates,
                self._phase_candidates,
                meta,
                self._pattern_rho,
                self.recognition.recognition_steps,
            )
        result, self._recognition, self._predicted = self._finish(
            np.asarray(packed, dtype=np.float64), u, seen, self._recognition, self._predicted
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
        outputs = self._layout.unpack(packed)
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
