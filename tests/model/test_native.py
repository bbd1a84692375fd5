"""The regression's loop in native code: the same loop as the compiled JAX one."""

from dataclasses import replace

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from rnnpb.model import MirrorSystem, NetworkConfig, OnlineConfig
from rnnpb.model import native as native_module
from rnnpb.model.meta import MetaParams
from rnnpb.model.native import NativeRegression, native_regression, prepare_block
from rnnpb.model.network import init_params
from rnnpb.model.online import OnlineState, regression
from rnnpb.model.parametric_bias import PBUpdateConfig
from rnnpb.safety import init_meta

from .synthetic import make_sequences

_jax_regression = jax.jit(regression, static_argnames=("config",))


def _start(mirror: MirrorSystem, hands: np.ndarray):
    """The state a mirror system's next step would regress from, given ``hands``, and its
    block for the kernel."""
    u = np.asarray(hands, np.float32)
    return prepare_block(
        mirror._params,
        mirror._state,
        u,
        np.isfinite(u),
        mirror.config,
        mirror._candidates,
        mirror._phase_candidates,
    )


def _assert_same_regression(kernel, params, start, block, gate, config, meta=None) -> None:
    expected = _jax_regression(params, start, gate, config, meta)
    got = kernel(block, meta)
    for name, want, have in zip(expected._fields, expected, got, strict=True):
        want = np.asarray(want)
        assert have.shape == want.shape, name
        # float32 arithmetic in another order and a sigmoid within 2e-7 of the exact one
        np.testing.assert_allclose(have, want, atol=1e-4, rtol=1e-4, err_msg=name)


@pytest.mark.parametrize(
    "setting", ["default", "paper", "recorded motor", "gated", "onset not regressed"]
)
def test_the_kernel_is_the_jax_loop_on_a_real_window(trained, setting):
    config = OnlineConfig()
    if setting == "paper":
        config = OnlineConfig.paper()
    elif setting == "recorded motor":
        config = config.with_tuning(motor_input="recorded")
    elif setting == "gated":
        config = config.with_tuning(surprise_gate=0.05)
    elif setting == "onset not regressed":
        config = config.with_tuning(optimize_onset=False)
    mirror = MirrorSystem(trained, config, native=False)
    demo = make_sequences(n_samples=1, n_steps=45, seed=3, kinds=(1,))[0]
    for u in demo.sensory[:44]:
        mirror.step(u)
    start, block = _start(mirror, demo.sensory[44])
    gate = None
    if config.surprise_gate > 0:
        gate = jnp.asarray(np.asarray(block)[0])
        assert 0 < float(gate) <= 1
    kernel = NativeRegression(mirror._params, trained.network, config)
    _assert_same_regression(kernel, mirror._params, start, block, gate, config)


@pytest.mark.parametrize("span", [1, 0])
def test_the_kernel_holds_the_safety_barrier(trained, span):
    # A random risk network: the barrier moves the PB well away from where the error alone
    # takes it.
    meta = MetaParams(*(jnp.asarray(a) for a in init_meta(trained.network.pb_size, 32, 0)))
    config = replace(OnlineConfig(), safety_guard="barrier").with_tuning(barrier_span=span)
    mirror = MirrorSystem(trained, config, native=False)
    demo = make_sequences(n_samples=1, n_steps=41, seed=4, kinds=(0,))[0]
    for u in demo.sensory[:40]:
        mirror.step(u)
    start, block = _start(mirror, demo.sensory[40])
    kernel = NativeRegression(mirror._params, trained.network, config, meta)
    assert kernel.applies(meta) and kernel.applies(None)
    gate = jnp.asarray(np.asarray(block)[0])  # the default regression is gated
    _assert_same_regression(kernel, mirror._params, start, block, gate, config, meta)
    unguarded = kernel(block, None)
    assert np.max(np.abs(kernel(block, meta).rho - unguarded.rho)) > 0.1
    _assert_same_regression(kernel, mirror._params, start, block, gate, config, None)


def test_the_kernel_pads_any_size_and_a_filling_window_with_lost_hands():
    # Sizes that are not whole 8-wide vectors, a window not yet full, hands not seen.
    network = NetworkConfig(sensory_size=3, motor_size=5, pb_size=3, hidden_size=13, context_size=6)
    params = init_params(network, jax.random.PRNGKey(4))
    params = params._replace(w_in=params.w_in * 3.0, w_out=params.w_out * 3.0)
    pb = PBUpdateConfig(learning_rate=0.3, momentum=0.8, k_bp=1.0, k_nb=0.2, integration_length=5)
    config = OnlineConfig(window=11, iterations=40).with_tuning(pb=pb)
    rng = np.random.default_rng(0)
    length, s, m, p, c = 11, 3, 5, 3, 6
    seen = rng.random((length, s)) > 0.3
    state = OnlineState(
        sensory=jnp.asarray(np.where(seen, rng.random((length, s)), 0.0), jnp.float32),
        seen=jnp.asarray(seen),
        motor_sent=jnp.asarray(rng.random((length, m)), jnp.float32),
        n=jnp.asarray(8, jnp.int32),
        rho=jnp.asarray(rng.normal(0, 1, (length, p)), jnp.float32),
        rho_velocity=jnp.asarray(rng.normal(0, 0.01, (length, p)), jnp.float32),
        onset_context=jnp.asarray(rng.normal(0, 1, c), jnp.float32),
        onset_motor=jnp.asarray(rng.normal(0, 1, m), jnp.float32),
        next_onset_context=jnp.zeros(c, jnp.float32),
        next_onset_motor=jnp.zeros(m, jnp.float32),
        predicted_sensory=jnp.full(s, 0.5, jnp.float32),
    )
    kernel = NativeRegression(params, network, config)
    block = native_module.step_block(params, state, None, config)
    _assert_same_regression(kernel, params, state, block, None, config)
    # The steps beyond the window's n stay as they were, without momentum.
    got = kernel(block)
    np.testing.assert_array_equal(got.rho[8:], np.asarray(state.rho)[8:])
    np.testing.assert_array_equal(got.velocity[8:], 0.0)


def test_sessions_regressed_together_are_each_regressed_alone(trained):
    # Five sessions at different places of a stream: a group of four and one left over.
    config = OnlineConfig()
    demo = make_sequences(n_samples=1, n_steps=60, seed=8, kinds=(2,))[0]
    mirror = MirrorSystem(trained, config, native=False)
    blocks = []
    for t, u in enumerate(demo.sensory[:59]):
        if t in (5, 18, 30, 44, 58):
            blocks.append(np.asarray(_start(mirror, demo.sensory[t + 1])[1]))
        mirror.step(u)
    kernel = NativeRegression(mirror._params, trained.network, config)
    together = kernel.many(np.stack(blocks))
    for b, block in enumerate(blocks):
        alone = kernel(block)
        for name, part, one in zip(alone._fields, together, alone, strict=True):
            # The same arithmetic to the last bit or two: the kernels of four sessions and of
            # one may contract a product and a sum into one fused operation differently.
            np.testing.assert_allclose(
                part[b], one, rtol=1e-6, atol=1e-9, err_msg=f"{name}, session {b}"
            )


def test_a_mirror_system_with_the_native_loop_steps_as_the_jax_one(trained):
    demo = make_sequences(n_samples=1, n_steps=60, seed=12, kinds=(2,))[0]
    hands = demo.sensory.copy()
    hands[20:24, :2] = np.nan  # a lost hand on the way
    fast, reference = MirrorSystem(trained), MirrorSystem(trained, native=False)
    assert fast._native is not None and reference._native is None
    for t, u in enumerate(hands):
        got, want = fast.step(u), reference.step(u)
        np.testing.assert_allclose(got.pb, want.pb, atol=1e-3, err_msg=f"step {t}")
        np.testing.assert_allclose(got.predicted_hands, want.predicted_hands, atol=1e-3)
        assert got.recognised == want.recognised, t
        assert got.held == want.held == False  # noqa: E712


def test_the_jax_step_runs_where_the_native_loop_cannot(trained, monkeypatch):
    params = MirrorSystem(trained, native=False)._params
    kernel = native_regression(params, trained.network, OnlineConfig())
    assert kernel is not None
    # A kernel holds the risk network it was built with, not another one; the projection
    # comes after the loop and runs with either.
    meta = MetaParams(
        *(jnp.asarray(a, jnp.float32) for a in init_meta(trained.network.pb_size, 8, 0))
    )
    assert kernel.applies(None)
    assert not kernel.applies(meta)
    with pytest.raises(ValueError, match="risk network"):
        kernel(np.zeros(kernel.shapes.block_layout()["total"][0], np.float32), meta)
    projection = native_regression(
        params, trained.network, replace(OnlineConfig(), safety_guard="projection")
    )
    assert projection is not None and projection.applies(meta)
    assert native_regression(params, trained.network, OnlineConfig(iterations=0)) is None

    # An LLVM that cannot build the kernel: a warning, and the JAX loop.
    def refuse(*_):
        raise RuntimeError("no target for this processor")

    monkeypatch.setattr(native_module, "compiled", refuse)
    with pytest.warns(RuntimeWarning, match="no target for this processor"):
        assert native_regression(params, trained.network, OnlineConfig(window=7)) is None
    monkeypatch.undo()
    monkeypatch.setenv("RNNPB_NATIVE", "0")
    assert native_regression(params, trained.network, OnlineConfig()) is None
    assert MirrorSystem(trained)._native is None
