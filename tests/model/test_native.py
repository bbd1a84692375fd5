"""The regression's loop in native code: the same loop as the compiled step's own."""

from dataclasses import replace

import jax
import numpy as np
import pytest

from rnnpb.model import MirrorSystem, NetworkConfig, OnlineConfig, online
from rnnpb.model import native as native_module
from rnnpb.model.meta import MetaParams
from rnnpb.model.mirror import normalized_hands
from rnnpb.model.native import NativeRegression, native_regression
from rnnpb.model.network import init_params
from rnnpb.model.online import OnlineState
from rnnpb.model.parametric_bias import PBUpdateConfig
from rnnpb.safety import init_meta

from .synthetic import make_sequences

_PARTS = ("rho", "rho_velocity", "onset_context", "onset_motor")


def _copy(state: OnlineState) -> OnlineState:
    return OnlineState(*(np.array(part) for part in state))


def _start(mirror: MirrorSystem, hands: np.ndarray) -> tuple[OnlineState, np.ndarray]:
    """The state a mirror system's next step would regress from, given ``hands``, and the
    step's gate."""
    u, seen = normalized_hands(hands, mirror.model.network.sensory_size)
    state, gates = _copy(mirror._state), np.empty(1, np.float32)
    start = online.start_arrays(state)
    online.prepare_sessions(
        mirror._net,
        state,
        u[None].astype(np.float32),
        seen[None],
        mirror._candidates,
        mirror._phase_candidates,
        mirror._settings,
        gates,
        start,
    )
    return state, gates


def _both(mirror, kernel, state, gates, guarded=False) -> tuple[OnlineState, OnlineState]:
    """The regression from ``state`` by the step's own loop and by the native kernel."""
    flags = np.full(len(gates), guarded)
    expected, got = _copy(state), _copy(state)
    online.regress_sessions(mirror._net, mirror._meta, expected, gates, flags, mirror._settings)
    layout, blocks = kernel.block_layout(), kernel.blocks(len(gates))
    barrier = flags & (mirror._settings.guard == 1)
    online.fill_blocks(mirror._net, got, gates, barrier, mirror._settings, layout, blocks)
    kernel.run(blocks)
    online.take_blocks(got, layout, blocks)
    return expected, got


def _assert_same(expected: OnlineState, got: OnlineState, tolerance: float = 1e-4) -> None:
    for name in _PARTS:
        # float32 arithmetic in another order
        np.testing.assert_allclose(
            getattr(got, name), getattr(expected, name), atol=tolerance, rtol=1e-4, err_msg=name
        )


@pytest.mark.parametrize(
    "setting", ["default", "paper", "recorded motor", "gated", "onset not regressed"]
)
def test_the_kernel_is_the_step_s_own_loop_on_a_real_window(trained, setting):
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
    state, gates = _start(mirror, demo.sensory[44])
    if config.surprise_gate > 0:
        assert 0 < float(gates[0]) <= 1
    kernel = NativeRegression(trained.params, trained.network, config)
    expected, got = _both(mirror, kernel, state, gates)
    _assert_same(expected, got)
    assert np.max(np.abs(got.rho - state.rho)) > 1e-3  # the regression moved the PB


@pytest.mark.parametrize("span", [1, 0])
def test_the_kernel_holds_the_safety_barrier(trained, span):
    # A random risk network: the barrier moves the PB well away from where the error alone
    # takes it.
    meta = MetaParams(*init_meta(trained.network.pb_size, 32, 0))
    config = replace(OnlineConfig(), safety_guard="barrier").with_tuning(barrier_span=span)
    mirror = MirrorSystem(trained, config, meta=meta, native=False)
    demo = make_sequences(n_samples=1, n_steps=41, seed=4, kinds=(0,))[0]
    for u in demo.sensory[:40]:
        mirror.step(u)
    state, gates = _start(mirror, demo.sensory[40])
    kernel = NativeRegression(trained.params, trained.network, config, meta)
    assert kernel.applies(meta) and kernel.applies(None)
    guarded = _both(mirror, kernel, state, gates, guarded=True)
    _assert_same(*guarded)
    unguarded = _both(mirror, kernel, state, gates, guarded=False)
    _assert_same(*unguarded)
    assert np.max(np.abs(guarded[1].rho - unguarded[1].rho)) > 0.1


def test_the_kernel_pads_any_size_and_a_filling_window_with_lost_hands(trained):
    # Sizes that are not whole 8-wide vectors, a window not yet full, hands not seen.
    network = NetworkConfig(sensory_size=3, motor_size=5, pb_size=3, hidden_size=13, context_size=6)
    params = init_params(network, jax.random.PRNGKey(4))
    params = params._replace(w_in=params.w_in * 3.0, w_out=params.w_out * 3.0)
    pb = PBUpdateConfig(learning_rate=0.3, momentum=0.8, k_bp=1.0, k_nb=0.2, integration_length=5)
    config = OnlineConfig(window=11, iterations=40).with_tuning(pb=pb)
    rng = np.random.default_rng(0)
    length, s, m, p, c = 11, 3, 5, 3, 6
    seen = rng.random((1, length, s)) > 0.3

    def values(*shape: int, scale: float = 1.0) -> np.ndarray:
        return (scale * rng.normal(0, 1, shape)).astype(np.float32)

    state = OnlineState(
        sensory=np.where(seen, rng.random((1, length, s)), 0.0).astype(np.float32),
        seen=seen,
        motor_sent=rng.random((1, length, m)).astype(np.float32),
        n=np.array([8]),
        rho=values(1, length, p),
        rho_velocity=values(1, length, p, scale=0.01),
        onset_context=values(1, c),
        onset_motor=values(1, m),
        next_onset_context=np.zeros((1, c), np.float32),
        next_onset_motor=np.zeros((1, m), np.float32),
        predicted_sensory=np.full((1, s), 0.5, np.float32),
    )

    class Odd:  # what _both reads of a mirror system, for this network
        _net = online.network_arrays(params, s, m, np.float32)
        _meta = online.meta_arrays(None, p, np.float32)
        _settings = online.settings_for(config, np.float32, 12)

    kernel = NativeRegression(params, network, config)
    expected, got = _both(Odd, kernel, state, np.ones(1, np.float32))
    _assert_same(expected, got)
    # The steps beyond the window's n stay as they were, without momentum.
    np.testing.assert_array_equal(got.rho[0, 8:], state.rho[0, 8:])
    np.testing.assert_array_equal(got.rho_velocity[0, 8:], 0.0)


def test_sessions_regressed_together_are_each_regressed_alone(trained):
    # Five sessions at different places of a stream: a group of four and one left over.
    config = OnlineConfig()
    demo = make_sequences(n_samples=1, n_steps=60, seed=8, kinds=(2,))[0]
    mirror = MirrorSystem(trained, config, native=False)
    starts = []
    for t, u in enumerate(demo.sensory[:59]):
        if t in (5, 18, 30, 44, 58):
            starts.append(_start(mirror, demo.sensory[t + 1]))
        mirror.step(u)
    together = OnlineState(
        *(np.concatenate(parts) for parts in zip(*(s for s, _ in starts), strict=True))
    )
    gates = np.concatenate([g for _, g in starts])
    kernel = NativeRegression(trained.params, trained.network, config)
    _, grouped = _both(mirror, kernel, together, gates)
    for b, (state, gate) in enumerate(starts):
        _, alone = _both(mirror, kernel, state, gate)
        for name in _PARTS:
            # The same arithmetic in another order: a session alone sums each product in two
            # chains (even and odd inputs), four sessions together in one.
            np.testing.assert_allclose(
                getattr(grouped, name)[b],
                getattr(alone, name)[0],
                rtol=1e-5,
                atol=1e-5,
                err_msg=f"{name}, session {b}",
            )


def test_a_mirror_system_with_the_native_loop_steps_as_without(trained):
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


def test_the_step_s_own_loop_runs_where_the_native_loop_cannot(trained, monkeypatch):
    kernel = native_regression(trained.params, trained.network, OnlineConfig())
    assert kernel is not None
    # A kernel holds the risk network it was built with, not another one; the projection
    # comes after the loop and runs with either.
    meta = MetaParams(*init_meta(trained.network.pb_size, 8, 0))
    assert kernel.applies(None)
    assert not kernel.applies(meta)
    blocks = kernel.blocks(1)
    blocks[0, 2] = 1.0  # the barrier asked for
    with pytest.raises(ValueError, match="risk network"):
        kernel.run(blocks)
    projection = native_regression(
        trained.params, trained.network, replace(OnlineConfig(), safety_guard="projection")
    )
    assert projection is not None and projection.applies(meta)
    assert native_regression(trained.params, trained.network, OnlineConfig(iterations=0)) is None
    assert MirrorSystem(trained)._native is not None

    # An LLVM that cannot build the kernel: a warning, and the step's own loop.
    def refuse(*_):
        raise RuntimeError("no target for this processor")

    monkeypatch.setattr(native_module, "compiled", refuse)
    with pytest.warns(RuntimeWarning, match="no target for this processor"):
        assert native_regression(trained.params, trained.network, OnlineConfig(window=7)) is None
    monkeypatch.undo()
    monkeypatch.setenv("RNNPB_NATIVE", "0")
    assert native_regression(trained.params, trained.network, OnlineConfig()) is None
    assert MirrorSystem(trained)._native is None
