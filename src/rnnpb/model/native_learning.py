"""The learning phase's iterations as native code: a drop-in twin of the compiled chunk of
:func:`rnnpb.model.learning.chunk_runner` (``rnnpb bench`` times the two side by side).

One iteration — every sequence run open loop from its noisy teacher-forced inputs, the error
back-propagated through time (:func:`rnnpb.model.learning.learning_gradients`), the weights'
step (gradient descent with momentum or Adam, as optax takes it), each PB profile's step by
eqs. 1–2 and, in a consolidation, the old network's predictions as the rehearsed sequences'
targets (:class:`rnnpb.model.learning.Teacher`) — is written in LLVM's intermediate language
with 8-wide vectors (the emitter of :mod:`rnnpb.model.native`) and compiled at run time by
llvmlite. Sequences run four at a time, so that each weight vector loaded serves four
sequences' sums, and the weights' gradients are summed as the errors come back, step by step.

The input noise is JAX's: each iteration's noise key is split off as the compiled chunk splits
it, and the kernel makes ``jax.random.normal``'s draws at the same places (threefry-2x32 bits,
the uniform's mantissa trick, √2 · erfinv by XLA's polynomial), so the two learn from the same
noise. The compiled JAX chunk is the reference and the fallback (llvmlite missing,
``RNNPB_NATIVE=0``, a kernel LLVM cannot build, a sequence without a step to predict);
``tests/model/test_native_learning.py`` holds the two together.

The number of sequences and their steps are the call's: one kernel, compiled per network size,
optimizer, teacher and noise, serves every set and every consolidation, and its machine code is
kept on disk (:func:`rnnpb.model.native.build`).

Layouts (float32, rows padded to whole 8-wide vectors): a step's inputs and outputs with the
context share one row of ``OP`` values — the inputs (or predictions) first, then the context —
so the context an output row holds is where the next input row wants it.
"""

from __future__ import annotations

import ctypes
import importlib
import threading
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from rnnpb.model.native import (
    V,
    _Emitter,
    _offsets,
    _padded,
    _pb_update,
    _vector_constant,
    build,
    module,
)

GROUP = 4  # sequences that share each loaded weight vector


@dataclass(frozen=True)
class LearningShapes:
    """What a learning kernel is compiled for: I inputs, P PB units, C context units, H hidden
    units, the optimizer, whether a teacher gives some sequences their targets and whether
    the inputs are noisy. The number of sequences and their steps are the call's."""

    io: int
    pb: int
    context: int
    hidden: int
    adam: bool
    teacher: bool
    noise: bool

    @property
    def op(self) -> int:
        """A row of inputs (or outputs) with the context, padded."""
        return _padded(self.io + self.context)

    @property
    def hp(self) -> int:
        return _padded(self.hidden)

    @property
    def pp(self) -> int:
        return _padded(self.pb)

    def weights_parts(self) -> dict[str, int]:
        """The weights, in the order the optimizer walks them: the inputs' and the context's
        weights to the hidden layer (rows: inputs, then context), the PB's, the hidden bias,
        the output weights and bias."""
        return {
            "w_xc": (self.io + self.context) * self.hp,
            "w_p": self.pb * self.hp,
            "b_h": self.hp,
            "w_out": self.hidden * self.op,
            "b_out": self.op,
        }

    @property
    def weights_size(self) -> int:
        return _offsets(self.weights_parts())["total"][0]

    def arrays(self, sequences: int, steps: int) -> dict[str, int]:
        """The kernel's arrays and their sizes (float32 values) for S sequences of N steps,
        in the order of the pointer table it is called with."""
        s, n, op, hp, pp = sequences, steps, self.op, self.hp, self.pp
        weights = self.weights_size
        arrays = {
            "scalars": 16,
            "weights": weights,
            "weight_grads": weights,
            "weight_first": weights,  # momentum's trace, or Adam's mu
            "weight_second": weights,  # Adam's nu
            "context": s * op,  # each sequence's initial context's logits, context columns
            "context_grads": s * op,
            "context_first": s * op,
            "context_second": s * op,
            "w_out_t": (self.io + self.context) * hp,
            "w_c_t": self.hidden * op,
            "w_p_t": self.hidden * pp,
            "rho": s * n * pp,
            "velocity": s * n * pp,
            "learns": s,  # 1 where the sequence's PB profile learns
            "inputs": s * n * op,  # the teacher-forced inputs x_0 … x_{N-1}
            "targets": s * n * op,  # the next steps x_1 … x_N
            "mask": s * n * op,  # 1 on a valid step's predictions
            "n": s,  # each sequence's valid steps
        }
        if self.teacher:
            arrays |= {
                "teacher": weights,
                "teacher_context": s * op,  # in (0, 1), in the context columns
                "teacher_pb": s * pp,
                "taught": s,
            }
        for g in range(GROUP):  # each of a group's sequences has its own
            arrays |= {f"{name}{g}": size for name, size in self.scratch_parts(n).items()}
        return arrays

    def scratch_parts(self, steps: int) -> dict[str, int]:
        """One sequence's working arrays in a group, for sequences of ``steps`` steps."""
        n, op, hp, pp = steps, self.op, self.hp, self.pp
        return {
            "z": n * op,  # each step's inputs with the context
            "pb": n * pp,
            "hid": n * hp,
            "out": n * op,
            "teacher_out": n * op,
            "noise": n * op,  # each step's input noise
            "teacher_z": op,
            "teacher_hid": hp,
            "first": op,
            "d_out": op,
            "dh": hp,
            "grad": n * pp,
            "cum": (n + 1) * pp,
            "rnew": n * pp,
        }


I32 = "<8 x i32>"
_LOG_P = (
    7.0376836292e-2,
    -1.1514610310e-1,
    1.1676998740e-1,
    -1.2420140846e-1,
    1.4249322787e-1,
    -1.6668057665e-1,
    2.0000714765e-1,
    -2.4999993993e-1,
    3.3333331174e-1,
)
# erfinv(x) ~ x · P(w), w = -log1p(-x²) (M. Giles's single-precision form, as XLA has it)
_ERFINV_SMALL = (
    2.81022636e-08,
    3.43273939e-07,
    -3.5233877e-06,
    -4.39150654e-06,
    0.00021858087,
    -0.00125372503,
    -0.00417768164,
    0.246640727,
    1.50140941,
)
_ERFINV_LARGE = (
    -0.000200214257,
    0.000100950558,
    0.00134934322,
    -0.00367342844,
    0.00573950773,
    -0.0076224613,
    0.00943887047,
    1.00167406,
    2.83297682,
)


def _int_vector(value: int) -> str:
    return "<" + ", ".join([f"i32 {value}"] * 8) + ">"


def _broadcast_int(e: _Emitter, scalar: str) -> str:
    first = e.op("b", f"insertelement {I32} undef, i32 {scalar}, i32 0")
    return e.op("b", f"shufflevector {I32} {first}, {I32} undef, <8 x i32> zeroinitializer")


def _int(e: _Emitter, operation: str, a: str, b: str) -> str:
    return e.op("u", f"{operation} {I32} {a}, {b}")


def _log(e: _Emitter, x: str) -> str:
    """The natural logarithm of positive ``x`` (Cephes' logf, within about 1 ulp)."""
    bits = e.op("u", f"bitcast {V} {x} to {I32}")
    exponent = _int(e, "sub", _int(e, "lshr", bits, _int_vector(23)), _int_vector(126))
    mantissa = _int(e, "or", _int(e, "and", bits, _int_vector(0x807FFFFF)), _int_vector(0x3F000000))
    m = e.op("u", f"bitcast {I32} {mantissa} to {V}")  # in [0.5, 1)
    small = e.op("u", f"fcmp fast olt {V} {m}, {_vector_constant(0.707106781186547524)}")
    lower = _int(e, "sub", exponent, _int_vector(1))
    exponent = e.op("u", f"select <8 x i1> {small}, {I32} {lower}, {I32} {exponent}")
    shifted = e.fsub(e.fadd(m, m), _vector_constant(1.0))
    x = e.op("u", f"select <8 x i1> {small}, {V} {shifted}, {V} {e.fsub(m, _vector_constant(1.0))}")
    power = e.op("u", f"sitofp {I32} {exponent} to {V}")
    z = e.fmul(x, x)
    y = _vector_constant(_LOG_P[0])
    for c in _LOG_P[1:]:
        y = e.fma(y, x, _vector_constant(c))
    y = e.fmul(e.fmul(y, x), z)
    y = e.fma(power, _vector_constant(-2.12194440e-4), y)
    y = e.fma(z, _vector_constant(-0.5), y)
    return e.fma(power, _vector_constant(0.693359375), e.fadd(x, y))


def _erfinv(e: _Emitter, x: str) -> str:
    """The inverse error function of ``x`` in (-1, 1)."""
    y = e.fmul(x, e.fsub("zeroinitializer", x))  # -x²: log1p(y) = log(1 + y) · y / ((1 + y) - 1)
    u = e.fadd(_vector_constant(1.0), y)
    d = e.fsub(u, _vector_constant(1.0))
    exact = e.op("u", f"fcmp fast oeq {V} {d}, zeroinitializer")
    scaled = e.fmul(_log(e, u), e.op("d", f"fdiv fast {V} {y}, {d}"))
    w = e.fsub("zeroinitializer", e.op("u", f"select <8 x i1> {exact}, {V} {y}, {V} {scaled}"))
    small = e.op("u", f"fcmp fast olt {V} {w}, {_vector_constant(5.0)}")
    root = e.op("r", f"call fast {V} @llvm.sqrt.v8f32({V} {w})")
    w = e.op(
        "u",
        f"select <8 x i1> {small}, {V} {e.fsub(w, _vector_constant(2.5))}, "
        f"{V} {e.fsub(root, _vector_constant(3.0))}",
    )

    def coefficient(i: int) -> str:
        return e.op(
            "u",
            f"select <8 x i1> {small}, {V} {_vector_constant(_ERFINV_SMALL[i])}, "
            f"{V} {_vector_constant(_ERFINV_LARGE[i])}",
        )

    p = coefficient(0)
    for i in range(1, len(_ERFINV_SMALL)):
        p = e.fma(p, w, coefficient(i))
    return e.fmul(p, x)


def _threefry(e: _Emitter, key: tuple[str, str], counts: str) -> str:
    """JAX's 32 random bits at ``counts`` (its flat indices) for ``key``: threefry-2x32 of
    (0, count), its two words xor-ed."""
    k1, k2 = key
    k3 = _int(e, "xor", _int(e, "xor", k1, k2), _int_vector(0x1BD11BDA))
    ks = [k1, k2, k3]
    rotations = ((13, 15, 26, 6), (17, 29, 16, 24))
    x0, x1 = k1, _int(e, "add", counts, k2)
    for block in range(5):
        for r in rotations[block % 2]:
            x0 = _int(e, "add", x0, x1)
            x1 = e.op(
                "u", f"call {I32} @llvm.fshl.v8i32({I32} {x1}, {I32} {x1}, {I32} {_int_vector(r)})"
            )
            x1 = _int(e, "xor", x0, x1)
        x0 = _int(e, "add", x0, ks[(block + 1) % 3])
        x1 = _int(e, "add", x1, _int(e, "add", ks[(block + 2) % 3], _int_vector(block + 1)))
    return _int(e, "xor", x0, x1)


def _normal(e: _Emitter, key: tuple[str, str], counts: str) -> str:
    """``jax.random.normal(key, shape)`` at the flat indices ``counts``: uniform bits in
    [-1, 1), then √2 · erfinv."""
    bits = _threefry(e, key, counts)
    mantissa = _int(e, "or", _int(e, "lshr", bits, _int_vector(9)), _int_vector(0x3F800000))
    floats = e.fsub(e.op("u", f"bitcast {I32} {mantissa} to {V}"), _vector_constant(1.0))
    low = _vector_constant(-0.99999994)
    u = e.fma(floats, _vector_constant(2.0), low)
    u = e.op("c", f"call fast {V} @llvm.maxnum.v8f32({V} {u}, {V} {low})")
    return e.fmul(_erfinv(e, u), _vector_constant(1.4142135))


def learning_ir(shapes: LearningShapes) -> str:
    """The kernel ``learn(iterations, half, sequences, steps, table, keys, schedule)``:
    ``iterations`` learning iterations of ``sequences`` sequences of ``steps`` prediction
    steps, in place on the arrays whose addresses ``table`` holds, in the order of
    :meth:`LearningShapes.arrays`. ``keys`` holds each iteration's noise key (two 32-bit
    words), ``schedule`` eight values per iteration (Adam's bias corrections); ``half``: the
    PB integration length's half."""
    e = _Emitter()
    io, p, c, h = shapes.io, shapes.pb, shapes.context, shapes.hidden
    op, hp, pp = shapes.op, shapes.hp, shapes.pp
    ov, hv, pv = op // 8, hp // 8, pp // 8
    zero = "zeroinitializer"
    rows = io + c
    ptr = {}
    for index, name in enumerate(shapes.arrays(1, 1)):
        slot = e.op("p", f"getelementptr inbounds ptr, ptr %table, i64 {index}")
        ptr[name] = e.op("t", f"load ptr, ptr {slot}, align 8")

    def parts(base: str, layout: dict[str, tuple[int, int]]) -> dict[str, str]:
        return {
            key: e.address(base, offset) for key, (offset, _) in layout.items() if key != "total"
        }

    weights_layout = _offsets(shapes.weights_parts())
    student = parts(ptr["weights"], weights_layout) | {"context": ptr["context"]}
    grads = parts(ptr["weight_grads"], weights_layout) | {"context": ptr["context_grads"]}
    teacher = parts(ptr["teacher"], weights_layout) if shapes.teacher else {}
    scalar = {
        name: e.broadcast(e.load_scalar(ptr["scalars"], i)) for i, name in enumerate(_SCALARS)
    }
    coefficient = {k: scalar[k] for k in ("k_bp", "k_nb", "rate", "momentum")}

    def lane_mask(low: int, high: int, v: int) -> str:
        values = [f"float {'1.0' if low <= 8 * v + lane < high else '0.0'}" for lane in range(8)]
        return "<" + ", ".join(values) + ">"

    context_mask = [lane_mask(io, rows, v) for v in range(ov)]
    input_mask = [lane_mask(0, io, v) for v in range(ov)]
    scratch = [{name: ptr[f"{name}{g}"] for name in shapes.scratch_parts(1)} for g in range(GROUP)]
    sequence_row = e.int_op("q", "mul", "%steps", op)  # one sequence's rows of OP values
    sequence_pbs = e.int_op("q", "mul", "%steps", pp)
    sequence_inputs = e.int_op("q", "mul", "%steps", io)

    def row(t: str, width: int, v: int = 0) -> str:
        return e.int_op("o", "add", e.int_op("o", "mul", t, width), 8 * v)

    def sequence_parts(sequence: str) -> dict[str, str]:
        """The pointers of one sequence's data and state (``sequence`` an i64 value)."""
        along = e.int_op("q", "mul", sequence, sequence_row)
        pbs = e.int_op("q", "mul", sequence, sequence_pbs)
        one = {
            "inputs": e.address(ptr["inputs"], along),
            "targets": e.address(ptr["targets"], along),
            "mask": e.address(ptr["mask"], along),
            "rho": e.address(ptr["rho"], pbs),
            "velocity": e.address(ptr["velocity"], pbs),
            "context": e.address(student["context"], e.int_op("q", "mul", sequence, op)),
            "grad_context": e.address(grads["context"], e.int_op("q", "mul", sequence, op)),
        }
        one["n"] = e.op("n", f"fptosi float {e.load_scalar(ptr['n'], sequence)} to i64")
        learns = e.load_scalar(ptr["learns"], sequence)
        one["learns"] = e.op("l", f"fcmp one float {learns}, 0.0")
        if shapes.teacher:
            one["teacher_context"] = e.address(
                ptr["teacher_context"], e.int_op("q", "mul", sequence, op)
            )
            one["teacher_pb"] = e.address(ptr["teacher_pb"], e.int_op("q", "mul", sequence, pp))
            taught = e.load_scalar(ptr["taught"], sequence)
            one["taught"] = e.op("l", f"fcmp one float {taught}, 0.0")
        return one

    def forward(
        weights: dict[str, str],
        seqs: list[dict[str, str]],
        scr: list[dict[str, str]],
        count: str,
        own: bool,
    ) -> None:
        """The open-loop run of ``count`` steps: ``own`` the student's (every step's inputs,
        PBs, hidden and outputs kept for the backward pass), else the teacher's (its outputs
        into ``teacher_out``)."""
        group = range(len(seqs))
        z_name, hid_name, out_name = (
            ("z", "hid", "out") if own else ("teacher_z", "teacher_hid", "teacher_out")
        )
        for g in group:  # the first step's context
            for v in range(ov):
                if own:
                    logits = e.load(seqs[g]["context"], 8 * v)
                    value = e.fmul(e.sigmoid(logits), context_mask[v])
                else:
                    value = e.load(seqs[g]["teacher_context"], 8 * v)
                e.store(value, scr[g]["first"], 8 * v)

        def step(t: str, _: list[str]) -> list[str]:
            first_step = e.op("z", f"icmp eq i64 {t}, 0")
            previous = e.int_op("y", "mul", e.int_op("y", "sub", t, 1), op)
            previous = e.op("y", f"select i1 {first_step}, i64 0, i64 {previous}")
            z_row = row(t, op) if own else "0"
            for g in group:
                source = e.op(
                    "y", f"select i1 {first_step}, ptr {scr[g]['first']}, ptr {scr[g][out_name]}"
                )
                for v in range(ov):
                    index = row(t, op, v)
                    x = e.load(seqs[g]["inputs"], index)
                    if shapes.noise:
                        x = e.fadd(x, e.load(scr[g]["noise"], index))
                    carried = e.load(source, e.int_op("y", "add", previous, 8 * v))
                    z = e.fma(carried, context_mask[v], x)
                    e.store(z, scr[g][z_name], e.int_op("z", "add", z_row, 8 * v))
            if own:
                pb_row = row(t, pp)
                for g in group:
                    for v in range(pv):
                        index = e.int_op("q", "add", pb_row, 8 * v)
                        e.store(e.sigmoid(e.load(seqs[g]["rho"], index)), scr[g]["pb"], index)
                pb_scalars = [(scr[g]["pb"], pb_row) for g in group]
            else:
                pb_scalars = [(seqs[g]["teacher_pb"], 0) for g in group]
            bias = [e.load(weights["b_h"], 8 * v) for v in range(hv)]
            sums = e.products(
                [list(bias) for _ in group],
                rows,
                [(scr[g][z_name], z_row) for g in group],
                weights["w_xc"],
                hp,
            )
            sums = e.products(sums, p, pb_scalars, weights["w_p"], hp)
            hid_row = row(t, hp) if own else "0"
            for g in group:
                for v, total in enumerate(sums[g]):
                    e.store(
                        e.sigmoid(total), scr[g][hid_name], e.int_op("h", "add", hid_row, 8 * v)
                    )
            bias = [e.load(weights["b_out"], 8 * v) for v in range(ov)]
            outputs = e.products(
                [list(bias) for _ in group],
                h,
                [(scr[g][hid_name], hid_row) for g in group],
                weights["w_out"],
                op,
            )
            for g in group:
                for v, total in enumerate(outputs[g]):
                    e.store(e.sigmoid(total), scr[g][out_name], row(t, op, v))
            return []

        e.loop(count, [], step)

    def accumulate(
        target: str,
        count: int,
        scalars: list[tuple[str, str | int]],
        vectors: list[list[str]],
        width: int,
    ) -> None:
        """``target[k, :] += Σ_g scalars_g[k] · vectors_g`` for ``k < count``: a layer's
        weights' gradient from one step's errors, a loaded row serving the whole group."""

        def body(k: str, _: list[str]) -> list[str]:
            factors = [
                e.broadcast(e.load_scalar(base, e.int_op("k", "add", start, k)))
                for base, start in scalars
            ]
            base_row = e.int_op("r", "mul", k, width)
            for v in range(len(vectors[0])):
                index = e.int_op("w", "add", base_row, 8 * v)
                total = e.load(target, index)
                for g, factor in enumerate(factors):
                    total = e.fma(factor, vectors[g][v], total)
                e.store(total, target, index)
            return []

        e.loop(count, [], body)

    def add_into(target: str, vectors: list[list[str]]) -> None:
        for v in range(len(vectors[0])):
            total = e.load(target, 8 * v)
            for values in vectors:
                total = e.fadd(total, values[v])
            e.store(total, target, 8 * v)

    def backward(
        seqs: list[dict[str, str]], scr: list[dict[str, str]], count: str, targets: list[str]
    ) -> None:
        group = range(len(seqs))

        def step(k: str, carried: list[str]) -> list[str]:
            d_context = [carried[g * ov : (g + 1) * ov] for g in group]
            t = e.int_op("t", "sub", e.int_op("t", "sub", count, 1), k)
            d_out = []
            for g in group:
                values = []
                for v in range(ov):
                    index = row(t, op, v)
                    out = e.load(scr[g]["out"], index)
                    error = e.fmul(
                        e.fsub(out, e.load(targets[g], index)), e.load(seqs[g]["mask"], index)
                    )
                    total = e.fadd(error, d_context[g][v])
                    value = e.fmul(e.fmul(total, out), e.one_minus(out))
                    e.store(value, scr[g]["d_out"], 8 * v)
                    values.append(value)
                d_out.append(values)
            hid_row = row(t, hp)
            accumulate(grads["w_out"], h, [(scr[g]["hid"], hid_row) for g in group], d_out, op)
            add_into(grads["b_out"], d_out)
            d_hidden = e.products(
                [[zero] * hv for _ in group],
                rows,
                [(scr[g]["d_out"], 0) for g in group],
                ptr["w_out_t"],
                hp,
            )
            dh = []
            for g in group:
                values = []
                for v, total in enumerate(d_hidden[g]):
                    hid = e.load(scr[g]["hid"], e.int_op("h", "add", hid_row, 8 * v))
                    value = e.fmul(e.fmul(total, hid), e.one_minus(hid))
                    e.store(value, scr[g]["dh"], 8 * v)
                    values.append(value)
                dh.append(values)
            z_row, pb_row = row(t, op), row(t, pp)
            accumulate(grads["w_xc"], rows, [(scr[g]["z"], z_row) for g in group], dh, hp)
            accumulate(grads["w_p"], p, [(scr[g]["pb"], pb_row) for g in group], dh, hp)
            add_into(grads["b_h"], dh)
            errors = [(scr[g]["dh"], 0) for g in group]
            d_pb = e.products([[zero] * pv for _ in group], h, errors, ptr["w_p_t"], pp)
            for g in group:
                for v, total in enumerate(d_pb[g]):
                    index = e.int_op("q", "add", pb_row, 8 * v)
                    pb = e.load(scr[g]["pb"], index)
                    gradient = e.fmul(e.fmul(total, pb), e.one_minus(pb))
                    e.store(e.fsub(zero, gradient), scr[g]["grad"], index)
            d_next = e.products([[zero] * ov for _ in group], h, errors, ptr["w_c_t"], op)
            return [value for values in d_next for value in values]

        d_first = e.loop(count, [zero] * (ov * len(seqs)), step)
        for g in group:  # the initial context's logits: d c_0 · c_0 (1 - c_0)
            for v in range(ov):
                first = e.load(scr[g]["first"], 8 * v)
                value = e.fmul(e.fmul(d_first[g * ov + v], first), e.one_minus(first))
                value = e.fmul(value, scalar["learn_context"])
                e.store(value, seqs[g]["grad_context"], 8 * v)

    def make_noise(
        indices: list[str], scr: list[dict[str, str]], count: str, key: tuple[str, str]
    ) -> None:
        """Each step's input noise, ``noise_scale · jax.random.normal(key, (S, N, I))`` at
        the group's sequences, into their scratch."""
        lanes = "<" + ", ".join(f"i32 {lane}" for lane in range(8)) + ">"
        bases = [e.int_op("b", "mul", index, sequence_inputs) for index in indices]

        def step(t: str, _: list[str]) -> list[str]:
            for g, base in enumerate(bases):
                at_step = e.int_op("b", "add", base, e.int_op("b", "mul", t, io))
                for v in range(ov):
                    if 8 * v >= io:
                        break
                    first_count = e.op(
                        "b", f"trunc i64 {e.int_op('b', 'add', at_step, 8 * v)} to i32"
                    )
                    counts = _int(e, "add", _broadcast_int(e, first_count), lanes)
                    value = e.fmul(_normal(e, key, counts), scalar["noise_scale"])
                    e.store(e.fmul(value, input_mask[v]), scr[g]["noise"], row(t, op, v))
            return []

        e.loop(count, [], step)

    def run_group(first: str, size: int, key: tuple[str, str]) -> None:
        indices = [e.int_op("g", "add", first, g) for g in range(size)]
        seqs = [sequence_parts(index) for index in indices]
        scr = scratch[:size]
        count = seqs[0]["n"]
        for g in range(1, size):  # the group runs to its longest sequence's last valid step
            longer = e.op("g", f"icmp sgt i64 {seqs[g]['n']}, {count}")
            count = e.op("g", f"select i1 {longer}, i64 {seqs[g]['n']}, i64 {count}")
        targets = [seqs[g]["targets"] for g in range(size)]
        if shapes.noise:
            make_noise(indices, scr, count, key)
        if shapes.teacher:
            forward(teacher, seqs, scr, count, own=False)
            targets = [
                e.op(
                    "y",
                    f"select i1 {seqs[g]['taught']}, ptr {scr[g]['teacher_out']}, ptr {targets[g]}",
                )
                for g in range(size)
            ]
        forward(student, seqs, scr, count, own=True)
        backward(seqs, scr, count, targets)
        for g in range(size):
            update, after = e.label("pb"), e.label("pb_done")
            e.emit(f"br i1 {seqs[g]['learns']}, label %{update}, label %{after}")
            e.block(update)
            _pb_update(e, scr[g], seqs[g], coefficient, seqs[g]["n"], pv, pp)
            e.emit(f"br label %{after}")
            e.block(after)

    def when(condition: str, body: Callable[[], None]) -> None:
        yes, after = e.label("when"), e.label("when_done")
        e.emit(f"br i1 {condition}, label %{yes}, label %{after}")
        e.block(yes)
        body()
        e.emit(f"br label %{after}")
        e.block(after)

    # whole groups of four, then a group of two and one of one for what is left
    full = e.op("g", f"udiv i64 %sequences, {GROUP}")
    rest = e.op("g", f"urem i64 %sequences, {GROUP}")
    pair = e.op("g", f"and i64 {rest}, 2")
    single = e.op("g", f"and i64 {rest}, 1")
    after_full = e.int_op("g", "mul", full, GROUP)
    after_pair = e.int_op("g", "add", after_full, pair)
    contexts = e.int_op("g", "mul", "%sequences", ov)  # the initial contexts' vectors

    def iteration(it: str, _: list[str]) -> list[str]:
        first = e.int_op("n", "mul", it, 2)
        words = []
        for index in (first, e.int_op("n", "add", first, 1)):
            word = e.op("p", f"getelementptr inbounds i32, ptr %keys, i64 {index}")
            words.append(_broadcast_int(e, e.op("k", f"load i32, ptr {word}")))
        key = (words[0], words[1])

        def whole_group(index: str, __: list[str]) -> list[str]:
            run_group(e.int_op("g", "mul", index, GROUP), GROUP, key)
            return []

        def whole_groups() -> None:
            e.loop(full, [], whole_group)

        when(e.op("g", f"icmp ugt i64 {full}, 0"), whole_groups)
        when(e.op("g", f"icmp ne i64 {pair}, 0"), lambda: run_group(after_full, 2, key))
        when(e.op("g", f"icmp ne i64 {single}, 0"), lambda: run_group(after_pair, 1, key))
        schedule = e.address("%schedule", e.int_op("n", "mul", it, 8))
        correction = [e.broadcast(e.load_scalar(schedule, i)) for i in range(2)]
        for names, count in (
            (
                ("weights", "weight_grads", "weight_first", "weight_second"),
                shapes.weights_size // 8,
            ),
            (("context", "context_grads", "context_first", "context_second"), contexts),
        ):
            _optimizer_step(e, shapes, [ptr[name] for name in names], scalar, correction, count)
        _transposes(e, shapes, student, ptr)
        return []

    e.loop("%iterations", [], iteration)
    return module(
        "learn(i64 %iterations, i64 %half, i64 %sequences, i64 %steps, ptr noalias %table, "
        "ptr noalias %keys, ptr noalias %schedule)",
        e,
    )


def _optimizer_step(
    e: _Emitter,
    shapes: LearningShapes,
    region: list[str],
    scalar: dict[str, str],
    correction: list[str],
    count: str | int,
) -> None:
    """The step of ``count`` vectors of learned values from their summed gradients, which it
    then clears: gradients over the valid steps' count, then optax's ``sgd(learning_rate,
    momentum)`` or ``adam(learning_rate)``. ``region``: the values, their gradients, their
    first and second moments."""
    values, grads, first_moments, second_moments = region
    minus_rate = e.fsub("zeroinitializer", scalar["learning_rate"])

    def body(k: str, _: list[str]) -> list[str]:
        index = e.int_op("k", "mul", k, 8)
        gradient = e.op("d", f"fdiv fast {V} {e.load(grads, index)}, {scalar['n_valid']}")
        first = e.load(first_moments, index)
        if shapes.adam:
            first = e.fma(scalar["beta1"], first, e.fmul(e.one_minus(scalar["beta1"]), gradient))
            second = e.load(second_moments, index)
            square = e.fmul(gradient, gradient)
            second = e.fma(scalar["beta2"], second, e.fmul(e.one_minus(scalar["beta2"]), square))
            e.store(second, second_moments, index)
            mean = e.op("d", f"fdiv fast {V} {first}, {correction[0]}")
            spread = e.op("d", f"fdiv fast {V} {second}, {correction[1]}")
            root = e.op("r", f"call fast {V} @llvm.sqrt.v8f32({V} {spread})")
            step = e.op("d", f"fdiv fast {V} {mean}, {e.fadd(root, scalar['eps'])}")
        else:
            first = e.fma(scalar["beta1"], first, gradient)  # beta1: the weights' momentum
            step = first
        e.store(first, first_moments, index)
        e.store(e.fadd(e.load(values, index), e.fmul(step, minus_rate)), values, index)
        e.store("zeroinitializer", grads, index)
        return []

    e.loop(count, [], body)


def _transposes(
    e: _Emitter, shapes: LearningShapes, student: dict[str, str], ptr: dict[str, str]
) -> None:
    """The transposed weights the backward pass reads, from the weights just stepped."""
    io, c, h = shapes.io, shapes.context, shapes.hidden
    op, hp, pp = shapes.op, shapes.hp, shapes.pp

    def transpose(
        source: str,
        source_width: int,
        target: str,
        target_width: int,
        rows: int,
        columns: int,
        row_shift: int,
        column_shift: int,
    ) -> None:
        """target[j + column_shift, k + row_shift] = source[k, j] for k < rows, j < columns."""

        def outer(k: str, _: list[str]) -> list[str]:
            def inner(j: str, __: list[str]) -> list[str]:
                value = e.load_scalar(
                    source, e.int_op("i", "add", e.int_op("i", "mul", k, source_width), j)
                )
                to = e.int_op(
                    "i",
                    "add",
                    e.int_op("i", "mul", e.int_op("i", "add", j, column_shift), target_width),
                    e.int_op("i", "add", k, row_shift),
                )
                e.emit(f"store float {value}, ptr {e.address(target, to)}, align 4")
                return []

            e.loop(columns, [], inner)
            return []

        e.loop(rows, [], outer)

    # w_out_t (rows: outputs with the context; HP): w_out (H, OP) transposed
    transpose(student["w_out"], op, ptr["w_out_t"], hp, h, io + c, 0, 0)
    # w_c_t (H, OP), context columns: the context rows of w_xc transposed
    context_rows = e.address(student["w_xc"], io * hp)
    transpose(context_rows, hp, ptr["w_c_t"], op, c, h, io, 0)
    # w_p_t (H, PP): w_p (P, HP) transposed
    transpose(student["w_p"], hp, ptr["w_p_t"], pp, shapes.pb, h, 0, 0)


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
_SCALARS = (
    "k_bp",
    "k_nb",
    "rate",
    "momentum",
    "learning_rate",
    "beta1",
    "beta2",
    "eps",
    "n_valid",
    "learn_context",
    "noise_scale",
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
