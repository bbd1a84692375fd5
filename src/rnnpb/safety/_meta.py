"""The meta-level network, learned: PB → risk (a small MLP, :mod:`rnnpb.model.meta`) and how
familiar a PB is (a kernel over the PBs whose behaviour was experienced).
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np
import optax

from rnnpb.errors import ConfigError
from rnnpb.model.meta import MetaParams, risk_logit
from rnnpb.safety._explore import Experience


@dataclass(frozen=True)
class MetaConfig:
    """``hidden`` units per layer; ``iterations`` of Adam at ``learning_rate`` on the weighted
    cross-entropy (unsafe examples weighted up to balance the classes); ``familiarity_width``:
    the width of the familiarity's kernel in PB units; ``seed`` of the initial weights."""

    hidden: int = 32
    iterations: int = 3000
    learning_rate: float = 3e-3
    familiarity_width: float = 0.05
    seed: int = 0

    def __post_init__(self) -> None:
        if self.hidden < 1 or self.iterations < 0 or self.learning_rate <= 0:
            raise ConfigError("hidden >= 1, iterations >= 0 and learning_rate > 0 expected")
        if self.familiarity_width <= 0:
            raise ConfigError(f"familiarity_width must be > 0, got {self.familiarity_width}")


def init_meta(pb_size: int, hidden: int, seed: int) -> MetaParams:
    k1, k2, k3 = jax.random.split(jax.random.PRNGKey(seed), 3)
    return MetaParams(
        w1=jax.random.normal(k1, (pb_size, hidden)) * 2.0,
        b1=jnp.zeros(hidden),
        w2=jax.random.normal(k2, (hidden, hidden)) / np.sqrt(hidden),
        b2=jnp.zeros(hidden),
        w3=jax.random.normal(k3, (hidden,)) / np.sqrt(hidden),
        b3=jnp.asarray(0.0),
    )


def fit_meta(experience: Experience, config: MetaConfig | None = None) -> MetaParams:
    """Learn PB → risk from labelled PBs; returns the weights as NumPy arrays."""
    config = config or MetaConfig()
    x = jnp.asarray(experience.pb, jnp.float32)
    y = jnp.asarray(experience.unsafe, jnp.float32)
    positive = float(np.mean(experience.unsafe))
    weight = jnp.where(y > 0, 0.5 / max(positive, 1e-3), 0.5 / max(1 - positive, 1e-3))
    params = init_meta(x.shape[1], config.hidden, config.seed)
    optimizer = optax.adam(config.learning_rate)

    def loss(p: MetaParams) -> jax.Array:
        logits = risk_logit(p, x)
        return jnp.mean(weight * optax.sigmoid_binary_cross_entropy(logits, y))

    @jax.jit
    def run(p: MetaParams) -> MetaParams:
        def body(_, carry):
            p, state = carry
            grads = jax.grad(loss)(p)
            updates, state = optimizer.update(grads, state, p)
            return optax.apply_updates(p, updates), state

        return jax.lax.fori_loop(0, config.iterations, body, (p, optimizer.init(p)))[0]

    trained = run(params)
    return MetaParams(*(np.asarray(a, dtype=np.float64) for a in trained))


def risk(meta: MetaParams, pb: np.ndarray) -> np.ndarray:
    """The learned risk (probability that the PB's behaviour is unsafe), shape (...)."""
    params = MetaParams(*(jnp.asarray(a, jnp.float32) for a in meta))
    return np.asarray(
        jax.nn.sigmoid(risk_logit(params, jnp.asarray(pb, jnp.float32))), dtype=np.float64
    )


def familiarity(experienced: np.ndarray, pb: np.ndarray, width: float) -> np.ndarray:
    """How familiar each PB (..., P) is, in [0, 1]: ``1 - exp(-k)`` with ``k`` the kernel
    density of the experienced PBs at it, ``sum_i exp(-|pb - e_i|² / 2 width²)`` (about how
    many experienced PBs lie within ``width`` of it). Near 1 where behaviour was generated
    many times, 0.63 at one experienced PB, → 0 far from all of them."""
    pb = np.asarray(pb, dtype=np.float64)
    flat = pb.reshape(-1, pb.shape[-1])
    density = np.empty(len(flat))
    for start in range(0, len(flat), 1024):
        d2 = ((flat[start : start + 1024, None, :] - experienced[None]) ** 2).sum(-1)
        density[start : start + 1024] = np.exp(-d2 / (2 * width**2)).sum(axis=1)
    return (1.0 - np.exp(-density)).reshape(pb.shape[:-1])
