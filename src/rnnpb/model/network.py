"""The recurrent neural network with parametric bias (RNNPB) of Tani & Ito (2003), as used by
Ito & Tani (2004), section 2.2.

A Jordan-type RNN. Its input layer holds the current sensory-motor values ``x_t`` (4 sensory +
8 motor, normalized to [0, 1]), the parametric bias ``p_t`` and the context ``c_t``; one hidden
layer; its output layer predicts the next sensory-motor values and the next context, which is fed
back as the context input of the next step::

    h_t     = sigmoid(W_xh x_t + W_ph p_t + W_ch c_t + b_h)          shape (hidden,)
    x̂_{t+1} = sigmoid(W_hy h_t + b_y)                               shape (sensory + motor,)
    c_{t+1} = sigmoid(W_hc h_t + b_c)                               shape (context,)

The three input matrices are stored stacked as one ``w_in = [W_xh; W_ph; W_ch]`` and the two
output matrices as ``w_out = [W_hy, W_hc]``: one matrix product per layer is what makes a step
fast at these small sizes.

Everything is built on one pure :func:`step`. Three ways to run a sequence:

* open loop (teacher forcing, the learning phase): every input is the recorded value;
* closed loop (generation, attractor analysis): every input is the network's own previous
  prediction — no external input at all;
* mixed (the interaction phase): the sensory input comes from outside (the user's hands), the
  motor input is the network's own previous motor prediction.

The parametric bias itself (eqs. 1–3) is computed by the callers
(:mod:`rnnpb.model.learning`, :mod:`rnnpb.model.online`) as ``p_t = sigmoid(rho_t)``; where a
unit's value must be turned back into the internal value it comes from (a learned PB into
``rho``, a context output into the next onset's logit), :func:`logit` does it.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from rnnpb.errors import ConfigError


@dataclass(frozen=True)
class NetworkConfig:
    """Sizes of the network. The defaults are the paper's (section 3)."""

    sensory_size: int = 4
    motor_size: int = 8
    pb_size: int = 4
    hidden_size: int = 40
    context_size: int = 30

    def __post_init__(self) -> None:
        for name, value in asdict(self).items():
            if not isinstance(value, int) or value < 1:
                raise ConfigError(f"network {name} must be a positive integer, got {value!r}")

    @property
    def io_size(self) -> int:
        """Size of the sensory-motor vector ``x`` (inputs and predicted outputs)."""
        return self.sensory_size + self.motor_size


class Params(NamedTuple):
    """The synaptic weights, shared by all patterns.

    Shapes (I = io_size, P = pb_size, C = context_size, H = hidden_size):
    ``w_in (I + P + C, H)`` — rows ``[W_xh; W_ph; W_ch]``; ``b_h (H,)``;
    ``w_out (H, I + C)`` — columns ``[W_hy, W_hc]``; ``b_out (I + C,)`` — ``[b_y, b_c]``.
    """

    w_in: jax.Array
    b_h: jax.Array
    w_out: jax.Array
    b_out: jax.Array


def init_params(config: NetworkConfig, key: jax.Array) -> Params:
    """Random initial weights: uniform in ±1/sqrt(fan-in), biases zero."""
    i, p, c, h = config.io_size, config.pb_size, config.context_size, config.hidden_size
    k_in, k_out = jax.random.split(key)
    a_in = 1.0 / np.sqrt(i + p + c)
    a_out = 1.0 / np.sqrt(h)
    return Params(
        w_in=jax.random.uniform(k_in, (i + p + c, h), jnp.float32, -a_in, a_in),
        b_h=jnp.zeros(h, jnp.float32),
        w_out=jax.random.uniform(k_out, (h, i + c), jnp.float32, -a_out, a_out),
        b_out=jnp.zeros(i + c, jnp.float32),
    )


def step(
    params: Params, context: jax.Array, x: jax.Array, pb: jax.Array
) -> tuple[jax.Array, jax.Array]:
    """One step of the network.

    Parameters
    ----------
    params : Params
    context : array, shape (..., C)
        The context ``c_t``.
    x : array, shape (..., I)
        The sensory-motor input ``x_t``, normalized.
    pb : array, shape (..., P)
        The parametric bias ``p_t`` in (0, 1).

    Returns
    -------
    context_next : array, shape (..., C)
        ``c_{t+1}``.
    prediction : array, shape (..., I)
        ``x̂_{t+1}``, the predicted next sensory-motor values.
    """
    hidden = jax.nn.sigmoid(jnp.concatenate([x, pb, context], axis=-1) @ params.w_in + params.b_h)
    output = jax.nn.sigmoid(hidden @ params.w_out + params.b_out)
    io_size = x.shape[-1]
    prediction, context_next = output[..., :io_size], output[..., io_size:]
    return context_next, prediction


def open_loop(
    params: Params, context: jax.Array, inputs: jax.Array, pbs: jax.Array, unroll: int | bool = 2
) -> tuple[jax.Array, jax.Array]:
    """Teacher-forced run: every input is given.

    Parameters
    ----------
    context : array, shape (..., C)
        Initial context.
    inputs : array, shape (T, ..., I)
        ``x_0 … x_{T-1}``.
    pbs : array, shape (T, ..., P)
        ``p_0 … p_{T-1}``.

    Returns
    -------
    predictions : array, shape (T, ..., I)
        ``x̂_1 … x̂_T``.
    contexts : array, shape (T, ..., C)
        ``c_1 … c_T``.
    """

    def body(c, xs):
        x, pb = xs
        c_next, y = step(params, c, x, pb)
        return c_next, (y, c_next)

    _, (predictions, contexts) = jax.lax.scan(body, context, (inputs, pbs), unroll=unroll)
    return predictions, contexts


def closed_loop(
    params: Params, context: jax.Array, x0: jax.Array, pbs: jax.Array
) -> tuple[jax.Array, jax.Array]:
    """Generation without external input: each prediction is the next input.

    Parameters
    ----------
    context : array, shape (..., C)
        Initial context.
    x0 : array, shape (..., I)
        First input.
    pbs : array, shape (T, ..., P)
        Parametric bias per step (constant rows for a fixed PB).

    Returns
    -------
    predictions : array, shape (T, ..., I)
        ``x̂_1 … x̂_T``.
    contexts : array, shape (T, ..., C)
        ``c_1 … c_T``.
    """

    def body(carry, pb):
        c, x = carry
        c_next, y = step(params, c, x, pb)
        return (c_next, y), (y, c_next)

    _, (predictions, contexts) = jax.lax.scan(body, (context, x0), pbs)
    return predictions, contexts


def mixed_loop(
    params: Params,
    context: jax.Array,
    motor0: jax.Array,
    sensory: jax.Array,
    pbs: jax.Array,
    sensory_seen: jax.Array | None = None,
    motor_inputs: jax.Array | None = None,
    unroll: int | bool = 1,
) -> tuple[jax.Array, jax.Array]:
    """The interaction phase's run: sensory input from outside, motor input from the network.

    Where ``sensory_seen`` is False (a hand not seen), the network's own sensory prediction is
    used as input instead, so the network runs on its own prediction through gaps.

    Parameters
    ----------
    context : array, shape (C,)
        Initial context.
    motor0 : array, shape (M,)
        Motor input of the first step.
    sensory : array, shape (T, S)
        Observed sensory values (normalized); entries where not seen are ignored.
    pbs : array, shape (T, P)
    sensory_seen : array of bool, shape (T, S), optional
        Which sensory entries were observed (default: all).
    motor_inputs : array, shape (T, M), optional
        Recorded motor inputs to use instead of the network's own motor predictions
        (``motor0`` is then ignored).

    Returns
    -------
    predictions : array, shape (T, I)
        ``x̂_1 … x̂_T`` (sensory first, then motor).
    contexts : array, shape (T, C)
        ``c_1 … c_T``.
    """
    n_sensory = sensory.shape[-1]
    if sensory_seen is None:
        sensory_seen = jnp.ones(sensory.shape, dtype=bool)
    recorded = motor_inputs is not None
    if motor_inputs is None:
        motor_inputs = jnp.zeros((sensory.shape[0], motor0.shape[-1]), sensory.dtype)

    def body(carry, xs):
        c, motor, predicted_sensory = carry
        u, seen, pb, recorded_motor = xs
        u_in = jnp.where(seen, u, predicted_sensory)
        m_in = recorded_motor if recorded else motor
        c_next, y = step(params, c, jnp.concatenate([u_in, m_in]), pb)
        return (c_next, y[n_sensory:], y[:n_sensory]), (y, c_next)

    first_sensory = jnp.where(sensory_seen[0], sensory[0], 0.5)
    _, (predictions, contexts) = jax.lax.scan(
        body,
        (context, motor0, first_sensory),
        (sensory, sensory_seen, pbs, motor_inputs),
        unroll=unroll,
    )
    return predictions, contexts


# A saturated unit (an output at 0 or 1 in float32) has no finite logit: values are clipped
# this far inside (0, 1) first, which bounds the internal values at about ±9.2.
LOGIT_CLIP = 1e-4


def logit(p: jax.Array) -> jax.Array:
    """The inverse of the units' sigmoid, ``log(p / (1 - p))``, for ``p`` clipped to
    ``[LOGIT_CLIP, 1 - LOGIT_CLIP]``; any shape. :func:`logit_numpy` is the same on the host."""
    p = jnp.clip(p, LOGIT_CLIP, 1 - LOGIT_CLIP)
    return jnp.log(p) - jnp.log1p(-p)


def logit_numpy(p: np.ndarray) -> np.ndarray:
    """:func:`logit` in NumPy, in the precision of ``p`` (float64 for host-side values: learned
    PBs, phase candidates, the compiled step's state)."""
    p = np.clip(p, LOGIT_CLIP, 1 - LOGIT_CLIP)
    return np.log(p) - np.log1p(-p)


def params_to_numpy(params: Params) -> dict[str, np.ndarray]:
    return {name: np.asarray(value) for name, value in params._asdict().items()}


def params_from_numpy(arrays: dict[str, np.ndarray]) -> Params:
    return Params(**{name: jnp.asarray(arrays[name], jnp.float32) for name in Params._fields})


def param_shapes(config: NetworkConfig) -> dict[str, tuple[int, ...]]:
    i, p, c, h = config.io_size, config.pb_size, config.context_size, config.hidden_size
    return {"w_in": (i + p + c, h), "b_h": (h,), "w_out": (h, i + c), "b_out": (i + c,)}
