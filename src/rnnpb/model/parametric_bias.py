"""The parametric bias update of Ito & Tani (2004), eqs. 1–3, shared by learning and
on-line regression.

For the ``i``-th PB unit at step ``t`` of a sequence (or of the regression window)::

    δρ_t = k_bp · Σ_{s=t-l/2}^{t+l/2} δ^bp_s + k_nb · (ρ_{t+1} - 2ρ_t + ρ_{t-1})      (1)
    Δρ_t = ε · δρ_t + η · Δρ_t^(previous iteration)                                 (2)
    p_t  = sigmoid(ρ_t)                                                             (3)

``δ^bp_s`` is the error back-propagated to the PB unit's internal value at step ``s`` (minus the
gradient of the squared prediction error with respect to ``ρ_s``). The sum over the integration
length ``l`` keeps local fluctuations of the error from shaping the PB profile; the second
term is a low-pass filter. The paper writes the momentum term as ``η · Δρ_{t-1}``; the index
there counts update iterations (momentum), not time steps — we read it so.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp

from rnnpb.errors import ConfigError


@dataclass(frozen=True)
class PBUpdateConfig:
    """Coefficients of eqs. 1–2. Each preset holds its own (``[learning.pb]`` for learning,
    ``[online.pb]`` for the on-line regression: :mod:`rnnpb.presets`)."""

    learning_rate: float  # ε
    momentum: float  # η
    k_bp: float
    k_nb: float
    integration_length: int  # l

    def __post_init__(self) -> None:
        if self.learning_rate <= 0:
            raise ConfigError(f"PB learning_rate must be > 0, got {self.learning_rate}")
        if not 0 <= self.momentum < 1:
            raise ConfigError(f"PB momentum must be in [0, 1), got {self.momentum}")
        if self.k_bp < 0 or self.k_nb < 0:
            raise ConfigError("PB k_bp and k_nb must be >= 0")
        if self.k_nb * self.learning_rate > 0.5:
            raise ConfigError(
                "PB k_nb * learning_rate must be <= 0.5 for the low-pass term to stay stable"
            )
        if self.integration_length < 0:
            raise ConfigError(f"PB integration_length must be >= 0, got {self.integration_length}")


def integrate(delta: jax.Array, length: int, valid: jax.Array | None = None) -> jax.Array:
    """Eq. 1's first sum: ``Σ_{s=t-l/2}^{t+l/2} δ_s`` along axis -2, clipped at the ends.

    Parameters
    ----------
    delta : array, shape (..., T, P)
    length : int
        The integration length ``l``.
    valid : array of bool, shape (T,), optional
        Steps that exist; the sum runs over valid steps only.
    """
    if valid is not None:
        delta = jnp.where(valid[:, None], delta, 0.0)
    half = length // 2
    n_steps = delta.shape[-2]
    cumulative = jnp.cumsum(delta, axis=-2)
    zeros = jnp.zeros_like(cumulative[..., :1, :])
    cumulative = jnp.concatenate([zeros, cumulative], axis=-2)  # (..., T+1, P)
    t = jnp.arange(n_steps)
    upper = jnp.minimum(t + half + 1, n_steps)
    lower = jnp.maximum(t - half, 0)
    return jnp.take(cumulative, upper, axis=-2) - jnp.take(cumulative, lower, axis=-2)


def second_difference(rho: jax.Array, valid: jax.Array | None = None) -> jax.Array:
    """Eq. 1's low-pass term ``ρ_{t+1} - 2ρ_t + ρ_{t-1}`` along axis -2, ends held flat."""
    previous = jnp.concatenate([rho[..., :1, :], rho[..., :-1, :]], axis=-2)
    following = jnp.concatenate([rho[..., 1:, :], rho[..., -1:, :]], axis=-2)
    if valid is not None:
        # The last valid step has no valid successor: hold it flat there.
        valid_next = jnp.concatenate([valid[1:], jnp.zeros((1,), bool)])
        following = jnp.where(valid_next[:, None], following, rho)
    return following - 2.0 * rho + previous


def pb_update(
    rho: jax.Array,
    velocity: jax.Array,
    grad_rho: jax.Array,
    config: PBUpdateConfig,
    valid: jax.Array | None = None,
) -> tuple[jax.Array, jax.Array]:
    """One iteration of eqs. 1–2.

    Parameters
    ----------
    rho, velocity, grad_rho : arrays, shape (..., T, P)
        Internal PB values, their last update ``Δρ`` (momentum), and the gradient of the
        squared prediction error with respect to ``rho``.
    valid : array of bool, shape (T,), optional
        Steps that exist (the on-line window while it fills); others are left unchanged.

    Returns
    -------
    rho, velocity : arrays, shape (..., T, P)
    """
    delta = config.k_bp * integrate(-grad_rho, config.integration_length, valid)
    delta = delta + config.k_nb * second_difference(rho, valid)
    velocity = config.learning_rate * delta + config.momentum * velocity
    if valid is not None:
        velocity = jnp.where(valid[:, None], velocity, 0.0)
    return rho + velocity, velocity
