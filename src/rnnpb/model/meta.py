"""The meta-level of the PB space (Ito & Tani 2004, section 4.1): a small network that maps a
PB vector to the risk that the behaviour it generates is unsafe.

"Another network is prepared which learns safe or unsafe regions in the PB space from
experience. The network can be used to prevent the PB values from coming too close to the
learned undesired regions." This module holds only the pure function of that network and the
barrier it puts into eq. 1, so that the on-line step (:mod:`rnnpb.model.online`) can use it
without knowing where its weights came from; :mod:`rnnpb.safety` learns the weights from the
robot's experience and stores them.

The network: ``risk_logit(p) = w3 · tanh(W2 tanh(W1 p + b1) + b2) + b3``; ``risk = σ(risk_logit)``.

The barrier: with ``c`` the risk level the PB should stay below, the regression adds
``barrier · softplus(risk_logit(p) − logit(c))`` per step of the window to the error of eq. 1,
so its gradient pushes ``ρ`` away from the learned unsafe region (and is ≈ 0 far from it).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np


class MetaParams(NamedTuple):
    """Weights of the risk network. Shapes: P PB, H hidden. JAX arrays for the compiled
    step, NumPy arrays for the NumPy twin."""

    w1: jax.Array | np.ndarray  # (P, H)
    b1: jax.Array | np.ndarray  # (H,)
    w2: jax.Array | np.ndarray  # (H, H)
    b2: jax.Array | np.ndarray  # (H,)
    w3: jax.Array | np.ndarray  # (H,)
    b3: jax.Array | np.ndarray  # ()


def risk_logit(params: MetaParams, pb: jax.Array) -> jax.Array:
    """The logit of the risk of the behaviour a PB generates.

    Parameters
    ----------
    pb : array, shape (..., P)
        PB values in [0, 1].

    Returns
    -------
    array, shape (...)
    """
    hidden = jnp.tanh(pb @ params.w1 + params.b1)
    hidden = jnp.tanh(hidden @ params.w2 + params.b2)
    return hidden @ params.w3 + params.b3


def barrier_energy(params: MetaParams, rho: jax.Array, level: float) -> jax.Array:
    """The barrier term per step, summed over ``rho`` (L, P) (the PB's internal values)."""
    excess = risk_logit(params, jax.nn.sigmoid(rho)) - jnp.log(level / (1.0 - level))
    return jnp.sum(jax.nn.softplus(excess))


def project_out(
    params: MetaParams, rho: jax.Array, level: float, steps: int, rate: float
) -> jax.Array:
    """Move each PB of ``rho`` (..., P) down the risk gradient until its risk is below
    ``level`` (at most ``steps`` gradient steps of size ``rate`` in ρ), the projection
    alternative to the barrier."""
    threshold = jnp.log(level / (1.0 - level))

    def one(r: jax.Array) -> jax.Array:
        def body(_, r):
            value, grad = jax.value_and_grad(lambda x: risk_logit(params, jax.nn.sigmoid(x)))(r)
            norm = jnp.sqrt(jnp.sum(grad**2)) + 1e-6
            return jnp.where(value > threshold, r - rate * grad / norm, r)

        return jax.lax.fori_loop(0, steps, body, r)

    flat = rho.reshape(-1, rho.shape[-1])
    return jax.vmap(one)(flat).reshape(rho.shape)
