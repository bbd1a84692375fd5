"""The learning phase's iterations in native code: the same chunk as the compiled JAX one."""

from dataclasses import replace

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from rnnpb.model import learning, native_learning
from rnnpb.model.learning import Teacher, TrainConfig, TrainingData, init_state
from rnnpb.model.network import NetworkConfig
from rnnpb.model.training import train

from .synthetic import make_sequences

NETWORK = NetworkConfig()


def _data(n_sequences: int, n_steps: int, ends: dict[int, int] | None = None) -> TrainingData:
    """Random-walk sequences; ``ends`` cuts sequence i after its step ``ends[i]`` (padded
    after it, as :func:`rnnpb.model.learning.prepare_data` pads)."""
    rng = np.random.default_rng(n_sequences * 100 + n_steps)
    walk = np.cumsum(rng.normal(0.0, 0.02, (n_sequences, n_steps, NETWORK.io_size)), axis=1)
    inputs = np.clip(walk + 0.5, 0.0, 1.0).astype(np.float32)
    valid = np.ones((n_sequences, n_steps - 1), bool)
    for i, end in (ends or {}).items():
        valid[i, end:] = False
        inputs[i, end + 1 :] = 0.5
    names = tuple(f"p{i}" for i in range(n_sequences))
    return TrainingData(inputs, valid, names, np.zeros(NETWORK.io_size), np.ones(NETWORK.io_size))


def _normal(config: TrainConfig) -> TrainConfig:
    return replace(config, iterations=0, seed=0, checkpoint_every=1).with_tuning(chunk_iterations=1)


def _both(config, data, iterations=40, pb_learning=None, teacher=None, seed=0):
    """The state after ``iterations`` of the compiled JAX chunk and of the native one, from
    the same start."""
    state = init_state(data, NETWORK, replace(config, seed=seed))
    config = _normal(config)
    reference = learning._compiled_chunk(config)
    if pb_learning is None:
        pb_learning = np.ones(data.valid.shape[0], bool)
    args = (
        jnp.asarray(data.inputs),
        jnp.asarray(data.valid),
        jnp.asarray(iterations, jnp.int32),
        jnp.asarray(pb_learning),
        teacher,
    )
    return (
        state,
        reference(state, *args),
        native_learning.NativeChunk(config, reference)(state, *args),
    )


def _assert_same_state(expected, got, tolerance: float) -> None:
    leaves = jax.tree_util.tree_leaves_with_path(expected)
    for (path, want), have in zip(leaves, jax.tree_util.tree_leaves(got), strict=True):
        name = jax.tree_util.keystr(path)
        want, have = np.asarray(want), np.asarray(have)
        assert have.shape == want.shape and have.dtype == want.dtype, name
        if np.issubdtype(want.dtype, np.integer):  # the key, the counts
            np.testing.assert_array_equal(have, want, err_msg=name)
        else:
            np.testing.assert_allclose(have, want, atol=tolerance, rtol=0, err_msg=name)


@pytest.mark.parametrize(
    ("setting", "sequences", "ends"),
    [
        ("paper", 6, {}),  # the paper's: momentum, no noise
        ("paper", 5, {1: 30, 4: 12}),  # a group of four and one, sequences of other lengths
        ("noisy", 9, {3: 20}),
        ("fast", 6, {2: 25}),  # Adam with input noise
        ("no initial contexts", 3, {}),
    ],
)
def test_the_native_chunk_is_the_jax_chunk(setting, sequences, ends):
    config = {
        "paper": TrainConfig.paper(),
        "noisy": TrainConfig.paper(input_noise=0.05),
        "fast": TrainConfig.fast(),
        "no initial contexts": TrainConfig.fast().with_tuning(learn_initial_context=False),
    }[setting]
    start, expected, got = _both(config, _data(sequences, 40, ends))
    moved = np.max(np.abs(np.asarray(expected.params.w_in) - np.asarray(start.params.w_in)))
    assert moved > 0.05  # the learning did move the weights
    # float32 sums in another order; Adam divides by the gradients' own size
    _assert_same_state(expected, got, 1e-4 if config.optimizer == "adam" else 2e-5)
    if setting == "no initial contexts":
        np.testing.assert_array_equal(
            np.asarray(got.initial_context_logit), np.asarray(start.initial_context_logit)
        )


def test_a_held_pb_keeps_its_values_and_a_teacher_sets_the_rehearsed_targets():
    data = _data(7, 36, {5: 28})
    start = init_state(data, NETWORK, TrainConfig.paper(seed=3))
    teacher = Teacher(
        start.params,
        jax.nn.sigmoid(start.initial_context_logit + 0.3),
        jnp.full((7, NETWORK.pb_size), 0.3),
        jnp.array([True, True, False, True, False, True, True]),
    )
    held = np.array([True, False, False, True, False, False, True])
    config = TrainConfig.paper(input_noise=0.03)
    _, expected, got = _both(config, data, pb_learning=~held, teacher=teacher, seed=3)
    _assert_same_state(expected, got, 2e-5)
    np.testing.assert_array_equal(np.asarray(got.rho)[held], np.asarray(start.rho)[held])
    assert np.all(np.asarray(got.rho_velocity)[held] == 0.0)
    # without the teacher the rehearsed sequences learn something else
    _, _, untaught = _both(config, data, pb_learning=~held, seed=3)
    assert np.max(np.abs(np.asarray(untaught.params.w_out) - np.asarray(got.params.w_out))) > 1e-3


def test_training_learns_the_same_with_either_chunk(monkeypatch):
    sequences = make_sequences(n_steps=30)
    limits = np.tile([-2.0, 2.0], (NETWORK.motor_size, 1))
    config = TrainConfig.paper(iterations=300, input_noise=0.02, seed=4)
    native = train(sequences, limits, NETWORK, config)
    monkeypatch.setattr(learning, "_runner", learning._compiled_chunk)
    reference = train(sequences, limits, NETWORK, config)
    for want, have in zip(reference.params, native.params, strict=True):
        np.testing.assert_allclose(np.asarray(have), np.asarray(want), atol=1e-4)
    history = np.array(native.meta["training"]["history"])
    expected = np.array(reference.meta["training"]["history"])
    np.testing.assert_allclose(history, expected, rtol=1e-3)
    assert history[-1, 1] < history[0, 1] / 2  # it learned
    # each model says which code learned it
    assert native.meta["training"]["code"].startswith("native (llvmlite ")
    assert reference.meta["training"]["code"] == "jax"


def test_a_kernel_llvm_cannot_build_falls_back_with_one_warning(monkeypatch):
    def broken(shapes):
        raise RuntimeError("no target")

    monkeypatch.setattr(native_learning, "compiled", broken)
    config = _normal(TrainConfig.paper())
    reference = learning._compiled_chunk(config)
    chunk = native_learning.NativeChunk(config, reference)
    data = _data(3, 20)
    state = init_state(data, NETWORK, config)
    args = (jnp.asarray(data.inputs), jnp.asarray(data.valid), 5, jnp.ones(3, bool))
    with pytest.warns(RuntimeWarning, match="native learning could not be built"):
        first = chunk(state, *args)
    _assert_same_state(reference(state, *args), first, 0.0)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        chunk(first, *args)  # warned once


def test_a_sequence_without_a_step_to_predict_runs_the_jax_chunk():
    data = _data(3, 20, {1: 0})
    config = _normal(TrainConfig.paper())
    reference = learning._compiled_chunk(config)
    state = init_state(data, NETWORK, config)
    args = (jnp.asarray(data.inputs), jnp.asarray(data.valid), 5, jnp.ones(3, bool))
    got = native_learning.NativeChunk(config, reference)(state, *args)
    _assert_same_state(reference(state, *args), got, 0.0)


_TINY = """define void @fill(ptr noalias %x) {
entry:
  store float 2.5, ptr %x, align 4
  ret void
}"""


def _fill_once() -> float:
    import ctypes

    from rnnpb.model._ir import build

    function, engine = build(_TINY, "fill", ctypes.CFUNCTYPE(None, ctypes.c_void_p))
    value = np.zeros(1, np.float32)
    function(value.ctypes.data)
    del engine
    return float(value[0])


def test_compiled_code_is_kept_on_disk_and_a_damaged_file_is_compiled_again(monkeypatch, tmp_path):
    monkeypatch.setenv("RNNPB_XLA_CACHE", str(tmp_path))
    assert _fill_once() == 2.5
    (kept,) = (tmp_path / "native").glob("fill-*.o")
    whole = kept.read_bytes()
    assert _fill_once() == 2.5  # loaded from the file
    kept.write_bytes(whole[: len(whole) // 2])  # cut short
    assert _fill_once() == 2.5
    assert kept.read_bytes() == whole  # compiled again and replaced
    monkeypatch.setenv("RNNPB_XLA_CACHE", "0")
    kept.unlink()
    assert _fill_once() == 2.5
    assert not list((tmp_path / "native").glob("fill-*.o"))  # turned off: nothing kept
