"""The learning phase's iterations as native code: a drop-in twin of the compiled chunk of
:func:`rnnpb.model.learning.chunk_runner` (``rnnpb bench`` times the two side by side).

One iteration — every sequence run open loop from its noisy teacher-forced inputs, the error
back-propagated through time (:func:`rnnpb.model.learning.learning_gradients`), the weights'
step (gradient descent with momentum or Adam, as optax takes it), each PB profile's step by
eqs. 1–2 and, in a consolidation, the old network's predictions as the rehearsed sequences'
targets (:class:`rnnpb.model.learning.Teacher`) — is written in LLVM's intermediate language
with 8-wide vectors (:mod:`rnnpb.model._learning_ir`, with the emitter of
:mod:`rnnpb.model._ir`) and compiled at run time by llvmlite. Sequences run four at a time, so
that each weight vector loaded serves four sequences' sums, and the weights' gradients are
summed as the errors come back, step by step.

The input noise is JAX's: each iteration's noise key is split off as the compiled chunk splits
it, and the kernel makes ``jax.random.normal``'s draws at the same places (threefry-2x32 bits,
the uniform's mantissa trick, √2 · erfinv by XLA's polynomial), so the two learn from the same
noise. The compiled JAX chunk is the reference and the fallback (llvmlite missing,
``RNNPB_NATIVE=0``, a kernel LLVM cannot build, a sequence without a step to predict);
``tests/model/test_native_learning.py`` holds the two together.

The number of sequences and their steps are the call's: one kernel, compiled per network size,
optimizer, teacher and noise, serves every set and every consolidation, and its machine code is
kept on disk (:func:`rnnpb.model._ir.build`). This module is the host side: the arrays the
kernel is called with and the learning state it gives back.
"""

from __future__ import annotations

import ctypes
import importlib
import threading
import warnings
from collections.abc import Callable
from functools import partial
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from rnnpb.model._ir import _offsets, build
from rnnpb.model._learning_ir import _SCALARS, LearningShapes, learning_ir

# --- compiling and calling ---------------------------------------------------------------

_compiled: dict[LearningShapes, tuple[Any, Any]] = {}
_compile_lock = threading.Lock()
_SIGNATURE = ctypes.CFUNCTYPE(
    None,
    ctypes.c_int64,
    ctypes.c_int64,
    ctypes.c_int64,
    ctypes.c_int64,
    ctypes.c_void_p,
    ctypes.c_void_p,
    ctypes.c_void_p,
)


def code_version() -> str:
    """What a model learned natively records as its learning's code."""
    return f"native (llvmlite {importlib.import_module('llvmlite').__version__})"


def compiled(shapes: LearningShapes) -> Any:
    """The learning kernel for ``shapes`` (:func:`learning_ir`), compiled once per process."""
    with _compile_lock:
        if shapes not in _compiled:
            _compiled[shapes] = build(learning_ir(shapes), "learn", _SIGNATURE)
        return _compiled[shapes][0]


def _pad_rows(values: np.ndarray, width: int, shift: int = 0) -> np.ndarray:
    """``values`` (..., K) placed at columns ``shift … shift + K`` of rows ``width`` wide."""
    padded = np.zeros((*values.shape[:-1], width), np.float32)
    padded[..., shift : shift + values.shape[-1]] = values
    return padded


def pack_weights(params: Any, shapes: LearningShapes) -> np.ndarray:
    """Weights (a :class:`rnnpb.model.network.Params`, or a tree of its shape such as an
    optimizer's moments) in the kernel's layout (:meth:`LearningShapes.weights_parts`)."""
    io, p, hp, op = shapes.io, shapes.pb, shapes.hp, shapes.op
    w_in = np.asarray(params.w_in, np.float32)
    parts = (
        _pad_rows(np.concatenate([w_in[:io], w_in[io + p :]]), hp),
        _pad_rows(w_in[io : io + p], hp),
        _pad_rows(np.asarray(params.b_h, np.float32), hp),
        _pad_rows(np.asarray(params.w_out, np.float32), op),
        _pad_rows(np.asarray(params.b_out, np.float32), op),
    )
    return np.concatenate([np.ravel(part) for part in parts])


def unpack_weights(flat: np.ndarray, shapes: LearningShapes) -> Any:
    """:func:`pack_weights`'s inverse, as JAX arrays."""
    from rnnpb.model.network import Params

    io, p, c, h = shapes.io, shapes.pb, shapes.context, shapes.hidden
    layout = _offsets(shapes.weights_parts())

    def part(name: str, rows: int, width: int) -> np.ndarray:
        offset, size = layout[name]
        return flat[offset : offset + size].reshape(rows, width)

    w_xc = part("w_xc", io + c, shapes.hp)[:, :h]
    w_in = np.concatenate([w_xc[:io], part("w_p", p, shapes.hp)[:, :h], w_xc[io:]])
    return Params(
        w_in=jnp.asarray(w_in),
        b_h=jnp.asarray(part("b_h", 1, shapes.hp)[0, :h]),
        w_out=jnp.asarray(part("w_out", h, shapes.op)[:, : io + c]),
        b_out=jnp.asarray(part("b_out", 1, shapes.op)[0, : io + c]),
    )


@partial(jax.jit, static_argnames=("n",))
def _keys(key: jax.Array, n: int) -> tuple[jax.Array, jax.Array]:
    """The key after ``n`` iterations and each iteration's noise key (n, 2): the compiled
    chunk's ``key, noise_key = split(key)``, in its order."""

    def one(k: jax.Array, _: None) -> tuple[jax.Array, jax.Array]:
        k, noise_key = jax.random.split(k)
        return k, noise_key

    return jax.lax.scan(one, key, None, length=n)


class NativeChunk:
    """``run_chunk(state, inputs, valid, n_iterations, pb_learning, teacher=None) -> state``
    as :func:`rnnpb.model.learning.chunk_runner`'s compiled chunk runs it, by the native
    kernel; ``fallback`` (that compiled chunk) runs what the kernel cannot (a sequence with no
    step to predict, a kernel LLVM could not build)."""

    def __init__(self, config: Any, fallback: Callable[..., Any]) -> None:
        self.config = config
        self.fallback = fallback
        self._warned = False

    def runs_natively(self, state: Any, valid: Any, teacher: Any = None) -> bool:
        """Whether a chunk from ``state`` over ``valid`` runs in the kernel (every sequence has
        a step to predict and the kernel builds), rather than the fallback."""
        if not np.all(np.asarray(valid, bool).sum(axis=1) >= 1):
            return False
        try:
            compiled(self.shapes(state, teacher))
        except Exception:  # noqa: BLE001 - the call warns and falls back
            return False
        return True

    def shapes(self, state: Any, teacher: Any) -> LearningShapes:
        return LearningShapes(
            io=int(np.shape(state.params.w_out)[1] - np.shape(state.initial_context_logit)[-1]),
            pb=int(np.shape(state.rho)[-1]),
            context=int(np.shape(state.initial_context_logit)[-1]),
            hidden=int(np.shape(state.params.w_in)[1]),
            adam=self.config.optimizer == "adam",
            teacher=teacher is not None,
            noise=self.config.input_noise > 0,
        )

    def __call__(
        self,
        state: Any,
        inputs: Any,
        valid: Any,
        n_iterations: Any,
        pb_learning: Any,
        teacher: Any = None,
    ) -> Any:
        n = int(n_iterations)
        valid_np = np.asarray(valid, bool)
        if n == 0 or not np.all(valid_np.sum(axis=1) >= 1):
            return self.fallback(state, inputs, valid, n_iterations, pb_learning, teacher)
        shapes = self.shapes(state, teacher)
        try:
            kernel = compiled(shapes)
        except Exception as error:  # noqa: BLE001 - an LLVM that cannot build it: JAX runs
            if not self._warned:
                warnings.warn(
                    f"the native learning could not be built ({error}); the JAX chunk runs instead",
                    RuntimeWarning,
                    stacklevel=2,
                )
                self._warned = True
            return self.fallback(state, inputs, valid, n_iterations, pb_learning, teacher)
        config = self.config
        io, op, pp = shapes.io, shapes.op, shapes.pp
        inputs_np = np.asarray(inputs, np.float32)
        n_seq, n_steps = valid_np.shape
        adam = shapes.adam
        opt = state.opt_state[0]
        first, context_first = opt.mu if adam else opt.trace
        scalars = {
            "k_bp": config.pb.k_bp,
            "k_nb": config.pb.k_nb,
            "rate": config.pb.learning_rate,
            "momentum": config.pb.momentum,
            "learning_rate": config.learning_rate,
            "beta1": 0.9 if adam else config.momentum,  # optax.adam's b1, or sgd's momentum
            "beta2": 0.999,  # optax.adam's
            "eps": 1e-8,  # optax.adam's
            "n_valid": max(int(valid_np.sum()), 1),
            "learn_context": 1.0 if config.learn_initial_context else 0.0,
            "noise_scale": config.input_noise,
        }
        w_in = np.asarray(state.params.w_in, np.float32)
        values: dict[str, Any] = {
            "scalars": [scalars[name] for name in _SCALARS],
            "weights": pack_weights(state.params, shapes),
            "weight_first": pack_weights(first, shapes),
            "context": _pad_rows(np.asarray(state.initial_context_logit), op, io),
            "context_first": _pad_rows(np.asarray(context_first), op, io),
            "w_out_t": _pad_rows(np.asarray(state.params.w_out, np.float32).T, shapes.hp),
            "w_c_t": _pad_rows(w_in[io + shapes.pb :].T, op, io),
            "w_p_t": _pad_rows(w_in[io : io + shapes.pb].T, pp),
            "rho": _pad_rows(np.asarray(state.rho, np.float32), pp),
            "velocity": _pad_rows(np.asarray(state.rho_velocity, np.float32), pp),
            "learns": np.asarray(pb_learning, np.float32),
            "inputs": _pad_rows(inputs_np[:, :-1], op),
            "targets": _pad_rows(inputs_np[:, 1:], op),
            "mask": _pad_rows(valid_np[..., None] * np.ones(io, np.float32), op),
            "n": valid_np.sum(axis=1),
        }
        if adam:
            second, context_second = opt.nu
            values["weight_second"] = pack_weights(second, shapes)
            values["context_second"] = _pad_rows(np.asarray(context_second), op, io)
        if teacher is not None:
            values |= {
                "teacher": pack_weights(teacher.params, shapes),
                "teacher_context": _pad_rows(np.asarray(teacher.initial_context), op, io),
                "teacher_pb": _pad_rows(np.asarray(teacher.pb), pp),
                "taught": np.asarray(teacher.taught, np.float32),
            }
        arrays = {}
        for name, size in shapes.arrays(n_seq, n_steps).items():
            array = np.zeros(size, np.float32)
            if name in values:
                flat = np.ravel(np.asarray(values[name], np.float32))
                array[: flat.size] = flat
            arrays[name] = array
        table = np.array([array.ctypes.data for array in arrays.values()], np.uint64)

        key, noise_keys = _keys(state.key, n)
        noise_keys = np.ascontiguousarray(np.asarray(noise_keys, np.uint32))
        schedule = np.zeros((n, 8), np.float32)
        if adam:
            powers = jnp.arange(n, dtype=jnp.float32) + jnp.float32(int(opt.count) + 1)
            schedule[:, 0] = np.asarray(1 - jnp.float32(0.9) ** powers)
            schedule[:, 1] = np.asarray(1 - jnp.float32(0.999) ** powers)
        kernel(
            n,
            config.pb.integration_length // 2,
            n_seq,
            n_steps,
            table.ctypes.data,
            noise_keys.ctypes.data,
            schedule.ctypes.data,
        )
        return self._state(state, arrays, shapes, key, n)

    def _state(
        self,
        state: Any,
        arrays: dict[str, np.ndarray],
        shapes: LearningShapes,
        key: jax.Array,
        n: int,
    ) -> Any:
        n_seq, n_steps = np.shape(state.rho)[:2]
        io, c, pb, pp = shapes.io, shapes.context, shapes.pb, shapes.pp

        def contexts(name: str) -> jax.Array:
            return jnp.asarray(arrays[name].reshape(n_seq, shapes.op)[:, io : io + c])

        def profile(name: str) -> jax.Array:
            return jnp.asarray(arrays[name].reshape(n_seq, n_steps, pp)[..., :pb])

        first = (unpack_weights(arrays["weight_first"], shapes), contexts("context_first"))
        opt = state.opt_state[0]
        if shapes.adam:
            second = (unpack_weights(arrays["weight_second"], shapes), contexts("context_second"))
            opt = opt._replace(count=opt.count + n, mu=first, nu=second)
        else:
            opt = opt._replace(trace=first)
        return type(state)(
            unpack_weights(arrays["weights"], shapes),
            contexts("context"),
            (opt, *state.opt_state[1:]),
            profile("rho"),
            profile("velocity"),
            key,
            state.iteration + n,
        )
