"""The on-line regression's loop as native code: the fast twin of the loop of
:func:`rnnpb.model.online.step_sessions` (``rnnpb bench`` and ``benchmarks/native_loop.py`` time
the two side by side).

The loop — ``iterations`` times the window's forward and backward pass, the PB update of eqs.
1–2 and the onset's step (:mod:`rnnpb.model.equations`) — is written here in LLVM's
intermediate language with explicit 8-wide vectors and compiled at run time for the machine's
processor by llvmlite. The sums of each layer's products stay in vector registers through the
products' loops, which the compiled Python of :mod:`rnnpb.model.equations` does not manage
(it keeps them in memory between inputs: docs/model.md, "Speed"); the sigmoid is the same
rational function as :func:`rnnpb.model.equations.unit`.

Everything before and after the loop — the new observation, the restarts, the surprise gate,
the outputs, recognition's evidence — is the compiled step of :mod:`rnnpb.model.online`, which
also fills each session's block for this kernel (:func:`rnnpb.model.online.fill_blocks`) and
takes its results back. The safety barrier's gradient (the risk network of
:mod:`rnnpb.model.meta` on the window's newest steps) is in the kernel too, for the risk
network it was built with. The step's own loop is the reference and the fallback: it runs
where llvmlite is missing or ``RNNPB_NATIVE=0`` asks for it. ``tests/model/test_native.py``
holds the two together.

Layouts (all float32): every row is padded to a whole number of 8-wide vectors — ``HP`` for the
hidden layer (H), ``IP`` for the inputs and outputs with the context (``I + C``), ``PP`` for the
PB (P); the padding's weights are 0, so it changes nothing.
"""

from __future__ import annotations

import ctypes
import threading
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from rnnpb.model._ir import (
    V,
    _Emitter,
    _offsets,
    _padded,
    _pb_update,
    _vector_constant,
    build,
    enabled,
    module,
)
from rnnpb.model.meta import MetaParams
from rnnpb.model.network import NetworkConfig, Params
from rnnpb.model.online_config import OnlineConfig

# Sessions regressed together by one kernel call (NativeRegression.many): each weight vector
# loaded serves all of them.
GROUP = 4
_SCALARS = 8  # the weights block opens with the PB update's coefficients (see _weights_block)


@dataclass(frozen=True)
class Shapes:
    """The sizes a kernel is compiled for: window L, sensory S, motor M, PB P, context C,
    hidden H."""

    window: int
    sensory: int
    motor: int
    pb: int
    context: int
    hidden: int
    # The safety barrier's risk network (rnnpb.model.meta): its hidden layer's size (0: no
    # barrier in the kernel) and the newest steps of the window it acts on.
    risk_hidden: int = 0
    barrier_span: int = 0

    @property
    def io(self) -> int:
        """Inputs (and outputs) with the context: S + M + C."""
        return self.sensory + self.motor + self.context

    @property
    def hp(self) -> int:
        return _padded(self.hidden)

    @property
    def ip(self) -> int:
        return _padded(self.io)

    @property
    def pp(self) -> int:
        return _padded(self.pb)

    @property
    def rp(self) -> int:
        return _padded(self.risk_hidden)

    def weights_layout(self) -> dict[str, tuple[int, int]]:
        """Offset and size of each part of the weights block."""
        h, hp, io, ip, p, pp = self.hidden, self.hp, self.io, self.ip, self.pb, self.pp
        parts = {
            "scalars": _SCALARS,
            "w_loop": io * hp,  # (IO, HP): the recurrent inputs' weights to the hidden layer
            "w_out": h * ip,  # (H, IP)
            "b_out": ip,
            "w_out_t": io * hp,  # (IO, HP)
            "w_loop_t": h * ip,  # (H, IP)
            "w_p": p * hp,  # (P, HP)
            "w_p_t": h * pp,  # (H, PP)
        }
        if self.risk_hidden:  # the risk network, padded (rnnpb.model.meta.MetaParams)
            r, rp = self.risk_hidden, self.rp
            parts |= {
                "risk_w1": p * rp,  # (P, RP)
                "risk_b1": rp,
                "risk_w2": r * rp,  # (R, RP)
                "risk_b2": rp,
                "risk_w3": rp,
                "risk_w2_t": r * rp,  # (R, RP)
                "risk_w1_t": r * pp,  # (R, PP)
            }
        return _offsets(parts)

    def block_layout(self) -> dict[str, tuple[int, int]]:
        """Offset and size of each part of a step's block (what :func:`prepare` returns)."""
        length, hp, ip, pp = self.window, self.hp, self.ip, self.pp
        parts = {
            "head": 8,  # [gate, n, barrier on]
            "fixed": length * hp,  # the hidden layer's input that does not depend on the loop
            "mask": length * ip,  # which outputs feed back as the next step's inputs
            "target": length * ip,  # the next observation, where it is a target
            "target_mask": length * ip,
            "next_mask": length * ip,  # mask of the following step (0 after the last)
            "learn": ip,  # 1 where the onset is regressed (motor and context)
            "onset": ip,  # logits of the window's first input
            "rho": length * pp,
            "velocity": length * pp,
        }
        return _offsets(parts)

    def scratch_size(self) -> int:
        return _offsets(self.scratch_parts())["total"][0]

    def scratch_parts(self) -> dict[str, int]:
        length, hp, ip, pp, rp = self.window, self.hp, self.ip, self.pp, self.rp
        return {
            "out": length * ip,
            "hid": length * hp,
            "x": ip,
            "g": ip,
            "first": ip,
            "dh": hp,
            "pb": length * pp,
            "grad": length * pp,
            "rnew": length * pp,
            "cum": (length + 1) * pp,
            "risk_h1": rp,
            "risk_d2": rp,
            "risk_d1": rp,
        }


# --- the intermediate language ------------------------------------------------------------


def regression_ir(shapes: Shapes, group: int = 1) -> str:
    """The kernel ``regress(iterations, half, weights, blocks, scratch)``: ``iterations`` of
    the on-line regression's loop over ``group`` sessions' blocks (:meth:`Shapes.block_layout`,
    one after the other at ``blocks``), updating each one's ``rho``, ``velocity`` and
    ``onset`` in place; ``scratch`` holds ``group`` times :meth:`Shapes.scratch_size`.
    ``half``: the integration length's half (eq. 1).

    The sessions of a group run in step: each weight vector loaded in a product's loop serves
    every session's sums (loading the weights, not multiplying, bounds one session's loop).
    Each session's arithmetic is the same, in the same order, as alone."""
    e = _Emitter()
    length, h, io, p = shapes.window, shapes.hidden, shapes.io, shapes.pb
    hp, ip, pp = shapes.hp, shapes.ip, shapes.pp
    hv, iv, pv = hp // 8, ip // 8, pp // 8
    zero = "zeroinitializer"
    sessions = range(group)

    def part(base: str, layout: dict[str, tuple[int, int]], key: str) -> str:
        return e.address(base, layout[key][0])

    weights, block = shapes.weights_layout(), shapes.block_layout()
    w = {key: part("%weights", weights, key) for key in weights if key != "total"}
    scratch_parts = _offsets(shapes.scratch_parts())
    b, s = [], []
    for g in sessions:
        base = e.address("%blocks", g * block["total"][0])
        b.append({key: part(base, block, key) for key in block if key != "total"})
        base = e.address("%scratch", g * scratch_parts["total"][0])
        s.append({key: part(base, scratch_parts, key) for key in scratch_parts if key != "total"})
    coefficient = {
        name: e.broadcast(e.load_scalar(w["scalars"], i))
        for i, name in enumerate(
            ("k_bp", "k_nb", "rate", "momentum", "onset_rate", "barrier_weight", "risk_offset")
        )
    }
    minus_gate = [e.fsub(zero, e.broadcast(e.load_scalar(b[g]["head"], 0))) for g in sessions]
    n = [e.op("n", f"fptosi float {e.load_scalar(b[g]['head'], 1)} to i64") for g in sessions]

    def row_index(t: str, width: int, v: int) -> str:
        return e.int_op("o", "add", e.int_op("o", "mul", t, width), 8 * v)

    def grouped(values: list[str], size: int) -> list[list[str]]:
        return [values[g * size : (g + 1) * size] for g in sessions]

    def iteration(_: str, __: list[str]) -> list[str]:
        # the window's first input: sigmoid of the onset's logits (0 gives the sensory 0.5)
        for g in sessions:
            for v in range(iv):
                e.store(e.sigmoid(e.load(b[g]["onset"], 8 * v)), s[g]["first"], 8 * v)

        def forward(t: str, _: list[str]) -> list[str]:
            pb_row = e.int_op("q", "mul", t, pp)
            for g in sessions:
                for v in range(pv):
                    index = e.int_op("q", "add", pb_row, 8 * v)
                    e.store(e.sigmoid(e.load(b[g]["rho"], index)), s[g]["pb"], index)
            sums = [
                [e.load(b[g]["fixed"], row_index(t, hp, v)) for v in range(hv)] for g in sessions
            ]
            sums = e.products(
                sums, p, [(s[g]["pb"], pb_row) for g in sessions], w["w_p"], hp, chains=2
            )
            # the recurrent input: the first input at t = 0, else the last output; masked
            first_step = e.op("z", f"icmp eq i64 {t}, 0")
            previous = e.int_op("y", "mul", e.int_op("y", "sub", t, 1), ip)
            previous = e.op("y", f"select i1 {first_step}, i64 0, i64 {previous}")
            for g in sessions:
                source = e.op(
                    "y", f"select i1 {first_step}, ptr {s[g]['first']}, ptr {s[g]['out']}"
                )
                for v in range(iv):
                    value = e.load(source, e.int_op("y", "add", previous, 8 * v))
                    mask = e.load(b[g]["mask"], row_index(t, ip, v))
                    e.store(e.fmul(value, mask), s[g]["x"], 8 * v)
            sums = e.products(
                sums, io, [(s[g]["x"], 0) for g in sessions], w["w_loop"], hp, chains=2
            )
            hidden_row = e.int_op("h", "mul", t, hp)
            for g in sessions:
                for v, total in enumerate(sums[g]):
                    index = e.int_op("h", "add", hidden_row, 8 * v)
                    e.store(e.sigmoid(total), s[g]["hid"], index)
            bias = [e.load(w["b_out"], 8 * v) for v in range(iv)]
            outputs = e.products(
                [list(bias) for _ in sessions],
                h,
                [(s[g]["hid"], hidden_row) for g in sessions],
                w["w_out"],
                ip,
                chains=2,
            )
            for g in sessions:
                for v, total in enumerate(outputs[g]):
                    e.store(e.sigmoid(total), s[g]["out"], row_index(t, ip, v))
            return []

        e.loop(length, [], forward)

        def backward(k: str, carried: list[str]) -> list[str]:
            d_input = grouped(carried, iv)
            t = e.int_op("t", "sub", length - 1, k)
            for g in sessions:
                for v in range(iv):
                    index = row_index(t, ip, v)
                    out = e.load(s[g]["out"], index)
                    error = e.fmul(
                        e.fsub(out, e.load(b[g]["target"], index)),
                        e.load(b[g]["target_mask"], index),
                    )
                    total = e.fma(d_input[g][v], e.load(b[g]["next_mask"], index), error)
                    e.store(e.fmul(total, e.fmul(out, e.one_minus(out))), s[g]["g"], 8 * v)
            d_hidden = e.products(
                [[zero] * hv for _ in sessions],
                io,
                [(s[g]["g"], 0) for g in sessions],
                w["w_out_t"],
                hp,
                chains=2,
            )
            hidden_row = e.int_op("h", "mul", t, hp)
            for g in sessions:
                for v, total in enumerate(d_hidden[g]):
                    hid = e.load(s[g]["hid"], e.int_op("h", "add", hidden_row, 8 * v))
                    e.store(e.fmul(total, e.fmul(hid, e.one_minus(hid))), s[g]["dh"], 8 * v)
            errors = [(s[g]["dh"], 0) for g in sessions]
            d_pb = e.products([[zero] * pv for _ in sessions], h, errors, w["w_p_t"], pp, chains=2)
            pb_row = e.int_op("q", "mul", t, pp)
            for g in sessions:
                for v, total in enumerate(d_pb[g]):
                    index = e.int_op("q", "add", pb_row, 8 * v)
                    pb = e.load(s[g]["pb"], index)
                    gradient = e.fmul(total, e.fmul(pb, e.one_minus(pb)))
                    e.store(e.fmul(gradient, minus_gate[g]), s[g]["grad"], index)
            d_input = e.products(
                [[zero] * iv for _ in sessions], h, errors, w["w_loop_t"], ip, chains=2
            )
            return [value for values in d_input for value in values]

        d_first = grouped(e.loop(length, [zero] * (iv * group), backward), iv)
        for g in sessions:
            # the onset's step (rnnpb.model.window.gradients: d_first · mask[0] · f (1 - f))
            for v in range(iv):
                first = e.load(s[g]["first"], 8 * v)
                gradient = e.fmul(d_first[g][v], e.load(b[g]["mask"], 8 * v))
                gradient = e.fmul(gradient, e.fmul(first, e.one_minus(first)))
                gradient = e.fmul(gradient, e.load(b[g]["learn"], 8 * v))
                onset = e.load(b[g]["onset"], 8 * v)
                step = e.fmul(coefficient["onset_rate"], gradient)
                e.store(e.fsub(onset, step), b[g]["onset"], 8 * v)
            if shapes.risk_hidden:
                _barrier(e, shapes, w, s[g], b[g], coefficient, n[g])
            _pb_update(e, s[g], b[g], coefficient, n[g], pv, pp)
        return []

    e.loop("%iterations", [], iteration)
    return module(
        "regress(i64 %iterations, i64 %half, ptr noalias %weights, ptr noalias %blocks, "
        "ptr noalias %scratch)",
        e,
    )


def _barrier(
    e: _Emitter,
    shapes: Shapes,
    w: dict[str, str],
    s: dict[str, str],
    b: dict[str, str],
    coefficient: dict[str, str],
    n: str,
) -> None:
    """The safety barrier's gradient (:func:`rnnpb.model.online._barrier_gradient`) on the
    window's newest ``barrier_span`` steps, added to the PB's error gradient: for each, the
    risk network's logit of its PB, and ``barrier_weight · σ(logit − logit(risk_level)) ·
    d logit / d rho`` by back-propagation through the network. Skipped at a step whose
    block says the barrier is off (head[2] = 0)."""
    length, p, pp, r, rp = shapes.window, shapes.pb, shapes.pp, shapes.risk_hidden, shapes.rp
    span = shapes.barrier_span
    on = e.op("z", f"fcmp one float {e.load_scalar(b['head'], 2)}, 0.0")
    body, after = e.label("barrier"), e.label("barrier_done")
    e.emit(f"br i1 {on}, label %{body}, label %{after}")
    e.block(body)
    start = e.int_op("z", "sub", n, span)
    start = e.op("z", f"select i1 {e.op('z', f'icmp sgt i64 {start}, 0')}, i64 {start}, i64 0")
    start = e.op(
        "z",
        f"select i1 {e.op('z', f'icmp slt i64 {start}, {length - span}')}, i64 {start}, "
        f"i64 {length - span}",
    )
    zero = "zeroinitializer"
    rv = rp // 8

    def one_step(k: str, _: list[str]) -> list[str]:
        row = e.int_op("z", "mul", e.int_op("z", "add", start, k), pp)
        hidden = [e.load(w["risk_b1"], 8 * v) for v in range(rv)]
        hidden = [e.tanh(a) for a in e.products([hidden], p, [(s["pb"], row)], w["risk_w1"], rp)[0]]
        for v, value in enumerate(hidden):
            e.store(value, s["risk_h1"], 8 * v)
        second = [e.load(w["risk_b2"], 8 * v) for v in range(rv)]
        second = [
            e.tanh(a) for a in e.products([second], r, [(s["risk_h1"], 0)], w["risk_w2"], rp)[0]
        ]
        total = zero
        for v, value in enumerate(second):
            total = e.fma(value, e.load(w["risk_w3"], 8 * v), total)
        logit = e.op("z", f"call fast float @llvm.vector.reduce.fadd.v8f32(float 0.0, {V} {total})")
        excess = e.fadd(e.broadcast(logit), coefficient["risk_offset"])
        factor = e.fmul(e.sigmoid(excess), coefficient["barrier_weight"])
        for v, value in enumerate(second):  # d logit / d (second layer's input)
            slope = e.fsub(_vector_constant(1.0), e.fmul(value, value))
            e.store(e.fmul(e.load(w["risk_w3"], 8 * v), slope), s["risk_d2"], 8 * v)
        first = e.products([[zero] * rv], r, [(s["risk_d2"], 0)], w["risk_w2_t"], rp)[0]
        for v, value in enumerate(first):
            h1 = e.load(s["risk_h1"], 8 * v)
            e.store(
                e.fmul(value, e.fsub(_vector_constant(1.0), e.fmul(h1, h1))), s["risk_d1"], 8 * v
            )
        d_pb = e.products([[zero] * (pp // 8)], r, [(s["risk_d1"], 0)], w["risk_w1_t"], pp)[0]
        for v, value in enumerate(d_pb):
            index = e.int_op("z", "add", row, 8 * v)
            pb = e.load(s["pb"], index)
            gradient = e.fmul(e.fmul(value, e.fmul(pb, e.one_minus(pb))), factor)
            e.store(e.fsub(e.load(s["grad"], index), gradient), s["grad"], index)
        return []

    e.loop(span, [], one_step)
    e.emit(f"br label %{after}")
    e.block(after)


# --- compiling and calling ---------------------------------------------------------------

_compiled: dict[tuple[Shapes, int], tuple[Any, Any]] = {}
_compile_lock = threading.Lock()
_SIGNATURE = ctypes.CFUNCTYPE(
    None, ctypes.c_int64, ctypes.c_int64, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p
)


def compiled(shapes: Shapes, group: int = 1) -> Any:
    """The kernel for ``shapes`` and ``group`` sessions at once (:func:`regression_ir`),
    compiled once per process for this machine's processor (LLVM's -O3 pipeline); a ctypes
    function."""
    key = (shapes, group)
    with _compile_lock:
        if key not in _compiled:
            _compiled[key] = build(regression_ir(shapes, group), "regress", _SIGNATURE)
        return _compiled[key][0]


def shapes_of(
    network: NetworkConfig, config: OnlineConfig, meta: MetaParams | None = None
) -> Shapes:
    """The kernel's sizes for a network, a window and, when the regression may go through the
    safety barrier, the risk network."""
    barrier = meta is not None and config.safety_guard == "barrier" and config.barrier_weight > 0
    return Shapes(
        window=config.window,
        sensory=network.sensory_size,
        motor=network.motor_size,
        pb=network.pb_size,
        context=network.context_size,
        hidden=network.hidden_size,
        risk_hidden=int(np.shape(meta.w1)[1]) if barrier and meta is not None else 0,
        barrier_span=(config.barrier_span or config.window) if barrier else 0,
    )


def _weights_block(
    params: Params, shapes: Shapes, config: OnlineConfig, meta: MetaParams | None
) -> np.ndarray:
    """The weights block (:meth:`Shapes.weights_layout`): the PB update's, the onset's and
    the barrier's coefficients, then the weights in the kernel's padded layouts."""
    s, m, p, h, io = shapes.sensory, shapes.motor, shapes.pb, shapes.hidden, shapes.io
    w_in = np.asarray(params.w_in, np.float32)
    w_out = np.asarray(params.w_out, np.float32)
    w_u, w_m = w_in[:s], w_in[s : s + m]
    w_p, w_c = w_in[s + m : s + m + p], w_in[s + m + p :]
    w_loop = np.concatenate([w_u, w_m, w_c])  # (IO, H)
    onset_rate = config.onset_learning_rate if config.optimize_onset else 0.0
    pb = config.pb
    level = config.risk_level
    risk_offset = 0.0 if meta is None else float(meta.b3) - np.log(level / (1.0 - level))
    scalars = [pb.k_bp, pb.k_nb, pb.learning_rate, pb.momentum, onset_rate]
    parts = {
        "scalars": np.array([*scalars, config.barrier_weight, risk_offset]),
        "w_loop": _pad(w_loop, io, shapes.hp),
        "w_out": _pad(w_out, h, shapes.ip),
        "b_out": _pad(np.asarray(params.b_out, np.float32)[None], 1, shapes.ip),
        "w_out_t": _pad(w_out.T, io, shapes.hp),
        "w_loop_t": _pad(w_loop.T, h, shapes.ip),
        "w_p": _pad(w_p, p, shapes.hp),
        "w_p_t": _pad(w_p.T, h, shapes.pp),
    }
    if shapes.risk_hidden and meta is not None:
        r, rp = shapes.risk_hidden, shapes.rp
        w1, w2 = np.asarray(meta.w1, np.float32), np.asarray(meta.w2, np.float32)
        parts |= {
            "risk_w1": _pad(w1, p, rp),
            "risk_b1": _pad(np.asarray(meta.b1, np.float32)[None], 1, rp),
            "risk_w2": _pad(w2, r, rp),
            "risk_b2": _pad(np.asarray(meta.b2, np.float32)[None], 1, rp),
            "risk_w3": _pad(np.asarray(meta.w3, np.float32)[None], 1, rp),
            "risk_w2_t": _pad(w2.T, r, rp),
            "risk_w1_t": _pad(w1.T, r, shapes.pp),
        }
    layout = shapes.weights_layout()
    block = np.zeros(layout["total"][0], np.float32)
    for name, values in parts.items():
        offset, _ = layout[name]
        flat = np.ravel(values).astype(np.float32)
        block[offset : offset + flat.size] = flat
    return block


def _pad(values: np.ndarray, rows: int, width: int) -> np.ndarray:
    padded = np.zeros((rows, width), np.float32)
    padded[: values.shape[0], : values.shape[1]] = values
    return padded


def native_regression(
    params: Params,
    network: NetworkConfig,
    config: OnlineConfig,
    meta: MetaParams | None = None,
) -> NativeRegression | None:
    """The kernel for these weights and this setting (with ``meta``, the risk network the
    safety barrier uses), or None where the compiled JAX step runs whole: native code not
    :func:`enabled`, or no regression (``iterations`` 0)."""
    if config.iterations == 0 or not enabled():
        return None
    try:
        return NativeRegression(params, network, config, meta)
    except Exception as error:  # noqa: BLE001 - an LLVM that cannot build it: the JAX loop runs
        warnings.warn(
            f"the native regression could not be built ({error}); the JAX loop runs instead",
            RuntimeWarning,
            stacklevel=2,
        )
        return None


class NativeRegression:
    """The kernel for one network's weights, one on-line setting and the risk network of its
    safety barrier, if any: call it with a step's block (from :func:`prepare_block`); it
    returns the regressed ``rho``, ``velocity``, onset context and onset motor values (NumPy
    float32)."""

    def __init__(
        self,
        params: Params,
        network: NetworkConfig,
        config: OnlineConfig,
        meta: MetaParams | None = None,
    ) -> None:
        self.shapes = shapes_of(network, config, meta)
        self.config = config
        self.meta = meta if self.shapes.risk_hidden else None
        self._weights = _weights_block(params, self.shapes, config, self.meta)
        self._scratch = np.zeros(GROUP * self.shapes.scratch_size(), np.float32)
        self._layout = self.shapes.block_layout()
        self._lock = threading.Lock()
        compiled(self.shapes)  # compile now, not at the first step

    def _barrier(self, meta: MetaParams | None) -> bool:
        """Whether a step given ``meta`` regresses through the safety barrier."""
        config = self.config
        return meta is not None and config.safety_guard == "barrier" and config.barrier_weight > 0

    def applies(self, meta: MetaParams | None) -> bool:
        """Whether this kernel can run a step given ``meta`` (the risk network, or None for a
        step without the guard): one without the barrier, or with the risk network it was
        built with."""
        return not self._barrier(meta) or meta is self.meta

    def block_layout(self) -> tuple[int, ...]:
        """Where a block's parts start, and the padded widths, as
        :func:`rnnpb.model.online.fill_blocks` takes them."""
        layout, shapes = self._layout, self.shapes
        names = ("fixed", "mask", "target", "target_mask", "next_mask", "learn", "onset", "rho")
        starts = tuple(layout[name][0] for name in (*names, "velocity"))
        return (*starts, shapes.hp, shapes.ip, shapes.pp)

    def blocks(self, sessions: int) -> np.ndarray:
        """Room for ``sessions`` blocks, (B, block)."""
        return np.zeros((sessions, self._layout["total"][0]), np.float32)

    def run(self, blocks: np.ndarray) -> None:
        """The regressions over many sessions' blocks (B, block), in place, ``GROUP``
        sessions to a kernel call. A block asks for the barrier with head[2] = 1; only a
        kernel built with a risk network (``meta``) has one."""
        if np.any(blocks[:, 2]) and self.meta is None:
            raise ValueError("this kernel was built without a risk network")
        with self._lock:  # one scratch per kernel
            for first in range(0, blocks.shape[0], GROUP):
                group = min(GROUP, blocks.shape[0] - first)
                compiled(self.shapes, group)(
                    self.config.iterations,
                    self.config.pb.integration_length // 2,
                    self._weights.ctypes.data,
                    blocks[first].ctypes.data,
                    self._scratch.ctypes.data,
                )
