"""How fast the on-line regression's window passes can run on one core: LLVM IR with explicit
8-wide vectors, compiled at run time by llvmlite, beside the regression loop XLA runs today.

A probe for a native kernel of the on-line regression that needs no C compiler: llvmlite is a
wheel with LLVM inside. The window is a real one (L = 30 steps, 42 inputs, 40 hidden units, 42
outputs): the model's mirror system after 40 steps of its first pattern. In the IR the hidden
layer's 40 sums are five 8-wide vectors and the outputs' 42 six, carried in registers through
the products' loops, and the sigmoid is a rational function (the form Eigen gives tanh); the
backward pass carries the inputs' error the same way. Prints, timed alternately, 100 forward
passes, 100 forward and backward passes, and 100 iterations of the regression loop as the
on-line step runs it in XLA (which also updates the PB and the onset: a few per cent more
arithmetic), and the IR's largest difference from float64 NumPy. Needs llvmlite, which the
package does not depend on::

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


def _products(
    name: str,
    entry: str,
    exit_: str,
    count: int,
    scalars: str,
    weights: str,
    width: int,
    initial: list[str],
    out: str,
    scalar_row: str | None = None,
) -> list[str]:
    """IR lines: a loop over ``count`` rows that adds scalar x weights' row to
    ``len(initial)`` 8-wide sums held in registers (phi values starting at ``initial``, last
    values ``%{out}0``, ``%{out}1``, ...). The scalars are at ``scalars`` (from index
    ``scalar_row`` when given), the rows of ``width`` floats at ``weights``; ``entry`` is the
    block the loop is entered from, ``exit_`` the block it opens after."""
    i = f"%{name}"
    lines = [f"br label %{name}.loop", f"{name}.loop:"]
    lines.append(f"{i} = phi i64 [0, %{entry}], [{i}.next, %{name}.loop]")
    lines += [
        f"%{name}s{v} = phi {V} [{start}, %{entry}], [%{out}{v}, %{name}.loop]"
        for v, start in enumerate(initial)
    ]
    index = i
    if scalar_row is not None:
        index = f"{i}.row"
        lines.append(f"{index} = add i64 {scalar_row}, {i}")
    lines += [
        f"{i}.p = getelementptr inbounds float, ptr {scalars}, i64 {index}",
        f"{i}.s = load float, ptr {i}.p",
        *_broadcast(f"{i}.s", f"{name}.b"),
        f"{i}.w = mul i64 {i}, {width}",
    ]
    for v in range(len(initial)):
        lines.append(f"{i}.wi{v} = add i64 {i}.w, {8 * v}")
        lines += _load(f"{name}.wv{v}", weights, f"{i}.wi{v}")
        lines.append(
            f"%{out}{v} = call fast {V} @llvm.fma.v8f32({V} %{name}.b, {V} %{name}.wv{v}, "
            f"{V} %{name}s{v})"
        )
    lines += [f"{i}.next = add i64 {i}, 1", f"{i}.done = icmp eq i64 {i}.next, {count}"]
    return [*lines, f"br i1 {i}.done, label %{exit_}, label %{name}.loop", f"{exit_}:"]


def forward_ir(with_backward: bool = False) -> str:
    """``forward(iters, pre, mask, w_loop, w_out, b_out, first, out, hid, x, ...)``: ``iters``
    forward passes of the window (the arrays as :func:`main` lays them out); with
    ``with_backward``, each followed by the back-propagation of the sensory error through the
    window (``..., w_out_t, w_loop_t, target, target_mask, next_mask, d_pre, g, dh``)."""
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
    # the hidden layer's sums: five vectors in registers
    sums = [f"%pv{v}" for v in range(HV)]
    body += _products("k", "hidden", "hsig", IO, "%x", "%wl", H, sums, "an")
    for v in range(HV):
        body += _sigmoid(f"%an{v}", f"hs{v}") + [f"%hi{v} = add i64 %prow, {8 * v}"]
        body += _store(f"%hs{v}r", "%hid", f"%hi{v}", f"hst{v}")
    for v in range(IV):
        body += _load(f"bv{v}", "%bo", str(8 * v))
    # the outputs' sums: six vectors in registers
    sums = [f"%bv{v}" for v in range(IV)]
    body += _products("j", "hsig", "osig", H, "%hid", "%wo", IP, sums, "on", scalar_row="%prow")
    body += [f"%outrow = mul i64 %t, {IP}"]
    for v in range(IV):
        body += _sigmoid(f"%on{v}", f"os{v}") + [f"%ooi{v} = add i64 %outrow, {8 * v}"]
        body += _store(f"%os{v}r", "%out", f"%ooi{v}", f"ost{v}")
    body += ["br label %step.end", "step.end:", "%t.next = add i64 %t, 1"]
    after = "back" if with_backward else "iter.end"
    body += [f"%tdone = icmp eq i64 %t.next, {L}", f"br i1 %tdone, label %{after}, label %step"]
    if with_backward:
        body += _backward()
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
            "ptr noalias %out, ptr noalias %hid, ptr noalias %x"
            + (
                ", ptr noalias %wot, ptr noalias %wlt, ptr noalias %target, ptr noalias %tmask, "
                "ptr noalias %nmask, ptr noalias %dpre, ptr noalias %g, ptr noalias %dh"
                if with_backward
                else ""
            )
            + ") {",
            "entry:",
            "  br label %iter",
            *indented,
            "}",
        ]
    )


def _backward() -> list[str]:
    """IR lines: the window's backward pass, from the last step to the first (the sums of the
    hidden layer's five vectors and of the inputs' six in registers, as in the forward pass)."""
    zero = "zeroinitializer"
    body = ["back:", "br label %bstep", "bstep:"]
    body.append(f"%bt = phi i64 [{L - 1}, %back], [%bt.next, %bend]")
    body += [f"%din{v} = phi {V} [{zero}, %back], [%dn{v}, %bend]" for v in range(IV)]
    body += [f"%brow = mul i64 %bt, {IP}", f"%hrow = mul i64 %bt, {H}"]
    for v in range(IV):  # g = (out - target) * target_mask + d_in * next_mask, times o (1 - o)
        body.append(f"%bi{v} = add i64 %brow, {8 * v}")
        for name, base in (("bo", "%out"), ("bx", "%target"), ("bm", "%tmask"), ("bn", "%nmask")):
            body += _load(f"{name}{v}", base, f"%bi{v}")
        body += [
            f"%be{v} = fsub fast {V} %bo{v}, %bx{v}",
            f"%bd{v} = fmul fast {V} %be{v}, %bm{v}",
            f"%bc{v} = call fast {V} @llvm.fma.v8f32({V} %din{v}, {V} %bn{v}, {V} %bd{v})",
            f"%bq{v} = fsub fast {V} {_vector(1.0)}, %bo{v}",
            f"%bs{v} = fmul fast {V} %bo{v}, %bq{v}",
            f"%bg{v} = fmul fast {V} %bc{v}, %bs{v}",
        ]
        body += _store(f"%bg{v}", "%g", str(8 * v), f"bgs{v}")
    # d_hidden = g @ w_out.T
    body += _products("ib", "bstep", "hb.done", IO, "%g", "%wot", H, [zero] * HV, "hn")
    for v in range(HV):  # times h (1 - h): the error at the hidden layer's input
        body.append(f"%hbi{v} = add i64 %hrow, {8 * v}")
        body += _load(f"hv{v}", "%hid", f"%hbi{v}")
        body += [
            f"%hq{v} = fsub fast {V} {_vector(1.0)}, %hv{v}",
            f"%hs{v}b = fmul fast {V} %hv{v}, %hq{v}",
            f"%dp{v} = fmul fast {V} %hn{v}, %hs{v}b",
        ]
        body += _store(f"%dp{v}", "%dpre", f"%hbi{v}", f"dps{v}")
        body += _store(f"%dp{v}", "%dh", str(8 * v), f"dhs{v}")
    # d_input = d_hidden @ w_loop.T
    body += _products("jb", "hb.done", "bend", H, "%dh", "%wlt", IP, [zero] * IV, "dn")
    body += ["%bt.next = sub i64 %bt, 1", "%btdone = icmp eq i64 %bt, 0"]
    body += ["br i1 %btdone, label %iter.end, label %bstep"]
    return body


def compiled_forward(with_backward: bool = False):
    """The IR compiled for this machine's processor (LLVM's -O3 pipeline), as a ctypes
    function, and the engine that owns its code (keep it alive while calling)."""
    llvm = importlib.import_module("llvmlite.binding")
    llvm.initialize_native_target()
    llvm.initialize_native_asmprinter()
    machine = llvm.Target.from_default_triple().create_target_machine(
        cpu=llvm.get_host_cpu_name(), features=llvm.get_host_cpu_features().flatten(), opt=3
    )
    module = llvm.parse_assembly(forward_ir(with_backward))
    module.verify()
    builder = llvm.create_pass_builder(machine, llvm.create_pipeline_tuning_options(speed_level=3))
    builder.getModulePassManager().run(module, builder)
    engine = llvm.create_mcjit_compiler(module, machine)
    engine.finalize_object()
    pointer = ctypes.c_void_p
    signature = ctypes.CFUNCTYPE(None, ctypes.c_int64, *[pointer] * (17 if with_backward else 9))
    return signature(engine.get_function_address("forward")), engine


def _window(model_path: str | None):
    """A real window: the model's mirror system after 40 steps of the demonstrator's first
    pattern and one more observation shifted in; the project's regression loop over it (100
    iterations of ``window.gradients`` and the PB update, as ``online_step`` runs them); and the
    IR's arrays for the same window."""
    from rnnpb import _xla

    _xla.single_threaded()
    _xla.configure()
    import jax
    import jax.numpy as jnp

    from rnnpb.demonstrator import held_scenario
    from rnnpb.model import MirrorSystem, OnlineConfig, TrainedModel, window
    from rnnpb.model import online as online_module
    from rnnpb.model.parametric_bias import pb_update
    from rnnpb.models import SHIPPED_MODEL

    model = TrainedModel.load(model_path or SHIPPED_MODEL)
    config = OnlineConfig.for_model(model).config
    mirror = MirrorSystem(model, config)
    hands = held_scenario(model.patterns[0], n_steps=42, seed=3).sensory
    for u in hands[:-1]:
        mirror.step(u)
    u, seen = hands[-1].astype(np.float32), np.isfinite(hands[-1])
    state = online_module._shift_in(mirror._state, jnp.asarray(u), jnp.asarray(seen))
    params = mirror._params
    length = state.sensory.shape[0]
    valid = jnp.arange(length) < state.n

    @jax.jit
    def project_loop(state):
        def iteration(_, carry):
            rho, velocity, context, motor = carry
            g_rho, g_context, g_motor = window.gradients(params, state, rho, context, motor, config)
            rho, velocity = pb_update(rho, velocity, g_rho, config.pb, valid)
            context = context - config.onset_learning_rate * g_context
            motor = motor - config.onset_learning_rate * g_motor
            return rho, velocity, context, motor

        start = (state.rho, state.rho_velocity, state.onset_context, state.onset_motor)
        return jax.lax.fori_loop(0, 100, iteration, start)

    # The IR's arrays (rnnpb.model.window._window_terms, in NumPy)
    n_s, n_m = model.network.sensory_size, model.network.motor_size
    n_p = model.network.pb_size
    w_in, w_out_full = np.asarray(params.w_in), np.asarray(params.w_out)
    w_u, w_m = w_in[:n_s], w_in[n_s : n_s + n_m]
    w_p, w_c = w_in[n_s + n_m : n_s + n_m + n_p], w_in[n_s + n_m + n_p :]
    sensory, rho = np.asarray(state.sensory), np.asarray(state.rho)
    n = int(state.n)
    seen_w = np.asarray(state.seen) & (np.arange(length) < n)[:, None]
    pre = np.where(seen_w, sensory, 0.0) @ w_u + (1 / (1 + np.exp(-rho))) @ w_p
    pre = (pre + np.asarray(params.b_h)).astype(np.float32)
    closed = config.motor_input == "closed_loop"
    mask = np.zeros((L, IP), np.float32)
    mask[:, :n_s] = ~seen_w
    mask[:, n_s : n_s + n_m] = 1.0 if closed else 0.0
    mask[:, n_s + n_m : IO] = 1.0
    first = np.zeros(IP, np.float32)
    first[:n_s] = 0.5
    first[n_s : n_s + n_m] = 1 / (1 + np.exp(-np.asarray(state.onset_motor)))
    first[n_s + n_m : IO] = 1 / (1 + np.exp(-np.asarray(state.onset_context)))
    w_loop = np.concatenate([w_u, w_m, w_c]).astype(np.float32)
    w_out = np.zeros((H, IP), np.float32)
    w_out[:, :IO] = w_out_full
    b_out = np.zeros(IP, np.float32)
    b_out[:IO] = np.asarray(params.b_out)
    target = np.zeros((L, IP), np.float32)
    target[:-1, :n_s] = sensory[1:]
    target_mask = np.zeros((L, IP), np.float32)
    steps = np.arange(L - 1) < n - 1
    target_mask[:-1, :n_s] = steps[:, None] & np.asarray(state.seen)[1:]
    arrays = (pre, mask, w_loop, w_out, b_out, first, target, target_mask)
    return (lambda: jax.block_until_ready(project_loop(state))), arrays


def main() -> None:
    parser = argparse.ArgumentParser(description=str(__doc__).splitlines()[0])
    parser.add_argument("--model", help="a learned model (default: the shipped one)")
    parser.add_argument("--repeats", type=int, default=30, help="timed calls of 100 passes each")
    args = parser.parse_args()
    try:
        forward, forward_engine = compiled_forward()
        both, both_engine = compiled_forward(with_backward=True)
    except ModuleNotFoundError:
        raise SystemExit("kernel_probe: needs llvmlite (.venv/bin/pip install llvmlite)") from None
    project_loop, arrays = _window(args.model)
    pre, mask, w_loop, w_out, b_out, first, target, target_mask = arrays
    # The backward pass's arrays: the weights transposed, the next step's mask (none after
    # the last), scratch.
    w_out_t = np.ascontiguousarray(w_out[:, :IO].T)
    w_loop_t = np.zeros((H, IP), np.float32)
    w_loop_t[:, :IO] = w_loop.T
    next_mask = np.zeros((L, IP), np.float32)
    next_mask[:-1] = mask[1:]

    def scratch():
        return np.zeros((L, IP), np.float32), np.zeros((L, H), np.float32), np.zeros(IP, np.float32)

    out, hid, x = scratch()
    weights = (pre, mask, w_loop, w_out, b_out, first)
    out_b, hid_b, x_b = scratch()
    d_pre, g, dh = np.zeros((L, H), np.float32), np.zeros(IP, np.float32), np.zeros(H, np.float32)
    both_arrays = (*weights, out_b, hid_b, x_b, w_out_t, w_loop_t, target, target_mask)
    both_arrays = (*both_arrays, next_mask, d_pre, g, dh)

    def pointers(arrays):
        return [a.ctypes.data_as(ctypes.c_void_p) for a in arrays]

    fwd_pointers, both_pointers = pointers((*weights, out, hid, x)), pointers(both_arrays)
    forward(1, *fwd_pointers)
    both(1, *both_pointers)

    # float64 NumPy: the forward pass and the backward pass of the same window
    ref_out, ref_hid = np.zeros((L, IO)), np.zeros((L, H))
    inputs = first[:IO] * mask[0, :IO]
    for t in range(L):
        if t:
            inputs = ref_out[t - 1] * mask[t, :IO]
        ref_hid[t] = 1 / (1 + np.exp(-(pre[t] + inputs @ w_loop)))
        ref_out[t] = 1 / (1 + np.exp(-(ref_hid[t] @ w_out[:, :IO] + b_out[:IO])))
    ref_d_pre, d_input = np.zeros((L, H)), np.zeros(IO)
    for t in range(L - 1, -1, -1):
        error = (ref_out[t] - target[t, :IO]) * target_mask[t, :IO]
        grad = (error + d_input * next_mask[t, :IO]) * ref_out[t] * (1 - ref_out[t])
        ref_d_pre[t] = (grad @ w_out[:, :IO].T) * ref_hid[t] * (1 - ref_hid[t])
        d_input = ref_d_pre[t] @ w_loop.T

    project_loop()
    times: dict[str, list[float]] = {"forward": [], "both": [], "project": []}
    calls = {
        "forward": lambda: forward(100, *fwd_pointers),
        "both": lambda: both(100, *both_pointers),
        "project": project_loop,
    }
    for _ in range(args.repeats):  # alternately, so that the machine's state is shared
        for name, call in calls.items():
            start = time.perf_counter()
            call()
            times[name].append(time.perf_counter() - start)
    ms = {name: float(np.median(t)) * 1e3 for name, t in times.items()}
    print("100 passes over a real window (L = 30) on one core, medians:")
    print(f"  forward pass, LLVM IR (8-wide vectors):           {ms['forward']:.3f} ms")
    print(f"  forward and backward pass, LLVM IR:               {ms['both']:.3f} ms")
    print(
        f"  the regression loop (XLA: gradients, PB update): {ms['project']:.3f} ms "
        f"({ms['project'] / ms['both']:.2f}x the IR's forward and backward)"
    )
    print(
        "largest difference from float64 NumPy: outputs "
        f"{np.max(np.abs(out[:, :IO] - ref_out)):.2e}, backward errors "
        f"{np.max(np.abs(d_pre - ref_d_pre)):.2e} (largest {np.max(np.abs(ref_d_pre)):.2e})"
    )
    del forward_engine, both_engine


if __name__ == "__main__":
    main()
