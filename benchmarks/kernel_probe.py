"""How fast the window's forward pass can run on one core: LLVM IR with explicit 8-wide
vectors, compiled at run time by llvmlite, against the same pass compiled by XLA.

A probe for a native kernel of the on-line regression that needs no C compiler: llvmlite is a
wheel with LLVM inside. The pass is the window's (L = 30 steps, 42 inputs, 40 hidden units,
42 outputs), with random weights of the network's shapes. In the IR the hidden layer's 40 sums
are five 8-wide vectors and the outputs' 42 six, carried in registers through the products'
loops, and the sigmoid is a rational function (the form Eigen gives tanh). Prints each one's
time for 100 passes (median), the ratio, and the largest difference from a float64 NumPy
pass. Needs llvmlite, which the package does not depend on::

    .venv/bin/pip install llvmlite
    PYTHONPATH=src .venv/bin/python benchmarks/kernel_probe.py [--repeats 30]
"""

from __future__ import annotations

import argparse
import ctypes
import importlib
import struct
import time

import numpy as np

L, H, IO, IP = 30, 40, 42, 48  # IO inputs and outputs, IP: padded to six vectors
HV, IV = H // 8, IP // 8
V = "<8 x float>"
# tanh(t) ~ t * P(t^2) / Q(t^2) on [-7.9, 7.9] (Eigen's float tanh); sigmoid(x) = 0.5 +
# 0.5 * tanh(x / 2).
TANH_P = (
    -2.76076847742355e-16,
    2.00018790482477e-13,
    -8.60467152213735e-11,
    5.12229709037114e-08,
    1.48572235717979e-05,
    6.37261928875436e-04,
    4.89352455891786e-03,
)
TANH_Q = (1.19825839466702e-06, 1.18534705686654e-04, 2.26843463243900e-03, 4.89352518554385e-03)
TANH_CLAMP = 7.90531110763549805


def _vector(value: float) -> str:
    """An <8 x float> constant (LLVM writes floats as the hex of their double)."""
    bits = struct.unpack(">Q", struct.pack(">d", float(np.float32(value))))[0]
    return "<" + ", ".join([f"float 0x{bits:016X}"] * 8) + ">"


def _sigmoid(x: str, p: str) -> list[str]:
    """IR lines: %{p}r = sigmoid(x), element-wise."""
    lines = [
        f"%{p}t0 = fmul fast {V} {x}, {_vector(0.5)}",
        f"%{p}t1 = call fast {V} @llvm.minnum.v8f32({V} %{p}t0, {V} {_vector(TANH_CLAMP)})",
        f"%{p}t = call fast {V} @llvm.maxnum.v8f32({V} %{p}t1, {V} {_vector(-TANH_CLAMP)})",
        f"%{p}t2 = fmul fast {V} %{p}t, %{p}t",
    ]
    for name, coefficients in (("p", TANH_P), ("q", TANH_Q)):
        previous = _vector(coefficients[0])
        for n, value in enumerate(coefficients[1:]):
            lines.append(f"%{p}{name}m{n} = fmul fast {V} %{p}t2, {previous}")
            lines.append(f"%{p}{name}a{n} = fadd fast {V} %{p}{name}m{n}, {_vector(value)}")
            previous = f"%{p}{name}a{n}"
        lines.append(f"%{p}{name} = bitcast {V} {previous} to {V}")
    lines += [
        f"%{p}n = fmul fast {V} %{p}t, %{p}p",
        f"%{p}d = fdiv fast {V} %{p}n, %{p}q",
        f"%{p}h = fmul fast {V} %{p}d, {_vector(0.5)}",
        f"%{p}r = fadd fast {V} %{p}h, {_vector(0.5)}",
    ]
    return lines


def _load(name: str, base: str, index: str) -> list[str]:
    return [
        f"%{name}.p = getelementptr inbounds float, ptr {base}, i64 {index}",
        f"%{name} = load {V}, ptr %{name}.p, align 4",
    ]


def _store(value: str, base: str, index: str, name: str) -> list[str]:
    return [
        f"%{name}.p = getelementptr inbounds float, ptr {base}, i64 {index}",
        f"store {V} {value}, ptr %{name}.p, align 4",
    ]


def _broadcast(scalar: str, name: str) -> list[str]:
    return [
        f"%{name}.0 = insertelement {V} undef, float {scalar}, i32 0",
        f"%{name} = shufflevector {V} %{name}.0, {V} undef, <8 x i32> zeroinitializer",
    ]


def forward_ir() -> str:
    """``forward(iters, pre, mask, w_loop, w_out, b_out, first, out, hid, x)``: ``iters``
    forward passes of the window (the arrays as :func:`main` lays them out)."""
    body: list[str] = ["iter:", "%it = phi i64 [0, %entry], [%it.next, %iter.end]"]
    for v in range(IV):  # x = first * mask[0]
        body += _load(f"f{v}", "%first", str(8 * v)) + _load(f"m{v}", "%mask", str(8 * v))
        body.append(f"%x{v} = fmul fast {V} %f{v}, %m{v}")
        body += _store(f"%x{v}", "%x", str(8 * v), f"xs{v}")
    body += ["br label %step", "step:", "%t = phi i64 [0, %iter], [%t.next, %step.end]"]
    body += ["%later = icmp ugt i64 %t, 0", "br i1 %later, label %setx, label %hidden", "setx:"]
    body += ["%tm1 = sub i64 %t, 1", f"%orow = mul i64 %tm1, {IP}", f"%mrow = mul i64 %t, {IP}"]
    for v in range(IV):  # x = out[t - 1] * mask[t]
        body += [f"%oi{v} = add i64 %orow, {8 * v}", f"%mi{v} = add i64 %mrow, {8 * v}"]
        body += _load(f"ov{v}", "%out", f"%oi{v}") + _load(f"mv{v}", "%mask", f"%mi{v}")
        body.append(f"%xn{v} = fmul fast {V} %ov{v}, %mv{v}")
        body += _store(f"%xn{v}", "%x", str(8 * v), f"xt{v}")
    body += ["br label %hidden", "hidden:", f"%prow = mul i64 %t, {H}"]
    for v in range(HV):
        body.append(f"%pi{v} = add i64 %prow, {8 * v}")
        body += _load(f"pv{v}", "%pre", f"%pi{v}")
    body += ["br label %kloop", "kloop:", "%k = phi i64 [0, %hidden], [%k.next, %kloop]"]
    body += [f"%a{v} = phi {V} [%pv{v}, %hidden], [%an{v}, %kloop]" for v in range(HV)]
    body += ["%xk.p = getelementptr inbounds float, ptr %x, i64 %k", "%xk = load float, ptr %xk.p"]
    body += _broadcast("%xk", "xb") + [f"%wrow = mul i64 %k, {H}"]
    for v in range(HV):  # the hidden layer's sums: five vectors in registers
        body.append(f"%wi{v} = add i64 %wrow, {8 * v}")
        body += _load(f"wv{v}", "%wl", f"%wi{v}")
        body.append(f"%an{v} = call fast {V} @llvm.fma.v8f32({V} %xb, {V} %wv{v}, {V} %a{v})")
    body += ["%k.next = add i64 %k, 1", f"%kdone = icmp eq i64 %k.next, {IO}"]
    body += ["br i1 %kdone, label %hsig, label %kloop", "hsig:"]
    for v in range(HV):
        body += _sigmoid(f"%an{v}", f"hs{v}") + [f"%hi{v} = add i64 %prow, {8 * v}"]
        body += _store(f"%hs{v}r", "%hid", f"%hi{v}", f"hst{v}")
    for v in range(IV):
        body += _load(f"bv{v}", "%bo", str(8 * v))
    body += ["br label %jloop", "jloop:", "%j = phi i64 [0, %hsig], [%j.next, %jloop]"]
    body += [f"%o{v} = phi {V} [%bv{v}, %hsig], [%on{v}, %jloop]" for v in range(IV)]
    body += [
        "%hj.i = add i64 %prow, %j",
        "%hj.p = getelementptr inbounds float, ptr %hid, i64 %hj.i",
    ]
    body += (
        ["%hj = load float, ptr %hj.p"] + _broadcast("%hj", "hb") + [f"%worow = mul i64 %j, {IP}"]
    )
    for v in range(IV):  # the outputs' sums: six vectors in registers
        body.append(f"%woi{v} = add i64 %worow, {8 * v}")
        body += _load(f"wov{v}", "%wo", f"%woi{v}")
        body.append(f"%on{v} = call fast {V} @llvm.fma.v8f32({V} %hb, {V} %wov{v}, {V} %o{v})")
    body += ["%j.next = add i64 %j, 1", f"%jdone = icmp eq i64 %j.next, {H}"]
    body += ["br i1 %jdone, label %osig, label %jloop", "osig:", f"%outrow = mul i64 %t, {IP}"]
    for v in range(IV):
        body += _sigmoid(f"%on{v}", f"os{v}") + [f"%ooi{v} = add i64 %outrow, {8 * v}"]
        body += _store(f"%os{v}r", "%out", f"%ooi{v}", f"ost{v}")
    body += ["br label %step.end", "step.end:", "%t.next = add i64 %t, 1"]
    body += [f"%tdone = icmp eq i64 %t.next, {L}", "br i1 %tdone, label %iter.end, label %step"]
    body += ["iter.end:", "%it.next = add i64 %it, 1", "%itdone = icmp eq i64 %it.next, %iters"]
    body += ["br i1 %itdone, label %done, label %iter", "done:", "ret void"]
    labels = {line[:-1] for line in body if line.endswith(":")}
    indented = [line if line[:-1] in labels else "  " + line for line in body]
    return "\n".join(
        [
            f"declare {V} @llvm.minnum.v8f32({V}, {V})",
            f"declare {V} @llvm.maxnum.v8f32({V}, {V})",
            f"declare {V} @llvm.fma.v8f32({V}, {V}, {V})",
            "define void @forward(i64 %iters, ptr noalias %pre, ptr noalias %mask, "
            "ptr noalias %wl, ptr noalias %wo, ptr noalias %bo, ptr noalias %first, "
            "ptr noalias %out, ptr noalias %hid, ptr noalias %x) {",
            "entry:",
            "  br label %iter",
            *indented,
            "}",
        ]
    )


def compiled_forward():
    """The IR compiled for this machine's processor (LLVM's -O3 pipeline), as a ctypes
    function, and the engine that owns its code (keep it alive while calling)."""
    llvm = importlib.import_module("llvmlite.binding")
    llvm.initialize_native_target()
    llvm.initialize_native_asmprinter()
    machine = llvm.Target.from_default_triple().create_target_machine(
        cpu=llvm.get_host_cpu_name(), features=llvm.get_host_cpu_features().flatten(), opt=3
    )
    module = llvm.parse_assembly(forward_ir())
    module.verify()
    builder = llvm.create_pass_builder(machine, llvm.create_pipeline_tuning_options(speed_level=3))
    builder.getModulePassManager().run(module, builder)
    engine = llvm.create_mcjit_compiler(module, machine)
    engine.finalize_object()
    pointer = ctypes.c_void_p
    signature = ctypes.CFUNCTYPE(None, ctypes.c_int64, *[pointer] * 9)
    return signature(engine.get_function_address("forward")), engine


def main() -> None:
    parser = argparse.ArgumentParser(description=str(__doc__).splitlines()[0])
    parser.add_argument("--repeats", type=int, default=30, help="timed calls of 100 passes each")
    args = parser.parse_args()
    try:
        forward, engine = compiled_forward()
    except ModuleNotFoundError:
        raise SystemExit("kernel_probe: needs llvmlite (.venv/bin/pip install llvmlite)") from None
    rng = np.random.default_rng(0)
    pre = rng.normal(size=(L, H)).astype(np.float32)
    mask = np.zeros((L, IP), np.float32)
    mask[:, :IO] = rng.random((L, IO)) > 0.1
    w_loop = (rng.normal(size=(IO, H)) * 0.3).astype(np.float32)
    w_out = np.zeros((H, IP), np.float32)
    w_out[:, :IO] = rng.normal(size=(H, IO)) * 0.3
    b_out = np.zeros(IP, np.float32)
    b_out[:IO] = rng.normal(size=IO)
    first = np.zeros(IP, np.float32)
    first[:IO] = rng.random(IO)
    out, hid, x = (
        np.zeros((L, IP), np.float32),
        np.zeros((L, H), np.float32),
        np.zeros(IP, np.float32),
    )
    arrays = (pre, mask, w_loop, w_out, b_out, first, out, hid, x)
    pointers = [a.ctypes.data_as(ctypes.c_void_p) for a in arrays]
    forward(1, *pointers)

    reference = np.zeros((L, IO))
    inputs = first[:IO] * mask[0, :IO]
    for t in range(L):
        if t:
            inputs = reference[t - 1] * mask[t, :IO]
        hidden = 1 / (1 + np.exp(-(pre[t] + inputs @ w_loop)))
        reference[t] = 1 / (1 + np.exp(-(hidden @ w_out[:, :IO] + b_out[:IO])))

    from rnnpb import _xla

    _xla.single_threaded()
    _xla.configure()
    import jax

    @jax.jit
    def xla_forward(pre, mask, w_loop, w_out, b_out, first):
        def step(previous, xs):
            pre_t, mask_t = xs
            hidden = jax.nn.sigmoid(pre_t + (previous * mask_t) @ w_loop)
            output = jax.nn.sigmoid(hidden @ w_out + b_out)
            return output, output

        def one_pass(_, start):  # each pass starts from the last one's last output
            _, outputs = jax.lax.scan(step, start, (pre, mask), unroll=5)
            return outputs[-1]

        return jax.lax.fori_loop(0, 100, one_pass, first)

    xla_args = (pre, mask[:, :IO], w_loop, w_out[:, :IO], b_out[:IO], first[:IO])
    jax.block_until_ready(xla_forward(*xla_args))
    ir_times, xla_times = [], []
    for _ in range(args.repeats):  # alternately, so that the machine's state is shared
        start = time.perf_counter()
        forward(100, *pointers)
        ir_times.append(time.perf_counter() - start)
        start = time.perf_counter()
        jax.block_until_ready(xla_forward(*xla_args))
        xla_times.append(time.perf_counter() - start)
    ir_ms, xla_ms = np.median(ir_times) * 1e3, np.median(xla_times) * 1e3
    print(f"window forward pass x100, LLVM IR (8-wide vectors): {ir_ms:.3f} ms median")
    print(f"the same in XLA:                                   {xla_ms:.3f} ms median")
    print(f"ratio XLA / IR: {xla_ms / ir_ms:.2f}")
    print(f"largest difference from float64 NumPy: {np.max(np.abs(out[:, :IO] - reference)):.2e}")
    del engine


if __name__ == "__main__":
    main()
