"""The hand-written gradients equal jax.grad and finite differences, in float64.

Learning's (rnnpb.model.learning) to jax.grad within 1e-8 relative (both exact up to rounding);
the kernels' window (rnnpb.model.equations) to jax.grad of the JAX network's within 1e-4 (their
sigmoid is within 2e-7 of the exact one); both to central finite differences with steps of
1e-6.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from rnnpb.model import NetworkConfig, equations, init_params, learning, online
from rnnpb.model.network import Params, mixed_loop

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


def test_learning_gradients_match_jax_and_finite_differences():
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
        # The hand-written gradients learning runs with equal jax.grad's.
        (h_params, h_context), h_rho = learning.learning_gradients(
            (params, jnp.asarray(context_logit)),
            jnp.asarray(rho),
            jnp.asarray(inputs),
            jnp.asarray(valid),
            noise,
        )
        for name in Params._fields:
            _close(getattr(h_params, name), getattr(g_params, name), rtol=1e-8)
        _close(h_rho, g_rho, rtol=1e-8)
        _close(h_context, g_context, rtol=1e-8)
        r_rho, r_params = (
            np.asarray(g_rho),
            {k: np.asarray(v) for k, v in g_params._asdict().items()},
        )

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


def _window(rng, length, n, unseen):
    sensory = rng.uniform(0.1, 0.9, (length, NET.sensory_size))
    seen = np.ones((length, NET.sensory_size), bool)
    for t, j in unseen:
        seen[t, j] = False
    sensory[~seen] = 0.0
    sensory[n:] = 0.0
    seen[n:] = False
    return sensory, seen, rng.uniform(0.2, 0.8, (length, NET.motor_size))


def _kernel_window(params, sensory, seen, motor_sent, n, rho, context, motor, recorded):
    """The kernels' window (rnnpb.model.equations) in float64: the error, its gradients with
    respect to rho, the onset context and motor logits, and the predictions."""
    s, m = NET.sensory_size, NET.motor_size
    net = online.network_arrays(params, s, m, np.float64)
    length = len(sensory)
    fixed, mask, target, target_mask = online._windows(
        net, sensory, seen, motor_sent, n, recorded, 1
    )
    hidden, outputs = online._run(net, fixed, mask, rho[None], context[None], motor[None], length)
    total, _ = equations.prediction_error(outputs, target, target_mask, 0, 0)
    d_pre, d_input = np.empty_like(hidden), np.empty((1, outputs.shape[2]))
    equations.window_backward(
        net, hidden, outputs, mask, target, target_mask, length, d_pre, d_input, d_input.copy()
    )
    d_rho = np.empty_like(rho)
    equations.pb_gradient(net, d_pre, rho, length, 0, d_rho)
    first = np.concatenate([np.full(s, 0.5), 1 / (1 + np.exp(-motor)), 1 / (1 + np.exp(-context))])
    d_first = d_input[0] * first * (1 - first)
    return 0.5 * total, d_rho, d_first[s + m :], d_first[s : s + m], outputs[:, 0]


@pytest.mark.parametrize("motor_input", ["closed_loop", "recorded"])
@pytest.mark.parametrize("n", [6, 10])
def test_window_gradients_match_jax_and_finite_differences(motor_input, n):
    """The kernels' window pass and hand-written back-propagation equal the JAX network's
    mixed loop and jax.grad of its error (to the kernels' sigmoid, within 2e-7 of the exact
    one), and central finite differences of the kernels' own error."""
    rng = np.random.default_rng(2)
    with jax.enable_x64(True):
        params = Params(*(np.asarray(a) for a in _params64(2)))
    length = 10
    recorded = motor_input == "recorded"
    sensory, seen, motor_sent = _window(rng, length, n, unseen=[(2, 0), (2, 1), (4, 3)])
    rho = rng.normal(0, 1, (length, NET.pb_size))
    context = rng.normal(0, 1, NET.context_size)
    motor = rng.normal(0, 1, NET.motor_size)
    error, d_rho, d_context, d_motor, outputs = _kernel_window(
        params, sensory, seen, motor_sent, n, rho, context, motor, recorded
    )
    assert np.abs(d_rho[:n]).max() > 1e-6  # the comparison is not of zeros
    valid = np.arange(length) < n
    targets = (np.arange(length - 1) < n - 1)[:, None] & seen[1:]

    def jax_error(rho, context, motor):
        predictions, contexts = mixed_loop(
            params,
            jax.nn.sigmoid(context),
            jax.nn.sigmoid(motor),
            jnp.asarray(sensory),
            jax.nn.sigmoid(rho),
            jnp.asarray(seen & valid[:, None]),
            motor_inputs=jnp.asarray(motor_sent) if recorded else None,
        )
        errors = jnp.where(targets, predictions[:-1, : NET.sensory_size] - sensory[1:], 0.0)
        return 0.5 * jnp.sum(errors**2), (predictions, contexts)

    with jax.enable_x64(True):
        (want, (predictions, contexts)), grads = jax.value_and_grad(
            jax_error, argnums=(0, 1, 2), has_aux=True
        )(jnp.asarray(rho), jnp.asarray(context), jnp.asarray(motor))
    io = NET.io_size
    _close(outputs[:, :io], predictions, rtol=1e-5, atol=1e-6)
    _close(outputs[:, io:], contexts, rtol=1e-5, atol=1e-6)
    assert error == pytest.approx(float(want), rel=1e-5)
    for have, expected in zip((d_rho, d_context, d_motor), grads, strict=True):
        _close(have, expected, rtol=1e-5, atol=1e-8)

    eps = 1e-6
    for index in [(0, 0), (3, 2), (n - 2, 1)]:
        plus, minus = rho.copy(), rho.copy()
        plus[index] += eps
        minus[index] -= eps
        numeric = (
            _kernel_window(params, sensory, seen, motor_sent, n, plus, context, motor, recorded)[0]
            - _kernel_window(params, sensory, seen, motor_sent, n, minus, context, motor, recorded)[
                0
            ]
        ) / (2 * eps)
        assert numeric == pytest.approx(float(d_rho[index]), rel=1e-6, abs=1e-10)


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
