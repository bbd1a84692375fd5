"""The regression window's forward and backward pass: the fast kernel of the on-line step.

:func:`run` is :func:`rnnpb.model.network.mixed_loop` over the regression window, rearranged
for speed; :func:`gradients` is the derivative of :func:`squared_error` (the window's sensory
error) with respect to the PB profile's internal values and the onset state, by a hand-written
back-propagation through the window. ``tests/model/test_gradients.py`` holds them together:
``run`` equals ``mixed_loop``, ``gradients`` equals ``jax.grad(squared_error)``, and both equal
the NumPy reference (:mod:`rnnpb.model.reference`).

Why the kernel is written as it is (docs/model.md, "Speed"): the regression's loops must hold
no operation XLA hands to a matrix library, so that each compiles as one function
(:mod:`rnnpb._xla`; ``tests/model/test_compiled_loop.py`` checks it).

Shapes: L window, S sensory, M motor, I = S + M, P PB, C context, H hidden.
"""

from __future__ import annotations

from typing import Protocol

import jax
import jax.numpy as jnp

from rnnpb.model.network import Params
from rnnpb.model.online_config import OnlineConfig


class WindowObservations(Protocol):
    """What the kernel reads of the on-line state (:class:`rnnpb.model.online.OnlineState`)."""

    @property
    def sensory(self) -> jax.Array:
        """(L, S) observed, normalized; 0 where not seen."""
        ...

    @property
    def seen(self) -> jax.Array:
        """(L, S) bool."""
        ...

    @property
    def motor_sent(self) -> jax.Array:
        """(L, M) motor commands sent, normalized (the inputs with ``motor_input="recorded"``)."""
        ...

    @property
    def n(self) -> jax.Array:
        """() int: steps in the window."""
        ...


# Unrolling the window's time loop by 5 runs as fast as unrolling it fully (measured) and
# compiles in a third of the time.
_UNROLL = 5


def _small_matmul(a: jax.Array, b: jax.Array) -> jax.Array:
    """``a @ b`` for the window's small matrices, (L, n) @ (n, m), written as ``n`` products
    and sums of whole rows: element-wise operations that XLA compiles into the surrounding
    regression loop, where a matrix product or a reduction would be handed to a matrix
    library and keep the loop from being compiled as one function (see :mod:`rnnpb._xla`)."""
    total = a[:, 0, None] * b[0][None, :]
    for k in range(1, a.shape[1]):
        total = total + a[:, k, None] * b[k][None, :]
    return total


def _window_terms(
    params: Params, state: WindowObservations, rho: jax.Array, config: OnlineConfig
) -> tuple[jax.Array, jax.Array, jax.Array, jax.Array]:
    """What the window's forward pass needs besides the recurrence (see :func:`run`)."""
    length, n_s = state.sensory.shape
    n_m = state.motor_sent.shape[1]
    n_io = n_s + n_m
    n_pb = rho.shape[1]
    valid = jnp.arange(length) < state.n
    seen = state.seen & valid[:, None]
    w_in = params.w_in
    w_u, w_m = w_in[:n_s], w_in[n_s:n_io]
    w_p, w_c = w_in[n_io : n_io + n_pb], w_in[n_io + n_pb :]
    recorded = config.motor_input == "recorded"
    pre = (
        _small_matmul(jnp.where(seen, state.sensory, 0.0), w_u)
        + _small_matmul(jax.nn.sigmoid(rho), w_p)
        + params.b_h
    )
    if recorded:
        pre = pre + _small_matmul(state.motor_sent, w_m)
    w_loop = jnp.concatenate([w_u, w_m, w_c], axis=0)
    motor_mask = jnp.zeros if recorded else jnp.ones
    mask = jnp.concatenate(
        [
            (~seen).astype(pre.dtype),
            motor_mask((length, n_m), pre.dtype),
            jnp.ones((length, w_c.shape[0]), pre.dtype),
        ],
        axis=1,
    )
    return pre, w_loop, mask, w_p


def _first_input(onset_context: jax.Array, onset_motor: jax.Array, n_s: int) -> jax.Array:
    return jnp.concatenate(
        [
            jnp.full((n_s,), 0.5, onset_motor.dtype),
            jax.nn.sigmoid(onset_motor),
            jax.nn.sigmoid(onset_context),
        ]
    )


def run(
    params: Params,
    state: WindowObservations,
    rho: jax.Array,
    onset_context: jax.Array,
    onset_motor: jax.Array,
    config: OnlineConfig,
) -> tuple[jax.Array, jax.Array]:
    """:func:`rnnpb.model.network.mixed_loop` over the window, rearranged for speed.

    Parameters
    ----------
    state : WindowObservations
        The window: observations (L, S), which were seen, the motor commands sent (L, M) and
        how many steps it holds (later steps are ignored).
    rho : array, shape (L, P)
        The PB profile's internal values (``p_t = sigmoid(rho_t)``).
    onset_context, onset_motor : arrays, shapes (C,) and (M,)
        Logits of the context and motor input at the window's first step.

    Returns
    -------
    predictions : array, shape (L, I)
    contexts : array, shape (L, C)

    The terms of the hidden layer's input that do not depend on the recurrence — the observed
    sensory values, the PB (and recorded motor inputs) — are multiplied for all steps at once
    outside the time loop. Inside it, the recurrent part of the next input is the previous
    output ``[sensory, motor, context]`` times a 0/1 mask (sensory kept only where not seen,
    motor only in closed loop). Same function as ``mixed_loop`` (tests/model/test_gradients.py
    holds them together).
    """
    n_io = state.sensory.shape[1] + onset_motor.shape[0]
    _, outputs = forward(params, state, rho, onset_context, onset_motor, config)
    return outputs[:, :n_io], outputs[:, n_io:]


def forward(
    params: Params,
    state: WindowObservations,
    rho: jax.Array,
    onset_context: jax.Array,
    onset_motor: jax.Array,
    config: OnlineConfig,
) -> tuple[jax.Array, jax.Array]:
    """The window's forward pass: hidden (L, H) and outputs (L, I + C) of every step."""
    pre, w_loop, mask, _ = _window_terms(params, state, rho, config)

    def step_(previous_output, xs):
        pre_t, mask_t = xs
        hidden = jax.nn.sigmoid(pre_t + (previous_output * mask_t) @ w_loop)
        output = jax.nn.sigmoid(hidden @ params.w_out + params.b_out)
        return output, (hidden, output)

    first = _first_input(onset_context, onset_motor, state.sensory.shape[1])
    _, (hidden, outputs) = jax.lax.scan(step_, first, (pre, mask), unroll=_UNROLL)
    return hidden, outputs


def prediction_errors(
    predictions: jax.Array, state: WindowObservations, since: jax.Array | int | None = None
) -> tuple[jax.Array, jax.Array]:
    """Each window step's sensory prediction minus the next observation, where one was seen
    (from step ``since`` on, when given): errors (L - 1, S), 0 elsewhere, and the mask."""
    length, n_s = state.sensory.shape
    index = jnp.arange(length - 1)
    steps = index < state.n - 1
    if since is not None:
        steps = steps & (index >= since)
    target = steps[:, None] & state.seen[1:]
    return jnp.where(target, predictions[:-1, :n_s] - state.sensory[1:], 0.0), target


def movement(state: WindowObservations, since: jax.Array | int | None = None) -> jax.Array:
    """The mean squared change of the observations from one step to the next over the steps
    :func:`prediction_errors` compares (from step ``since`` on, when given), where both were
    seen (0 if none): how far the hands move a step."""
    length, _ = state.sensory.shape
    index = jnp.arange(length - 1)
    steps = index < state.n - 1
    if since is not None:
        steps = steps & (index >= since)
    both = steps[:, None] & state.seen[1:] & state.seen[:-1]
    return mean_squared(jnp.where(both, state.sensory[1:] - state.sensory[:-1], 0.0), both)


def mean_squared(error: jax.Array, target: jax.Array) -> jax.Array:
    """The mean of the squared ``error`` over the entries where ``target`` holds (0 if none)."""
    return jnp.sum(error**2) / jnp.maximum(jnp.sum(target), 1)


def gradients(
    params: Params,
    state: WindowObservations,
    rho: jax.Array,
    onset_context: jax.Array,
    onset_motor: jax.Array,
    config: OnlineConfig,
) -> tuple[jax.Array, jax.Array, jax.Array]:
    """The gradients of :func:`squared_error` with respect to ``rho`` (L, P), the onset
    context (C,) and the onset motor values (M,), by a hand-written back-propagation through
    the window.

    Equal to ``jax.grad(squared_error)`` (tests/model/test_gradients.py) and about a third
    cheaper: it needs none of the general machinery of a differentiated scan.
    """
    length, n_s = state.sensory.shape
    n_m = onset_motor.shape[0]
    _, w_loop, mask, w_p = _window_terms(params, state, rho, config)
    first = _first_input(onset_context, onset_motor, n_s)
    hidden, outputs = forward(params, state, rho, onset_context, onset_motor, config)
    error, _ = prediction_errors(outputs, state)
    d_output_direct = jnp.zeros_like(outputs).at[:-1, :n_s].set(error)
    next_mask = jnp.concatenate([mask[1:], jnp.zeros_like(mask[:1])])
    w_out_t = params.w_out.T
    w_loop_t = w_loop.T

    def backward(d_input_next, xs):
        h_t, o_t, direct_t, next_mask_t = xs
        d_output = direct_t + d_input_next * next_mask_t
        d_hidden_in = ((d_output * o_t * (1.0 - o_t)) @ w_out_t) * h_t * (1.0 - h_t)
        return d_hidden_in @ w_loop_t, d_hidden_in

    d_first, d_pre = jax.lax.scan(
        backward,
        jnp.zeros_like(first),
        (hidden, outputs, d_output_direct, next_mask),
        reverse=True,
        unroll=_UNROLL,
    )
    d_first = d_first * mask[0]
    pb = jax.nn.sigmoid(rho)
    d_rho = _small_matmul(d_pre, w_p.T) * pb * (1.0 - pb)
    motor0 = first[n_s : n_s + n_m]
    context0 = first[n_s + n_m :]
    d_motor = d_first[n_s : n_s + n_m] * motor0 * (1.0 - motor0)
    d_context = d_first[n_s + n_m :] * context0 * (1.0 - context0)
    return d_rho, d_context, d_motor


def squared_error(
    params: Params,
    state: WindowObservations,
    rho: jax.Array,
    onset_context: jax.Array,
    onset_motor: jax.Array,
    config: OnlineConfig,
) -> jax.Array:
    """0.5 · Σ over the window of the squared error of the sensory predictions (arguments as
    for :func:`run`): what the regression descends."""
    predictions, _ = run(params, state, rho, onset_context, onset_motor, config)
    error, _ = prediction_errors(predictions, state)
    return 0.5 * jnp.sum(error**2)
