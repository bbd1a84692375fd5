"""Eqs. 1-2 as vectorised in JAX equal the kernels' step-by-step version."""

from typing import Any

import jax.numpy as jnp
import numpy as np
import pytest

from rnnpb.errors import ConfigError
from rnnpb.model import equations, pb_update
from rnnpb.model.parametric_bias import PBUpdateConfig, integrate


def test_integration_sums_the_window_around_each_step():
    delta = np.arange(1.0, 11.0)[:, None]  # (10, 1)
    out = np.asarray(integrate(jnp.asarray(delta), 4))
    for t in range(10):
        assert out[t, 0] == delta[max(t - 2, 0) : t + 3, 0].sum()


@pytest.mark.parametrize("n_valid", [1, 4, 12])
def test_update_matches_reference(n_valid):
    rng = np.random.default_rng(0)
    config = PBUpdateConfig(
        learning_rate=0.3, momentum=0.8, k_bp=1.5, k_nb=0.4, integration_length=6
    )
    rho = rng.normal(size=(12, 3))
    velocity = rng.normal(size=(12, 3)) * 0.1
    velocity[n_valid:] = 0
    grad = rng.normal(size=(12, 3))
    valid = np.arange(12) < n_valid
    new_rho, new_velocity = pb_update(
        jnp.asarray(rho), jnp.asarray(velocity), jnp.asarray(grad), config, jnp.asarray(valid)
    )
    # The kernels' eqs. 1-2 (rnnpb.model.equations), in place, on a float64 copy.
    ref_rho, ref_velocity = rho.copy(), velocity.copy()
    equations.pb_update(
        ref_rho,
        ref_velocity,
        grad,
        n_valid,
        config.integration_length // 2,
        config.k_bp,
        config.k_nb,
        config.learning_rate,
        config.momentum,
        np.empty((13, 3)),
        np.empty((12, 3)),
    )
    np.testing.assert_allclose(np.asarray(new_rho), ref_rho, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(np.asarray(new_velocity), ref_velocity, rtol=1e-5, atol=1e-6)
    # Steps that do not exist yet are left as they were.
    np.testing.assert_allclose(np.asarray(new_rho)[n_valid:], rho[n_valid:], rtol=1e-6)


def test_update_descends_the_error():
    # A single PB unit, error 0.5 (p - 0.8)^2 at every step: the PB must move towards 0.8.
    config = PBUpdateConfig(
        learning_rate=0.5, momentum=0.5, k_bp=1.0, k_nb=0.1, integration_length=4
    )
    rho = jnp.zeros((8, 1))
    velocity = jnp.zeros((8, 1))
    for _ in range(200):
        p = 1 / (1 + jnp.exp(-rho))
        grad = (p - 0.8) * p * (1 - p)
        rho, velocity = pb_update(rho, velocity, grad, config)
    np.testing.assert_allclose(1 / (1 + np.exp(-np.asarray(rho))), 0.8, atol=1e-3)


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(learning_rate=0),
        dict(momentum=1.0),
        dict(k_nb=-1),
        dict(integration_length=-2),
        dict(learning_rate=2.0, k_nb=0.5),
    ],
)
def test_bad_coefficients_are_rejected(kwargs):
    good: dict[str, Any] = dict(
        learning_rate=1.0, momentum=0.9, k_bp=1.0, k_nb=0.1, integration_length=4
    )
    PBUpdateConfig(**good)
    with pytest.raises(ConfigError):
        PBUpdateConfig(**{**good, **kwargs})
