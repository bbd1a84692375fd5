"""The JAX gradients equal a hand-written NumPy BPTT and finite differences, in float64.

Tolerance: relative 1e-8 between JAX and the NumPy reference (both exact up to rounding);
1e-5 relative to finite differences with central steps of 1e-6.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from rnnpb.model import NetworkConfig, OnlineConfig, init_params, learning, reference, window
from rnnpb.model.network import Params, mixed_loop
from rnnpb.model.online import OnlineState

NET = NetworkConfig(sensory_size=4, motor_size=8, pb_size=3, hidden_size=7, context_size=5)


def _params64(seed: int) -> Params:
    params = init_params(NET, jax.random.PRNGKey(seed))
    rng = np.random.default_rng(seed)
    # Non-zero biases so their gradients are exercised too.
    return Params(
        w_in=jnp.asarray(np.asarray(params.w_in) * 3, jnp.float64),
        b_h=jnp.asarray(rng.normal(0, 0.3, params.b_h.shape), jnp.float64),
        w_out=jnp.asarray(np.asarray(params.w_out) * 3, jnp.float64),
        b_out=jnp.asarray(rng.normal(0, 0.3, params.b_out.shape), jnp.float64),
    )


def _close(a, b, rtol, atol=1e-12):
    np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=rtol, atol=atol)


def test_learning_gradients_match_numpy_reference_and_finite_differences():
    with jax.enable_x64(True):
        rng = np.random.default_rng(1)
        params = _params64(1)
        n_seq, n_steps = 2, 9
        inputs = rng.uniform(0.1, 0.9, (n_seq, n_steps, NET.io_size))
        valid = np.ones((n_seq, n_steps - 1), bool)
        valid[1, 6:] = False  # a shorter second sequence
        rho = rng.normal(0, 1, (n_seq, n_steps - 1, NET.pb_size))
        context_logit = rng.normal(0, 1, (n_seq, NET.context_size))
        noise = jnp.zeros((n_seq, n_steps - 1, NET.io_size))

        error_fn = jax.jit(learning.squared_error)
        (g_params, g_context), g_rho = jax.grad(learning.squared_error, argnums=(0, 1))(
            (params, jnp.asarray(context_logit)),
            jnp.asarray(rho),
            jnp.asarray(inputs),
            jnp.asarray(valid),
            noise,
        )
        error, r_params, r_rho, r_context = reference.training_error_and_gradients(
            params, rho, context_logit, inputs, valid
        )

        assert float(error_fn((params, context_logit), rho, inputs, valid, noise)) == pytest.approx(
            error, rel=1e-12
        )
        for name in Params._fields:
            _close(getattr(g_params, name), r_params[name], rtol=1e-8)
        _close(g_rho, r_rho, rtol=1e-8)
        _close(g_context, r_context, rtol=1e-8)
        # The hand-written gradients learning runs with are the same.
        (h_params, h_context), h_rho = learning.learning_gradients(
            (params, jnp.asarray(context_logit)),
            jnp.asarray(rho),
            jnp.asarray(inputs),
            jnp.asarray(valid),
            noise,
        )
        for name in Params._fields:
            _close(getattr(h_params, name), r_params[name], rtol=1e-8)
        _close(h_rho, r_rho, rtol=1e-8)
        _close(h_context, r_context, rtol=1e-8)

        # Finite differences on a few coordinates of each kind.
        eps = 1e-6

        def total(p=params, r=rho, c=context_logit):
            return float(error_fn((p, jnp.asarray(c)), jnp.asarray(r), inputs, valid, noise))

        for index in [(0, 3, 1), (1, 5, 2), (1, 7, 0)]:
            plus, minus = rho.copy(), rho.copy()
            plus[index] += eps
            minus[index] -= eps
            numeric = (total(r=plus) - total(r=minus)) / (2 * eps)
            assert numeric == pytest.approx(float(r_rho[index]), rel=1e-5, abs=1e-10)
        w = np.asarray(params.w_in)
        for index in [(0, 0), (NET.io_size + 1, 3), (w.shape[0] - 1, 6)]:
            plus, minus = w.copy(), w.copy()
            plus[index] += eps
            minus[index] -= eps
            numeric = (
                total(p=params._replace(w_in=jnp.asarray(plus)))
                - total(p=params._replace(w_in=jnp.asarray(minus)))
            ) / (2 * eps)
            assert numeric == pytest.approx(float(r_params["w_in"][index]), rel=1e-5)


def _window_state(rng, length, n, unseen):
    sensory = rng.uniform(0.1, 0.9, (length, NET.sensory_size))
    seen = np.ones((length, NET.sensory_size), bool)
    for t, j in unseen:
        seen[t, j] = False
    sensory[~seen] = 0.0
    sensory[n:] = 0.0
    seen[n:] = False
    return OnlineState(
        sensory=jnp.asarray(sensory),
        seen=jnp.asarray(seen),
        motor_sent=jnp.asarray(rng.uniform(0.2, 0.8, (length, NET.motor_size))),
        n=jnp.asarray(n),
        rho=jnp.zeros((length, NET.pb_size)),
        rho_velocity=jnp.zeros((length, NET.pb_size)),
        onset_context=jnp.zeros(NET.context_size),
        onset_motor=jnp.zeros(NET.motor_size),
        next_onset_context=jnp.zeros(NET.context_size),
        next_onset_motor=jnp.zeros(NET.motor_size),
        predicted_sensory=jnp.zeros(NET.sensory_size),
    )


@pytest.mark.parametrize("motor_input", ["closed_loop", "recorded"])
@pytest.mark.parametrize("n", [6, 10])
def test_window_gradients_match_numpy_reference_and_finite_differences(motor_input, n):
    with jax.enable_x64(True):
        rng = np.random.default_rng(2)
        params = _params64(2)
        length = 10
        state = _window_state(rng, length, n, unseen=[(2, 0), (2, 1), (4, 3)])
        config = OnlineConfig(window=length).with_tuning(motor_input=motor_input)
        rho = rng.normal(0, 1, (length, NET.pb_size))
        context = rng.normal(0, 1, NET.context_size)
        motor = rng.normal(0, 1, NET.motor_size)

        error_fn = jax.jit(window.squared_error, static_argnames="config")
        g_rho, g_context, g_motor = jax.grad(window.squared_error, argnums=(2, 3, 4))(
            params, state, jnp.asarray(rho), jnp.asarray(context), jnp.asarray(motor), config
        )
        recorded = np.asarray(state.motor_sent) if motor_input == "recorded" else None
        error, r_rho, r_context, r_motor, predictions, contexts = (
            reference.window_error_and_gradients(
                params,
                np.asarray(state.sensory),
                np.asarray(state.seen),
                n,
                rho,
                context,
                motor,
                recorded,
            )
        )
        assert float(error_fn(params, state, rho, context, motor, config)) == pytest.approx(
            error, rel=1e-12
        )
        _close(g_rho, r_rho, rtol=1e-8)
        _close(g_context, r_context, rtol=1e-8)
        _close(g_motor, r_motor, rtol=1e-8)
        assert np.abs(r_rho[:n]).max() > 1e-6  # the comparison is not of zeros
        # The hand-written back-propagation the on-line step uses agrees too.
        m_rho, m_context, m_motor = window.gradients(
            params, state, jnp.asarray(rho), jnp.asarray(context), jnp.asarray(motor), config
        )
        _close(m_rho, r_rho, rtol=1e-8)
        _close(m_context, r_context, rtol=1e-8)
        _close(m_motor, r_motor, rtol=1e-8)

        # The fast window run equals the plain mixed loop of network.py.
        fast_predictions, fast_contexts = window.run(
            params, state, jnp.asarray(rho), jnp.asarray(context), jnp.asarray(motor), config
        )
        valid = np.arange(length) < n
        plain_predictions, plain_contexts = mixed_loop(
            params,
            jax.nn.sigmoid(context),
            jax.nn.sigmoid(motor),
            state.sensory,
            jax.nn.sigmoid(rho),
            state.seen & valid[:, None],
            motor_inputs=state.motor_sent if motor_input == "recorded" else None,
        )
        _close(fast_predictions, plain_predictions, rtol=1e-10)
        _close(fast_contexts, plain_contexts, rtol=1e-10)
        _close(fast_predictions, predictions, rtol=1e-10)
        _close(fast_contexts, contexts, rtol=1e-10)

        eps = 1e-6
        for index in [(0, 0), (3, 2), (n - 2, 1)]:
            plus, minus = rho.copy(), rho.copy()
            plus[index] += eps
            minus[index] -= eps
            numeric = (
                float(error_fn(params, state, plus, context, motor, config))
                - float(error_fn(params, state, minus, context, motor, config))
            ) / (2 * eps)
            assert numeric == pytest.approx(float(r_rho[index]), rel=1e-5, abs=1e-10)


def test_hand_written_learning_gradients_equal_jax_with_noise_and_other_targets():
    """With input noise and targets other than the next steps (a rehearsal of the old
    network's function)."""
    with jax.enable_x64(True):
        params = _params64(3)
        rng = np.random.default_rng(3)
        n_seq, n_steps = 3, 11
        inputs = jnp.asarray(rng.uniform(0.1, 0.9, (n_seq, n_steps, NET.io_size)))
        valid = jnp.ones((n_seq, n_steps - 1), bool).at[1, 6:].set(False)
        rho = jnp.asarray(rng.normal(0, 1, (n_seq, n_steps - 1, NET.pb_size)))
        context_logit = jnp.asarray(rng.normal(0, 1, (n_seq, NET.context_size)))
        noise = jnp.asarray(rng.normal(0, 0.02, (n_seq, n_steps - 1, NET.io_size)))
        targets = jnp.asarray(rng.uniform(0.1, 0.9, (n_seq, n_steps - 1, NET.io_size)))
        args = ((params, context_logit), rho, inputs, valid, noise, targets)
        expected = jax.grad(learning.squared_error, argnums=(0, 1))(*args)
        got = learning.learning_gradients(*args)
        leaves = jax.tree_util.tree_leaves
        for a, b in zip(leaves(expected), leaves(got), strict=True):
            assert a.shape == b.shape
            _close(b, a, rtol=1e-10, atol=1e-13)
