"""The learning iteration's kernel in LLVM's intermediate language: its sizes
(:class:`LearningShapes`) and its code (:func:`learning_ir`), written with the emitter of
:mod:`rnnpb.model._ir`. :mod:`rnnpb.model.native_learning` compiles it and runs it.

Layouts (float32, rows padded to whole 8-wide vectors): a step's inputs and outputs with the
context share one row of ``OP`` values — the inputs (or predictions) first, then the context —
so the context an output row holds is where the next input row wants it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from rnnpb.model._ir import (
    V,
    _broadcast_int,
    _Emitter,
    _int,
    _normal,
    _offsets,
    _padded,
    _pb_update,
    module,
)

GROUP = 4  # sequences that share each loaded weight vector

# The scalars the kernel reads, in the order of its first array.
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
