"""A straightforward NumPy implementation of the RNNPB with hand-written back-propagation
through time, in float64.

It is the reference the JAX implementation is held to (tests/model/test_gradients.py and
test_online.py) and the baseline ``rnnpb bench`` compares the compiled on-line step with. It is
written for clarity, not speed: plain loops over time, one matrix product at a time.
:class:`ReferenceMirrorSystem` is the drop-in twin of :class:`rnnpb.model.mirror.MirrorSystem`;
:data:`MIRROR_SYSTEMS` names both.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from rnnpb.model.io import TrainedModel
from rnnpb.model.meta import MetaLevel, MetaParams, regime_of
from rnnpb.model.mirror import (
    MirrorSystem,
    StepResult,
    motor_command,
    normalized_hands,
    one_step_prediction_error,
)
from rnnpb.model.network import Params, logit_numpy
from rnnpb.model.online import phase_candidates, restart_candidates
from rnnpb.model.online_config import TUNED_MOVEMENT, OnlineConfig, suggested_online_config
from rnnpb.model.parametric_bias import PBUpdateConfig
from rnnpb.model.recognition import (
    RecognitionConfig,
    initial_recognition_state,
    recognise,
    taught_stretches,
)


def sigmoid(z: np.ndarray) -> np.ndarray:
    return 1.0 / (1.0 + np.exp(-z))


def as_numpy(params: Params) -> dict[str, np.ndarray]:
    return {k: np.asarray(v, dtype=np.float64) for k, v in params._asdict().items()}


def _layer(w: dict[str, np.ndarray], a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    h = sigmoid(a @ w["w_in"] + w["b_h"])
    o = sigmoid(h @ w["w_out"] + w["b_out"])
    return h, o


def _layer_backward(
    w: dict[str, np.ndarray],
    a: np.ndarray,
    h: np.ndarray,
    o: np.ndarray,
    d_o: np.ndarray,
    grads: dict[str, np.ndarray] | None,
) -> np.ndarray:
    """Back through one step; accumulate weight gradients into ``grads``; return dE/da."""
    dz_o = d_o * o * (1.0 - o)
    dh = dz_o @ w["w_out"].T
    dz_h = dh * h * (1.0 - h)
    if grads is not None:
        h2, dz_o2 = h.reshape(-1, h.shape[-1]), dz_o.reshape(-1, dz_o.shape[-1])
        a2, dz_h2 = a.reshape(-1, a.shape[-1]), dz_h.reshape(-1, dz_h.shape[-1])
        grads["w_out"] += h2.T @ dz_o2
        grads["b_out"] += dz_o2.sum(0)
        grads["w_in"] += a2.T @ dz_h2
        grads["b_h"] += dz_h2.sum(0)
    return dz_h @ w["w_in"].T


def training_error_and_gradients(
    params: Params,
    rho: np.ndarray,
    context_logit: np.ndarray,
    inputs: np.ndarray,
    valid: np.ndarray,
) -> tuple[float, dict[str, np.ndarray], np.ndarray, np.ndarray]:
    """The learning phase's error ``E = 0.5 Σ (x̂_{t+1} - x_{t+1})²`` and its gradients.

    Parameters
    ----------
    rho : array, shape (S, T-1, P)
    context_logit : array, shape (S, C)
    inputs : array, shape (S, T, I)
        Normalized sequences (teacher-forced inputs and targets).
    valid : array of bool, shape (S, T-1)

    Returns
    -------
    error, weight gradients (dict like Params), dE/drho (S, T-1, P), dE/dcontext_logit (S, C)
    """
    w = as_numpy(params)
    n_io = inputs.shape[-1]
    n_pb = rho.shape[-1]
    n_steps = rho.shape[1]
    pb = sigmoid(rho)
    context = sigmoid(context_logit)
    acts, hs, os_ = [], [], []
    c = context
    error = 0.0
    for t in range(n_steps):
        a = np.concatenate([inputs[:, t], pb[:, t], c], axis=-1)
        h, o = _layer(w, a)
        acts.append(a)
        hs.append(h)
        os_.append(o)
        c = o[:, n_io:]
        e = (o[:, :n_io] - inputs[:, t + 1]) * valid[:, t, None]
        error += 0.5 * float(np.sum(e**2))
    grads = {k: np.zeros_like(v) for k, v in w.items()}
    d_rho = np.zeros_like(rho)
    d_c_next = np.zeros_like(context)
    for t in reversed(range(n_steps)):
        o = os_[t]
        e = (o[:, :n_io] - inputs[:, t + 1]) * valid[:, t, None]
        d_o = np.concatenate([e, d_c_next], axis=-1)
        d_a = _layer_backward(w, acts[t], hs[t], o, d_o, grads)
        d_rho[:, t] = d_a[:, n_io : n_io + n_pb] * pb[:, t] * (1.0 - pb[:, t])
        d_c_next = d_a[:, n_io + n_pb :]
    d_context_logit = d_c_next * context * (1.0 - context)
    return error, grads, d_rho, d_context_logit


def window_error_and_gradients(
    params: Params,
    sensory: np.ndarray,
    seen: np.ndarray,
    n: int,
    rho: np.ndarray,
    onset_context_logit: np.ndarray,
    onset_motor_logit: np.ndarray,
    motor_inputs: np.ndarray | None = None,
):
    """The interaction phase's window error and its gradients (mixed mode, hand-written BPTT).

    Parameters
    ----------
    sensory, seen : arrays, shape (L, S)
        The window's observations (normalized) and which were seen; steps ``>= n`` are empty.
    rho : array, shape (L, P)
    onset_context_logit : array, shape (C,)
    onset_motor_logit : array, shape (M,)
    motor_inputs : array, shape (L, M), optional
        Recorded motor inputs (else the network's own motor predictions, closed loop).

    Returns
    -------
    error, dE/drho (L, P), dE/donset_context_logit (C,), dE/donset_motor_logit (M,),
    predictions (L, I), contexts (L, C)
    """
    w = as_numpy(params)
    length, n_s = sensory.shape
    n_pb = rho.shape[-1]
    n_m = onset_motor_logit.shape[0]
    n_io = n_s + n_m
    seen = seen & (np.arange(length) < n)[:, None]
    pb = sigmoid(rho)
    c = sigmoid(onset_context_logit)
    motor0 = sigmoid(onset_motor_logit)
    motor = motor0
    predicted_sensory = np.where(seen[0], sensory[0], 0.5)
    acts, hs, os_ = [], [], []
    for t in range(length):
        u_in = np.where(seen[t], sensory[t], predicted_sensory)
        m_in = motor_inputs[t] if motor_inputs is not None else motor
        a = np.concatenate([u_in, m_in, pb[t], c])
        h, o = _layer(w, a)
        acts.append(a)
        hs.append(h)
        os_.append(o)
        c = o[n_io:]
        motor = o[n_s:n_io]
        predicted_sensory = o[:n_s]
    predictions = np.array([o[:n_io] for o in os_])
    contexts = np.array([o[n_io:] for o in os_])
    has_target = np.zeros((length, n_s), bool)
    has_target[:-1] = (np.arange(length - 1) < n - 1)[:, None] & seen[1:]
    errors = np.zeros((length, n_s))
    errors[:-1] = np.where(has_target[:-1], predictions[:-1, :n_s] - sensory[1:], 0.0)
    error = 0.5 * float(np.sum(errors**2))
    d_rho = np.zeros_like(rho)
    d_c_next = np.zeros(c.shape)
    d_u_in_next = np.zeros(n_s)  # dE/d(sensory input of step t+1)
    d_m_in_next = np.zeros(n_m)  # dE/d(motor input of step t+1)
    for t in reversed(range(length)):
        o = os_[t]
        d_y = errors[t].copy()
        if t + 1 < length:
            # The next step's sensory input is this step's prediction where not seen.
            d_y += np.where(seen[t + 1], 0.0, d_u_in_next)
        d_m = d_m_in_next if motor_inputs is None else np.zeros(n_m)
        d_o = np.concatenate([d_y, d_m, d_c_next])
        d_a = _layer_backward(w, acts[t], hs[t], o, d_o, None)
        d_u_in_next = d_a[:n_s]
        d_m_in_next = d_a[n_s:n_io]
        d_rho[t] = d_a[n_io : n_io + n_pb] * pb[t] * (1.0 - pb[t])
        d_c_next = d_a[n_io + n_pb :]
    onset_c = sigmoid(onset_context_logit)
    d_context = d_c_next * onset_c * (1.0 - onset_c)
    d_motor = d_m_in_next * motor0 * (1.0 - motor0) if motor_inputs is None else np.zeros(n_m)
    return error, d_rho, d_context, d_motor, predictions, contexts


def pb_update(
    rho: np.ndarray, velocity: np.ndarray, grad: np.ndarray, config: PBUpdateConfig, n_valid: int
) -> tuple[np.ndarray, np.ndarray]:
    """Eqs. 1–2 on the first ``n_valid`` steps of a (T, P) profile, written out step by step."""
    length = rho.shape[0]
    half = config.integration_length // 2
    new_rho = rho.copy()
    new_velocity = np.zeros_like(velocity)
    for t in range(n_valid):
        lo, hi = max(t - half, 0), min(t + half + 1, n_valid)
        summed = -grad[lo:hi].sum(axis=0)
        previous = rho[t - 1] if t > 0 else rho[t]
        following = rho[t + 1] if t + 1 < min(n_valid, length) else rho[t]
        delta = config.k_bp * summed + config.k_nb * (following - 2 * rho[t] + previous)
        new_velocity[t] = config.learning_rate * delta + config.momentum * velocity[t]
        new_rho[t] = rho[t] + new_velocity[t]
    return new_rho, new_velocity


def risk_logit_and_gradient(meta: MetaParams, rho: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The risk network (:func:`rnnpb.model.meta.risk_logit`) at the PBs ``sigmoid(rho)``,
    rows (n, P): the logits (n,) and their gradients with respect to ``rho`` (n, P), by hand."""
    pb = sigmoid(rho)
    h1 = np.tanh(pb @ meta.w1 + meta.b1)
    h2 = np.tanh(h1 @ meta.w2 + meta.b2)
    logits = h2 @ meta.w3 + meta.b3
    d_a2 = meta.w3 * (1.0 - h2**2)
    d_a1 = (d_a2 @ meta.w2.T) * (1.0 - h1**2)
    return np.asarray(logits), np.asarray((d_a1 @ meta.w1.T) * pb * (1.0 - pb))


def barrier_gradient(meta: MetaParams, rho: np.ndarray, n: int, config: OnlineConfig) -> np.ndarray:
    """The gradient of the barrier ``softplus(risk_logit - logit(risk_level))`` summed over
    the newest ``config.barrier_span`` rows of ``rho`` (L, P) (all for 0), zero elsewhere
    (as :func:`rnnpb.model.online._barrier_gradient`)."""
    length = len(rho)
    span = config.barrier_span or length
    start = 0 if span >= length else int(np.clip(n - span, 0, length - span))
    rows = slice(start, start + min(span, length))
    logits, grad = risk_logit_and_gradient(meta, rho[rows])
    threshold = math.log(config.risk_level / (1.0 - config.risk_level))
    out = np.zeros_like(rho)
    out[rows] = sigmoid(logits - threshold)[:, None] * grad  # softplus' = sigmoid
    return out


def project_out(meta: MetaParams, rho: np.ndarray, config: OnlineConfig) -> np.ndarray:
    """Each row of ``rho`` (n, P) moved down the risk gradient until its risk is below
    ``risk_level`` (as :func:`rnnpb.model.meta.project_out`)."""
    threshold = math.log(config.risk_level / (1.0 - config.risk_level))
    rho = rho.copy()
    for _ in range(config.projection_steps):
        logits, grad = risk_logit_and_gradient(meta, rho)
        norm = np.sqrt(np.sum(grad**2, axis=1, keepdims=True)) + 1e-6
        rho = np.where(
            (logits > threshold)[:, None], rho - config.projection_rate * grad / norm, rho
        )
    return rho


class ReferenceMirrorSystem:
    """:class:`rnnpb.model.mirror.MirrorSystem` in plain NumPy, float64: its drop-in twin.

    Same constructor, same :meth:`step` returning a :class:`~rnnpb.model.mirror.StepResult`,
    same :meth:`reset`, :attr:`pb`, :attr:`pb_profile` and :attr:`steps`; same algorithm and
    same state, kept in the attributes below (normalized units) and written out step by step.
    :data:`MIRROR_SYSTEMS` names both.
    """

    def __init__(
        self,
        model: TrainedModel,
        config: OnlineConfig | None = None,
        meta: MetaParams | None = None,
        recognition: RecognitionConfig | None = None,
        steering: str = "always",
        inhibition: bool = False,
    ) -> None:
        self.model = model
        self.config = config or OnlineConfig()
        self.recognition = recognition or suggested_online_config(model).recognition
        self.patterns = tuple(model.pattern_pb)
        self.learned_pb = np.array([model.pattern_pb[name] for name in self.patterns])
        self.taught = taught_stretches(model.taught_hands or {}, self.patterns, self.recognition)
        self.pattern_rho = restart_candidates(model)
        self.params = model.params
        # The safety guard's risk network, as the compiled step takes it (docs/safety.md).
        self.meta = (
            None if meta is None else MetaParams(*(np.asarray(a, dtype=np.float64) for a in meta))
        )
        self.meta_level = (
            None if meta is None else MetaLevel(meta, self.config.risk_level, steering, inhibition)
        )
        # The same learned states as the compiled step's (they are its inputs, not its work).
        self.phase_candidates = phase_candidates(model) if self.config.phase_restarts > 0 else None
        self.candidates = restart_candidates(model) if self.config.restart_span > 0 else None
        self.reset()

    def reset(self, initial_pb: np.ndarray | None = None) -> None:
        """Forget the window: the next step starts a new interaction."""
        net = self.model.network
        length = self.config.window
        pb0 = (
            np.mean(list(self.model.pattern_pb.values()), axis=0)
            if initial_pb is None
            else np.asarray(initial_pb, dtype=np.float64)
        )
        self.sensory = np.zeros((length, net.sensory_size))
        self.seen = np.zeros((length, net.sensory_size), bool)
        self.motor_sent = np.full((length, net.motor_size), 0.5)
        self.n = 0
        self.rho = np.tile(logit_numpy(pb0), (length, 1))
        self.velocity = np.zeros_like(self.rho)
        self.onset_context = logit_numpy(
            np.asarray(self.model.mean_initial_context, dtype=np.float64)
        )
        self.onset_motor = np.zeros(net.motor_size)
        self.next_onset_context = self.onset_context.copy()
        self.next_onset_motor = self.onset_motor.copy()
        self.predicted_sensory = np.full(net.sensory_size, 0.5)
        self._predicted: np.ndarray | None = None
        self.recognition_state = initial_recognition_state(
            net.sensory_size, net.pb_size, self.recognition
        )
        meta_level = getattr(self, "meta_level", None)  # None before __init__ made it
        if meta_level is not None:
            meta_level.reset()
        self.steps = 0

    @property
    def pb(self) -> np.ndarray:
        """The current PB, shape (P,)."""
        return sigmoid(self.rho[max(self.n - 1, 0)])

    @property
    def pb_profile(self) -> np.ndarray:
        """The PB over the filled part of the window, shape (n, P)."""
        return sigmoid(self.rho[: self.n])

    def step(self, observed_hands: np.ndarray) -> StepResult:
        """Observe the user's hands for this step; regress the PB; return the motor command
        (as :meth:`rnnpb.model.mirror.MirrorSystem.step`)."""
        u, seen = normalized_hands(observed_hands, self.model.network.sensory_size)
        motor, predicted, pb, window_error, held, context, errors = self._regress(u, seen)
        self.steps += 1
        prediction_error = one_step_prediction_error(self._predicted, u, seen)
        self._predicted = predicted
        self.recognition_state, seen_now = recognise(
            self.recognition_state,
            u,
            seen,
            errors,
            pb,
            self.learned_pb,
            self.patterns,
            self.recognition,
            self.taught,
        )
        result = StepResult(
            motor=motor_command(self.model, motor),
            predicted_hands=predicted,
            pb=pb,
            prediction_error=prediction_error,
            window_error=window_error,
            seen=seen,
            held=held,
            context=context,
            recognised=seen_now.recognised,
            confidence=seen_now.confidence,
            novelty=seen_now.novelty,
            pattern_confidence=seen_now.confidences,
            pattern_errors=errors,
            regime=regime_of(seen, seen_now.novelty),
            repeating=seen_now.repeating,
        )
        if self.meta_level is not None:
            sent, why = self.meta_level.inhibit(result.regime, result.pb, result.motor)
            if why:
                result = replace(result, motor=sent, inhibited=why, generated=result.motor)
        return result

    def _window(self, motor_inputs: np.ndarray | None):
        """:func:`window_error_and_gradients` over the window as it stands."""
        return window_error_and_gradients(
            self.params,
            self.sensory,
            self.seen,
            self.n,
            self.rho,
            self.onset_context,
            self.onset_motor,
            motor_inputs,
        )

    def _recent_mse(
        self, predictions: np.ndarray, sensory: np.ndarray, seen: np.ndarray, first: int, last: int
    ) -> float:
        """Mean squared error of the predictions made at steps ``first`` … ``last - 1``."""
        squared = [
            (predictions[t, j] - sensory[t + 1, j]) ** 2
            for t in range(first, last)
            for j in range(sensory.shape[1])
            if seen[t + 1, j]
        ]
        return float(np.mean(squared)) if squared else 0.0

    def _level_scale(self, first: int, last: int) -> float:
        """As :func:`rnnpb.model.online.level_scale`: the RMS one-step change of the
        observations ``first + 1`` … ``last`` seen at both ends, over ``TUNED_MOVEMENT``, at
        least 1."""
        squared = [
            (self.sensory[t + 1, j] - self.sensory[t, j]) ** 2
            for t in range(max(first, 0), last)
            for j in range(self.sensory.shape[1])
            if self.seen[t + 1, j] and self.seen[t, j]
        ]
        moved = float(np.sqrt(np.mean(squared))) if squared else 0.0
        return max(moved / TUNED_MOVEMENT, 1.0)

    def _phase_restart(self, motor_inputs: np.ndarray | None) -> None:
        """Start the window over from the learned state that best predicts the last
        ``phase_restarts`` observations, where it does so much better than the window."""
        cfg = self.config
        length = cfg.window
        span = cfg.phase_restarts + 1
        start = self.n - span
        n_pb = self.rho.shape[1]
        n_m = self.onset_motor.shape[0]
        piece = slice(start, start + span)
        sensory, seen = self.sensory[piece], self.seen[piece]
        inputs = None if motor_inputs is None else motor_inputs[piece]
        best_error, best = None, None
        assert self.phase_candidates is not None  # the caller checks
        for candidate in self.phase_candidates:
            predictions = window_error_and_gradients(
                self.params,
                sensory,
                seen,
                span,
                np.tile(candidate[:n_pb], (span, 1)),
                candidate[n_pb + n_m :],
                candidate[n_pb : n_pb + n_m],
                inputs,
            )[4]
            error = self._recent_mse(predictions, sensory, seen, 0, span - 1)
            if best_error is None or error < best_error:
                best_error, best = error, candidate
        assert best_error is not None and best is not None  # one candidate per learned pattern
        predictions = self._window(motor_inputs)[4]
        current = self._recent_mse(predictions, self.sensory, self.seen, start, self.n - 1)
        level = cfg.phase_restart_level * self._level_scale(start, self.n - 1)
        if not (best_error < cfg.phase_restart_ratio * current and current > level**2):
            return
        for name in ("sensory", "seen", "motor_sent"):
            buffer = getattr(self, name)
            moved = buffer[start:].copy()
            buffer[: len(moved)] = moved
            buffer[len(moved) :] = moved[-1]
        self.n = span
        self.rho = np.tile(best[:n_pb], (length, 1))
        self.velocity = np.zeros_like(self.velocity)
        self.onset_motor = best[n_pb : n_pb + n_m].copy()
        self.onset_context = best[n_pb + n_m :].copy()

    def _pattern_errors(self, motor_inputs: np.ndarray | None) -> np.ndarray:
        """Each learned pattern's PB in place of the profile, from the regressed onset, the
        window's last ``recognition_steps`` steps generated (not seen): mean squared error of
        those predictions against the observations, (K,)."""
        n = self.n
        first = max(n - 1 - self.recognition.recognition_steps, 0)
        # The last recognition_steps steps not seen: the network generates them.
        blind = (
            self.seen
            & (np.arange(len(self.seen)) < n - self.recognition.recognition_steps)[:, None]
        )
        errors = []
        for rho_k in self.pattern_rho:
            predictions = window_error_and_gradients(
                self.params,
                self.sensory,
                blind,
                n,
                np.tile(rho_k, (len(self.rho), 1)),
                self.onset_context,
                self.onset_motor,
                motor_inputs,
            )[4]
            errors.append(self._recent_mse(predictions, self.sensory, self.seen, first, n - 1))
        return np.array(errors)

    def _regress(
        self, u: np.ndarray, seen: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, bool, np.ndarray, np.ndarray]:
        """One on-line step on normalized hands ``u`` (S,) (0 where not ``seen``): the motor
        command (M,), the predicted hands (S,), the PB (P,), the window's error, whether the
        last good state was kept, the context after the step (C,) and each learned pattern's
        evidence (K,)."""
        cfg = self.config
        length = cfg.window
        last = max(min(self.n, length) - 1, 0)
        held_motor = self.motor_sent[last].copy()
        if self.n >= length:
            for name in ("sensory", "seen", "motor_sent", "rho", "velocity"):
                buffer = getattr(self, name)
                buffer[:-1] = buffer[1:].copy()
            self.sensory[-1], self.seen[-1] = u, seen
            self.motor_sent[-1] = self.motor_sent[-2]
            self.rho[-1] = self.rho[-2]
            self.velocity[-1] = 0.0
            self.onset_context = self.next_onset_context
            self.onset_motor = self.next_onset_motor
        else:
            i = self.n
            self.sensory[i], self.seen[i] = u, seen
            self.motor_sent[i] = self.motor_sent[last]
            self.rho[i] = self.rho[last]
            self.velocity[i] = 0.0
        self.n = min(self.n + 1, length)
        motor_inputs = self.motor_sent if cfg.motor_input == "recorded" else None
        if self.phase_candidates is not None and self.n >= cfg.phase_restarts + 1:
            self._phase_restart(motor_inputs)
            motor_inputs = self.motor_sent if cfg.motor_input == "recorded" else None
        if self.candidates is not None:
            # Restarts: the recent end of the profile at each learned PB; keep the best fit.
            recent = np.arange(length) >= self.n - cfg.restart_span
            recent &= np.arange(length) < self.n
            best_error, best = None, None
            for k, candidate in enumerate([None, *self.candidates]):
                profile = self.rho.copy()
                if candidate is not None:
                    profile[recent] = candidate
                error = window_error_and_gradients(
                    self.params,
                    self.sensory,
                    self.seen,
                    self.n,
                    profile,
                    self.onset_context,
                    self.onset_motor,
                    motor_inputs,
                )[0]
                if best_error is None or error < best_error:
                    best_error, best = error, (k, profile)
            assert best is not None  # the current profile is always a candidate
            if best[0] > 0:
                self.rho = best[1]
                self.velocity = np.zeros_like(self.velocity)
        # Where the regression would hand out a non-finite value, the step keeps this state.
        start_rho, start_context, start_motor = (
            self.rho.copy(),
            self.onset_context,
            self.onset_motor,
        )
        gate = 1.0
        if cfg.surprise_gate > 0:
            # The surprise gate: RMS error of the last gate_steps predictions before regressing.
            predictions = self._window(motor_inputs)[4]
            rms = float(
                np.sqrt(
                    self._recent_mse(
                        predictions,
                        self.sensory,
                        self.seen,
                        max(self.n - 1 - cfg.gate_steps, 0),
                        self.n - 1,
                    )
                )
            )
            level = cfg.surprise_gate * self._level_scale(
                max(self.n - 1 - cfg.gate_steps, 0), self.n - 1
            )
            gate = float(np.clip((rms / level) ** cfg.gate_power, cfg.gate_floor, 1.0))
        steers = self.meta_level is None or self.meta_level.steers()
        guard = cfg.safety_guard if self.meta is not None and steers else "off"
        barrier = guard == "barrier" and cfg.barrier_weight > 0
        for _ in range(cfg.iterations):
            _, g_rho, g_c, g_m, _, _ = self._window(motor_inputs)
            g_rho = gate * g_rho
            if barrier:
                assert self.meta is not None  # the guard is "off" without it
                g_rho = g_rho + cfg.barrier_weight * barrier_gradient(
                    self.meta, self.rho, self.n, cfg
                )
            self.rho, self.velocity = pb_update(self.rho, self.velocity, g_rho, cfg.pb, self.n)
            if cfg.optimize_onset:
                self.onset_context = self.onset_context - cfg.onset_learning_rate * g_c
                self.onset_motor = self.onset_motor - cfg.onset_learning_rate * g_m
        if guard == "projection":
            assert self.meta is not None
            self.rho[: self.n] = project_out(self.meta, self.rho[: self.n], cfg)
        _, _, _, _, predictions, contexts = self._window(motor_inputs)
        s = self.sensory.shape[1]
        n = self.n
        motor = predictions[n - 2, s:] if n >= 2 else sigmoid(self.onset_motor)
        predicted = predictions[n - 1, :s]
        if not all(
            np.all(np.isfinite(a)) for a in (self.rho, motor, self.onset_context, predicted)
        ):
            self.rho, self.velocity = start_rho, np.zeros_like(self.velocity)
            self.onset_context, self.onset_motor = start_context, start_motor
            self.motor_sent[n - 1] = held_motor
            return (
                held_motor,
                self.predicted_sensory.copy(),
                sigmoid(self.rho[n - 1]),
                math.nan,
                True,
                sigmoid(self.next_onset_context),
                np.full(len(self.patterns), np.nan),
            )
        self.motor_sent[n - 1] = motor
        self.next_onset_context = logit_numpy(contexts[0])
        self.next_onset_motor = logit_numpy(predictions[0, s:])
        self.predicted_sensory = predicted
        window_error = self._recent_mse(predictions, self.sensory, self.seen, 0, n - 1)
        return (
            motor,
            predicted,
            sigmoid(self.rho[n - 1]),
            window_error,
            False,
            contexts[n - 1],
            self._pattern_errors(motor_inputs),
        )


#: The mirror system's twins by name, so that a test or the bench swaps one for the other.
MIRROR_SYSTEMS: dict[str, type[MirrorSystem] | type[ReferenceMirrorSystem]] = {
    "compiled": MirrorSystem,
    "reference": ReferenceMirrorSystem,
}
