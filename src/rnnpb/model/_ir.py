"""The intermediate-language toolkit of the native loops (:mod:`rnnpb.model.native`, the on-line
regression's; :mod:`rnnpb.model.native_learning`, the learning iteration's): an emitter of LLVM
functions with explicit 8-wide vectors (:class:`_Emitter`), the sigmoid, eqs. 1–2
(:func:`_pb_update`) and JAX's normal draws (:func:`_normal`) in it, and :func:`build`, which
compiles a module with llvmlite for this machine's processor and keeps the machine code on disk.

``RNNPB_NATIVE=0`` turns the native loops off (:func:`enabled`); ``RNNPB_NATIVE_CPU`` names a
processor to compile for instead of this one (``haswell``: AVX2 code on a machine with
AVX-512), with that processor's own features.
"""

from __future__ import annotations

import hashlib
import importlib
import os
import struct
import threading
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb.model.equations import TANH_CLAMP, TANH_P, TANH_Q

V = "<8 x float>"


def _padded(n: int) -> int:
    return 8 * -(-n // 8)


def _offsets(parts: dict[str, int]) -> dict[str, tuple[int, int]]:
    layout, offset = {}, 0
    for name, size in parts.items():
        layout[name] = (offset, size)
        offset += size
    layout["total"] = (offset, 0)
    return layout


def _vector_constant(value: float) -> str:
    """An <8 x float> constant (LLVM writes floats as the hex of their double)."""
    return "<" + ", ".join([f"float {_float(value)}"] * 8) + ">"


def _float(value: float) -> str:
    bits = struct.unpack(">Q", struct.pack(">d", float(np.float32(value))))[0]
    return f"0x{bits:016X}"


class _Emitter:
    """Builds one function's body: unique names, blocks, counted loops with carried values."""

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.count = 0
        self.current = "entry"

    def name(self, stem: str) -> str:
        self.count += 1
        return f"%{stem}.{self.count}"

    def label(self, stem: str) -> str:
        self.count += 1
        return f"{stem}.{self.count}"

    def emit(self, line: str) -> None:
        self.lines.append("  " + line)

    def block(self, label: str) -> None:
        self.lines.append(f"{label}:")
        self.current = label

    def op(self, stem: str, expression: str) -> str:
        result = self.name(stem)
        self.emit(f"{result} = {expression}")
        return result

    # vectors
    def fmul(self, a: str, b: str) -> str:
        return self.op("m", f"fmul fast {V} {a}, {b}")

    def fadd(self, a: str, b: str) -> str:
        return self.op("a", f"fadd fast {V} {a}, {b}")

    def fsub(self, a: str, b: str) -> str:
        return self.op("s", f"fsub fast {V} {a}, {b}")

    def fma(self, a: str, b: str, c: str) -> str:
        return self.op("f", f"call fast {V} @llvm.fma.v8f32({V} {a}, {V} {b}, {V} {c})")

    def address(self, base: str, index: str | int) -> str:
        return self.op("p", f"getelementptr inbounds float, ptr {base}, i64 {index}")

    def load(self, base: str, index: str | int) -> str:
        return self.op("v", f"load {V}, ptr {self.address(base, index)}, align 4")

    def load_scalar(self, base: str, index: str | int) -> str:
        return self.op("x", f"load float, ptr {self.address(base, index)}, align 4")

    def store(self, value: str, base: str, index: str | int) -> None:
        self.emit(f"store {V} {value}, ptr {self.address(base, index)}, align 4")

    def broadcast(self, scalar: str) -> str:
        first = self.op("b", f"insertelement {V} undef, float {scalar}, i32 0")
        return self.op("b", f"shufflevector {V} {first}, {V} undef, <8 x i32> zeroinitializer")

    def int_op(self, stem: str, operation: str, a: str | int, b: str | int) -> str:
        return self.op(stem, f"{operation} i64 {a}, {b}")

    def one_minus(self, x: str) -> str:
        return self.fsub(_vector_constant(1.0), x)

    def sigmoid(self, x: str) -> str:
        half = _vector_constant(0.5)
        t = self.fmul(x, half)
        t = self.op(
            "c", f"call fast {V} @llvm.minnum.v8f32({V} {t}, {V} {_vector_constant(TANH_CLAMP)})"
        )
        t = self.op(
            "c", f"call fast {V} @llvm.maxnum.v8f32({V} {t}, {V} {_vector_constant(-TANH_CLAMP)})"
        )
        t2 = self.fmul(t, t)
        polynomials = []
        for coefficients in (TANH_P, TANH_Q):
            value = _vector_constant(coefficients[0])
            for c in coefficients[1:]:
                value = self.fma(t2, value, _vector_constant(c))
            polynomials.append(value)
        ratio = self.op("d", f"fdiv fast {V} {self.fmul(t, polynomials[0])}, {polynomials[1]}")
        return self.fma(ratio, half, half)

    def tanh(self, x: str) -> str:
        """tanh(x) = 2 sigmoid(2x) - 1."""
        value = self.sigmoid(self.fmul(x, _vector_constant(2.0)))
        return self.fma(value, _vector_constant(2.0), _vector_constant(-1.0))

    def loop(self, count: str | int, carried: list[str], body: Any) -> list[str]:
        """A counted loop ``for i in range(count)`` (``count`` ≥ 1) whose ``body(i, values)``
        emits its code and returns the carried vectors' next values; returns their last."""
        before = self.current
        head, end = self.label("loop"), self.label("done")
        i, following = self.name("i"), self.name("i")
        self.emit(f"br label %{head}")
        self.block(head)
        phi_at = len(self.lines)
        values = [self.name("phi") for _ in carried]
        updated = body(i, values)
        latch = self.current
        phis = [f"  {i} = phi i64 [0, %{before}], [{following}, %{latch}]"]
        phis += [
            f"  {v} = phi {V} [{start}, %{before}], [{new}, %{latch}]"
            for v, start, new in zip(values, carried, updated, strict=True)
        ]
        self.lines[phi_at:phi_at] = phis
        self.emit(f"{following} = add i64 {i}, 1")
        finished = self.op("e", f"icmp eq i64 {following}, {count}")
        self.emit(f"br i1 {finished}, label %{end}, label %{head}")
        self.block(end)
        return updated

    def products(
        self,
        sums: list[list[str]],
        count: int,
        scalars: Sequence[tuple[str, str | int]],
        weights: str,
        width: int,
        chains: int = 1,
    ) -> list[list[str]]:
        """For each session ``g``: ``sums[g][v] + Σ_k x_g[start_g + k] · weights[k, 8v : 8v
        + 8]`` for ``k < count``, where ``scalars[g]`` is ``(x_g, start_g)``; the sums held in
        registers through the loop, each weight vector loaded once for every session. With
        ``chains`` 2, where the registers allow (the sums of one session, or of two of one
        vector), the even and the odd inputs go to two sets of sums added at the end, so that a
        sum waits for one multiply-add in two."""
        group, vectors = len(sums), len(sums[0])
        size = group * vectors

        def accumulate(k: str | int, flat: list[str]) -> list[str]:
            current = [flat[g * vectors : (g + 1) * vectors] for g in range(group)]
            factors = [
                self.broadcast(self.load_scalar(base, self.int_op("k", "add", start, k)))
                for base, start in scalars
            ]
            row = self.int_op("r", "mul", k, width)
            updated = [list(values) for values in current]
            for v in range(vectors):
                weight = self.load(weights, self.int_op("w", "add", row, 8 * v))
                for g in range(group):
                    updated[g][v] = self.fma(factors[g], weight, current[g][v])
            return [value for values in updated for value in values]

        start = [value for values in sums for value in values]
        if chains < 2 or count < 2 or 2 * size > 12:
            flat = self.loop(count, start, accumulate)
        else:

            def pair(i: str, flat: list[str]) -> list[str]:
                even = self.int_op("k", "mul", i, 2)
                odd = self.int_op("k", "add", even, 1)
                return accumulate(even, flat[:size]) + accumulate(odd, flat[size:])

            both = self.loop(count // 2, start + ["zeroinitializer"] * size, pair)
            flat = both[:size]
            if count % 2:
                flat = accumulate(count - 1, flat)
            flat = [self.fadd(a, b) for a, b in zip(flat, both[size:], strict=True)]
        return [flat[g * vectors : (g + 1) * vectors] for g in range(group)]


def module(signature: str, e: _Emitter) -> str:
    """A module of one function, ``void @signature``, whose body ``e`` holds (its return
    added), with the intrinsics the emitter's code calls declared."""
    e.emit("ret void")
    return "\n".join(
        [
            f"declare {V} @llvm.minnum.v8f32({V}, {V})",
            f"declare {V} @llvm.maxnum.v8f32({V}, {V})",
            f"declare {V} @llvm.fma.v8f32({V}, {V}, {V})",
            f"declare {V} @llvm.sqrt.v8f32({V})",
            f"declare float @llvm.vector.reduce.fadd.v8f32(float, {V})",
            "declare <8 x i32> @llvm.fshl.v8i32(<8 x i32>, <8 x i32>, <8 x i32>)",
            f"define void @{signature} {{",
            "entry:",
            *e.lines,
            "}",
        ]
    )


def _pb_update(
    e: _Emitter,
    s: dict[str, str],
    b: dict[str, str],
    coefficient: dict[str, str],
    n: str,
    pv: int,
    pp: int,
) -> None:
    """Eqs. 1–2 over the window's ``n`` valid steps (:func:`rnnpb.model.parametric_bias.
    pb_update`): the error term summed over the integration length by a cumulative sum, the
    second difference held flat at the ends, momentum."""
    zero = "zeroinitializer"
    for v in range(pv):
        e.store(zero, s["cum"], 8 * v)

    def cumulate(t: str, running: list[str]) -> list[str]:
        row = e.int_op("q", "mul", t, pp)
        following = e.int_op("q", "add", row, pp)
        updated = []
        for v in range(pv):
            total = e.fadd(running[v], e.load(s["grad"], e.int_op("q", "add", row, 8 * v)))
            e.store(total, s["cum"], e.int_op("q", "add", following, 8 * v))
            updated.append(total)
        return updated

    e.loop(n, [zero] * pv, cumulate)

    def update(t: str, _: list[str]) -> list[str]:
        upper = e.int_op("u", "add", t, "%half")
        upper = e.int_op("u", "add", upper, 1)
        upper = e.op(
            "u", f"select i1 {e.op('u', f'icmp slt i64 {upper}, {n}')}, i64 {upper}, i64 {n}"
        )
        lower = e.int_op("u", "sub", t, "%half")
        lower = e.op("u", f"select i1 {e.op('u', f'icmp sgt i64 {lower}, 0')}, i64 {lower}, i64 0")
        before = e.int_op("u", "sub", t, 1)
        before = e.op("u", f"select i1 {e.op('u', f'icmp eq i64 {t}, 0')}, i64 0, i64 {before}")
        after = e.int_op("u", "add", t, 1)
        after = e.op(
            "u", f"select i1 {e.op('u', f'icmp slt i64 {after}, {n}')}, i64 {after}, i64 {t}"
        )
        rows = {
            name: e.int_op("u", "mul", index, pp)
            for name, index in (
                ("t", t),
                ("upper", upper),
                ("lower", lower),
                ("before", before),
                ("after", after),
            )
        }
        for v in range(pv):
            at = {name: e.int_op("u", "add", row, 8 * v) for name, row in rows.items()}
            integral = e.fsub(e.load(s["cum"], at["upper"]), e.load(s["cum"], at["lower"]))
            rho = e.load(b["rho"], at["t"])
            smooth = e.fadd(e.load(b["rho"], at["after"]), e.load(b["rho"], at["before"]))
            smooth = e.fsub(smooth, e.fadd(rho, rho))
            delta = e.fma(coefficient["k_nb"], smooth, e.fmul(coefficient["k_bp"], integral))
            velocity = e.fmul(coefficient["momentum"], e.load(b["velocity"], at["t"]))
            velocity = e.fma(coefficient["rate"], delta, velocity)
            e.store(velocity, b["velocity"], at["t"])
            e.store(e.fadd(rho, velocity), s["rnew"], at["t"])
        return []

    e.loop(n, [], update)

    def copy(t: str, _: list[str]) -> list[str]:
        row = e.int_op("q", "mul", t, pp)
        for v in range(pv):
            index = e.int_op("q", "add", row, 8 * v)
            e.store(e.load(s["rnew"], index), b["rho"], index)
        return []

    e.loop(n, [], copy)


def enabled() -> bool:
    """Whether the native loop runs: llvmlite importable and ``RNNPB_NATIVE`` not ``0``."""
    if os.environ.get("RNNPB_NATIVE", "1") == "0":
        return False
    try:
        importlib.import_module("llvmlite.binding")
    except ImportError:
        return False
    return True


def build(ir: str, name: str, signature: Any) -> tuple[Any, Any]:
    """The function ``name`` of the module ``ir``, compiled for this machine's processor
    (LLVM's -O3 pipeline), as a ctypes function of ``signature``; and the engine that owns
    its code (keep it as long as the function).

    The machine code is kept on disk beside the compiled JAX programs (:func:`object_folder`),
    named by a digest of the module, the processor, its features and LLVM's version, so that
    a later process loads it instead of compiling it again; a file that does not match its
    own digest is compiled again and replaced."""
    llvm = importlib.import_module("llvmlite.binding")
    llvm.initialize_native_target()
    llvm.initialize_native_asmprinter()
    cpu, features = llvm.get_host_cpu_name(), llvm.get_host_cpu_features().flatten()
    if os.environ.get("RNNPB_NATIVE_CPU"):  # another processor's code, with its own features
        cpu, features = os.environ["RNNPB_NATIVE_CPU"], ""
    target = llvm.Target.from_default_triple()
    machine = target.create_target_machine(cpu=cpu, features=features, opt=3)
    version = importlib.import_module("llvmlite").__version__
    digest = hashlib.sha256(
        "\n".join([version, str(llvm.get_default_triple()), cpu, features, ir]).encode()
    ).hexdigest()
    folder = object_folder()
    path = None if folder is None else folder / f"{name}-{digest[:32]}.o"
    code = _read_object(path)
    if code is None:
        module = llvm.parse_assembly(ir)
        module.verify()
        options = llvm.create_pipeline_tuning_options(speed_level=3)
        builder = llvm.create_pass_builder(machine, options)
        builder.getModulePassManager().run(module, builder)
        code = machine.emit_object(module)
        _write_object(path, code)
    engine = llvm.create_mcjit_compiler(llvm.parse_assembly(""), machine)
    engine.add_object_file(llvm.ObjectFileRef.from_data(code))
    engine.finalize_object()
    address = engine.get_function_address(name)
    if not address:
        raise RuntimeError(f"the compiled code has no function {name!r}")
    return signature(address), engine


_OBJECT_MAGIC = b"rnnpb native object 1\n"


def object_folder() -> Path | None:
    """Where compiled native code is kept: ``native`` in the folder of the compiled JAX
    programs (``rnnpb._xla.cache_folder``: ``RNNPB_XLA_CACHE`` moves it, ``0`` turns both
    off); None when off or when the folder cannot be made (a read-only home: compiled in
    every process, silently)."""
    from rnnpb import _xla

    base = _xla.cache_folder()
    if base is None:
        return None
    folder = base / "native"
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    return folder


def _read_object(path: Path | None) -> bytes | None:
    """The machine code kept at ``path``, or None: no file, unreadable, or not matching its
    digest (a file cut short or damaged)."""
    if path is None:
        return None
    try:
        data = path.read_bytes()
    except OSError:
        return None
    head = len(_OBJECT_MAGIC)
    digest, code = data[head : head + 32], data[head + 32 :]
    if data[:head] != _OBJECT_MAGIC or hashlib.sha256(code).digest() != digest or not code:
        return None
    return code


def _write_object(path: Path | None, code: bytes) -> None:
    """Keep ``code`` at ``path`` whole or not at all (a temporary file renamed over it); a
    folder that cannot be written to is left alone."""
    if path is None:
        return
    temporary = path.with_name(f".{path.name}.{os.getpid()}.{threading.get_ident()}")
    try:
        temporary.write_bytes(_OBJECT_MAGIC + hashlib.sha256(code).digest() + code)
        os.replace(temporary, path)
    except OSError:
        temporary.unlink(missing_ok=True)


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
