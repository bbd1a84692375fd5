"""The learning phase (Ito & Tani 2004, sections 2.2–2.3): BPTT over whole sequences.

The weights are shared by all training sequences; each sequence has its own PB profile
``p_t = sigmoid(rho_t)`` (eqs. 1–3, the window being the whole sequence) and, optionally, its
own learned initial context. Each iteration runs every sequence open loop (teacher forced),
back-propagates the squared prediction error through time, and updates

* the weights (and initial contexts) by gradient descent with momentum — the paper's — or Adam;
* each sequence's ``rho`` profile by eqs. 1–2 — or, for a sequence whose PB is held (a
  consolidation keeping the old patterns' PBs, :class:`WarmStart`), not at all.

This module is the pure part: the settings, the training data as arrays, the error, and one
compiled chunk of iterations (state in, state out). The driver that runs the chunks with a
progress bar, a clock and checkpoints is :func:`rnnpb.model.training.train`.
"""

from __future__ import annotations

import functools
import hashlib
from collections.abc import Callable, Mapping
from collections.abc import Sequence as SequenceABC
from dataclasses import InitVar, asdict, dataclass, field, replace
from functools import cache
from typing import Any, Literal, NamedTuple, cast

import jax
import jax.numpy as jnp
import numpy as np
import optax

from rnnpb.errors import ConfigError, DataFileError
from rnnpb.model._tuned import Tuning, section_values, settle, tuning_of
from rnnpb.model._tuned import with_tuning as _with_tuning
from rnnpb.model.network import NetworkConfig, Params, init_params, logit_numpy, open_loop
from rnnpb.model.parametric_bias import PBUpdateConfig, pb_update
from rnnpb.presets import Preset, load_preset
from rnnpb.sequences import Sequence
from rnnpb.vectors import MOTOR_NAMES, SENSORY_NAMES, SENSORY_SIZE

_DEFAULT = section_values("paper", "learning")
_USER = ("iterations", "input_noise", "seed", "checkpoint_every")


@cache
def _preset_tuning(preset: str) -> Tuning:
    values = section_values(preset, "learning")
    return Tuning(preset, {k: v for k, v in values.items() if k not in _USER})


@dataclass(frozen=True)
class TrainConfig:
    """How to learn.

    ``TrainConfig.paper()`` (the plain constructor's) is the paper's algorithm: gradient
    descent with momentum, no input noise, 50,000 iterations, l = 20. ``TrainConfig.fast()``
    is the fast preset: Adam with noise on the teacher-forced inputs, 3,000 iterations.

    Settings a user changes
    -----------------------
    iterations : int
        Learning iterations.
    input_noise : float
        Standard deviation of the noise on the teacher-forced inputs (normalized units).
    seed : int
        The random seed: weights, PBs and noise. A seeded run repeats bit for bit.
    checkpoint_every : int
        Iterations between checkpoints (``rnnpb train --resume``).

    Every other field is tuned: read from the learning preset's ``[learning]`` section (its
    evidence beside it), shown read-only, changed by :meth:`with_tuning`: ``optimizer``
    (``"momentum"``, the paper's, or ``"adam"``), ``learning_rate`` and ``momentum`` of the
    weights, ``pb`` (the PB update's coefficients, eqs. 1–2), ``learn_initial_context``
    (each sequence's initial context learned) and ``chunk_iterations`` (iterations per
    compiled call, between progress reports).
    """

    iterations: int = _DEFAULT["iterations"]
    optimizer: Literal["momentum", "adam"] = field(init=False, repr=False)
    learning_rate: float = field(init=False, repr=False)
    momentum: float = field(init=False, repr=False)
    pb: PBUpdateConfig = field(init=False, repr=False)
    input_noise: float = _DEFAULT["input_noise"]
    learn_initial_context: bool = field(init=False, repr=False)
    seed: int = 0
    chunk_iterations: int = field(init=False, repr=False)
    checkpoint_every: int = _DEFAULT["checkpoint_every"]
    _tuning: InitVar[Mapping[str, Any] | None] = None

    def __post_init__(self, _tuning: Mapping[str, Any] | None) -> None:
        settle(self, _tuning, _preset_tuning("paper"), PBUpdateConfig)
        if self.iterations < 0:
            raise ConfigError(f"iterations must be >= 0, got {self.iterations}")
        if self.optimizer not in ("momentum", "adam"):
            raise ConfigError(f"optimizer must be 'momentum' or 'adam', got {self.optimizer!r}")
        if not self.learning_rate > 0:
            raise ConfigError(f"learning_rate must be > 0, got {self.learning_rate}")
        if not 0 <= self.momentum < 1:
            raise ConfigError(f"momentum must be in [0, 1), got {self.momentum}")
        if self.input_noise < 0:
            raise ConfigError(f"input_noise must be >= 0, got {self.input_noise}")
        if self.chunk_iterations < 1 or self.checkpoint_every < 1:
            raise ConfigError("chunk_iterations and checkpoint_every must be >= 1")

    @property
    def tuning(self) -> Tuning:
        """The tuned values and the preset they were read from."""
        return tuning_of(self)

    @property
    def preset(self) -> str:
        """The learning preset this learning was made from (``"paper"`` or ``"fast"``)."""
        return self.tuning.preset

    def with_tuning(self, **changes: Any) -> TrainConfig:
        """This learning with tuned values changed, for research: e.g.
        ``TrainConfig.paper().with_tuning(pb={"k_nb": 0.1})``."""
        return _with_tuning(self, changes)

    @classmethod
    def from_preset(cls, preset: Preset | str, **changes: Any) -> TrainConfig:
        """The learning a preset's ``[learning]`` section holds; ``changes``: settings."""
        loaded = load_preset(preset) if isinstance(preset, str) else preset
        values = section_values(loaded, "learning")
        tuning = Tuning(loaded.name, {k: v for k, v in values.items() if k not in _USER})
        settings = {k: values[k] for k in _USER if k in values}
        return cls(**{**settings, **changes}, _tuning=tuning)

    @classmethod
    def paper(cls, **changes: Any) -> TrainConfig:
        """The paper's learning: momentum descent, no noise, 50,000 iterations, l = 20.
        ``changes``: settings a user changes (``iterations``, ``seed``, ...)."""
        return cls.from_preset("paper", **changes)

    @classmethod
    def fast(cls, **changes: Any) -> TrainConfig:
        """Adam with noise on the teacher-forced inputs: reaches the paper's error in far
        fewer iterations. ``changes``: settings a user changes."""
        return cls.from_preset("fast", **changes)

    def to_dict(self) -> dict[str, Any]:
        """Every value, settings and tuned, as one flat record (``pb`` a dict): what a model
        file records as ``train_config``."""
        return asdict(self)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> TrainConfig:
        """A learning from :meth:`to_dict`'s record. Its preset is the one its optimizer
        implies (Adam: ``fast``); values the record lacks are that preset's."""
        data = dict(data)
        settings = {k: data.pop(k) for k in _USER if k in data}
        preset = "fast" if data.get("optimizer") == "adam" else "paper"
        tuning = Tuning(preset, {**_preset_tuning(preset), **data})
        return cls(**settings, _tuning=tuning)


def preset_record(config: TrainConfig) -> dict[str, Any]:
    """What a model records of its learning preset (``meta["preset"]``): the preset's name,
    version and fingerprint (of its values: which values the version held), and the tuned
    values its learning changed from the preset's, if any."""
    preset = load_preset(config.preset)
    own = _preset_tuning(config.preset)
    changed = [key for key, value in config.tuning.items() if _plain(value) != _plain(own[key])]
    record: dict[str, Any] = {
        "name": preset.name,
        "version": preset.version,
        "fingerprint": preset.fingerprint,
    }
    if changed:
        record["changed"] = changed
    return record


def _plain(value: Any) -> Any:
    return asdict(value) if isinstance(value, PBUpdateConfig) else value


class TrainState(NamedTuple):
    """Everything that changes during learning (S sequences, T-1 prediction steps)."""

    params: Params
    initial_context_logit: jax.Array  # (S, C)
    opt_state: Any
    rho: jax.Array  # (S, T-1, P)
    rho_velocity: jax.Array  # (S, T-1, P)
    key: jax.Array
    iteration: jax.Array  # scalar int


@dataclass(frozen=True)
class TrainingData:
    """Training sequences normalized and padded into arrays.

    ``inputs`` (S, T, I) normalized, ``valid`` (S, T-1): whether step t predicts a real step.
    """

    inputs: np.ndarray
    valid: np.ndarray
    patterns: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray

    @property
    def fingerprint(self) -> str:
        digest = hashlib.sha256()
        for array in (self.inputs, self.valid, self.lower, self.upper):
            digest.update(np.ascontiguousarray(array).tobytes())
        digest.update("\n".join(self.patterns).encode())
        return digest.hexdigest()


def normalization_for(joint_limits: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Normalization bounds (I,): sensory in [0, 1] as is, motor by the joint limits (8, 2)."""
    limits = np.asarray(joint_limits, dtype=np.float64)
    lower = np.concatenate([np.zeros(SENSORY_SIZE), limits[:, 0]])
    upper = np.concatenate([np.ones(SENSORY_SIZE), limits[:, 1]])
    return lower, upper


def prepare_data(sequences: SequenceABC[Sequence], joint_limits: np.ndarray) -> TrainingData:
    """Normalize and pad sequences; motor values outside the joint limits are an error."""
    if not sequences:
        raise DataFileError("no training sequences")
    lower, upper = normalization_for(joint_limits)
    if np.asarray(joint_limits).shape[0] != sequences[0].motor.shape[1]:
        raise ConfigError("joint limits do not match the motor vector size")
    n_steps = max(s.n_steps for s in sequences)
    io = lower.shape[0]
    inputs = np.full((len(sequences), n_steps, io), 0.5)
    valid = np.zeros((len(sequences), n_steps - 1), dtype=bool)
    for i, seq in enumerate(sequences):
        raw = np.concatenate([seq.sensory, seq.motor], axis=1)
        x = (raw - lower) / (upper - lower)
        if np.any(x < -1e-9) or np.any(x > 1 + 1e-9):
            bad = np.argwhere((x < -1e-9) | (x > 1 + 1e-9))[0]
            names = (*SENSORY_NAMES, *MOTOR_NAMES)
            column = names[bad[1]] if len(names) == io else f"column {bad[1]}"
            kind = "a hand position" if bad[1] < seq.sensory.shape[1] else "a joint angle"
            raise DataFileError(
                f"{seq.source or 'sequence'}: step {bad[0]}, {column} = "
                f"{raw[bad[0], bad[1]]:.4g} is outside its range [{lower[bad[1]]:.4g}, "
                f"{upper[bad[1]]:.4g}] ({kind}: hands in [0, 1], joints within the robot's "
                "limits, radians)"
            )
        inputs[i, : seq.n_steps] = x
        valid[i, : seq.n_steps - 1] = True
    return TrainingData(inputs, valid, tuple(s.pattern for s in sequences), lower, upper)


def optimizer_for(config: TrainConfig) -> optax.GradientTransformation:
    """The weights' optimizer: gradient descent with momentum (the paper's) or Adam."""
    if config.optimizer == "adam":
        return optax.adam(config.learning_rate)
    return optax.sgd(config.learning_rate, momentum=config.momentum)


def squared_error(
    trainable: tuple[Params, jax.Array],
    rho: jax.Array,
    inputs: jax.Array,
    valid: jax.Array,
    noise: jax.Array,
    targets: jax.Array | None = None,
) -> jax.Array:
    """0.5 · Σ over sequences, valid steps and outputs of the squared prediction error:
    predictions from the (noisy) teacher-forced ``inputs[:, :-1]`` against ``targets`` (S,
    T-1, I), by default the next steps ``inputs[:, 1:]``."""
    params, context_logit = trainable
    pbs = jax.nn.sigmoid(rho)  # (S, T-1, P)
    teacher = inputs[:, :-1] + noise
    predictions, _ = open_loop(
        params, jax.nn.sigmoid(context_logit), jnp.swapaxes(teacher, 0, 1), jnp.swapaxes(pbs, 0, 1)
    )
    targets = inputs[:, 1:] if targets is None else targets
    error = (jnp.swapaxes(predictions, 0, 1) - targets) * valid[..., None]
    return 0.5 * jnp.sum(error**2)


def learning_gradients(
    trainable: tuple[Params, jax.Array],
    rho: jax.Array,
    inputs: jax.Array,
    valid: jax.Array,
    noise: jax.Array,
    targets: jax.Array | None = None,
) -> tuple[tuple[Params, jax.Array], jax.Array]:
    """The gradients of :func:`squared_error` with respect to ``trainable`` (the weights and
    the initial contexts' logits) and ``rho``, by a hand-written back-propagation through
    time, in the structure ``jax.grad(squared_error, argnums=(0, 1))`` gives.

    Equal to it (tests/model/test_gradients.py) and about 1.5 times as fast: the backward
    loop over the steps carries only the errors of the context and the hidden layer (two
    small products a step), and the weights' and the PBs' gradients are then one product each
    over all steps and sequences, where the differentiated loop made them step by step.
    """
    params, context_logit = trainable
    n_io, n_pb = inputs.shape[-1], rho.shape[-1]
    pbs = jax.nn.sigmoid(rho)  # (S, T-1, P)
    context = jax.nn.sigmoid(context_logit)  # (S, C)

    def forward(c: jax.Array, xs: tuple[jax.Array, jax.Array]):
        x, pb = xs
        z = jnp.concatenate([x, pb, c], axis=-1)
        h = jax.nn.sigmoid(z @ params.w_in + params.b_h)
        o = jax.nn.sigmoid(h @ params.w_out + params.b_out)
        return o[:, n_io:], (z, h, o)

    forced = jnp.swapaxes(inputs[:, :-1] + noise, 0, 1)  # (T-1, S, I): steps first
    _, (z, h, o) = jax.lax.scan(forward, context, (forced, jnp.swapaxes(pbs, 0, 1)), unroll=2)
    targets = inputs[:, 1:] if targets is None else targets
    mask = jnp.swapaxes(valid, 0, 1)[..., None].astype(o.dtype)
    d_prediction = (o[..., :n_io] - jnp.swapaxes(targets, 0, 1)) * mask
    w_out_t, w_context_t = params.w_out.T, params.w_in[n_io + n_pb :].T

    def backward(d_context_next: jax.Array, xs: tuple[jax.Array, jax.Array, jax.Array]):
        h_t, o_t, d_prediction_t = xs
        d_output = jnp.concatenate([d_prediction_t, d_context_next], axis=-1)
        d_output_in = d_output * o_t * (1.0 - o_t)
        d_hidden_in = (d_output_in @ w_out_t) * h_t * (1.0 - h_t)
        return d_hidden_in @ w_context_t, (d_output_in, d_hidden_in)

    d_context, (d_output_in, d_hidden_in) = jax.lax.scan(
        backward, jnp.zeros_like(context), (h, o, d_prediction), reverse=True, unroll=2
    )
    rows = d_output_in.shape[0] * d_output_in.shape[1]
    d_out_rows, d_hidden_rows = d_output_in.reshape(rows, -1), d_hidden_in.reshape(rows, -1)
    grads = Params(
        w_in=z.reshape(rows, -1).T @ d_hidden_rows,
        b_h=jnp.sum(d_hidden_rows, axis=0),
        w_out=h.reshape(rows, -1).T @ d_out_rows,
        b_out=jnp.sum(d_out_rows, axis=0),
    )
    d_pb = jnp.swapaxes(d_hidden_in @ params.w_in[n_io : n_io + n_pb].T, 0, 1)  # (S, T-1, P)
    return (grads, d_context * context * (1.0 - context)), d_pb * pbs * (1.0 - pbs)


class Teacher(NamedTuple):
    """A network whose function some sequences learn (a rehearsal of the old network's
    function, :mod:`rnnpb.model.consolidation`): a sequence flagged in ``taught`` learns
    towards what ``params``, run from that sequence's ``initial_context`` and ``pb``, predicts
    from the same noisy teacher-forced inputs, instead of towards its own next step."""

    params: Params
    initial_context: jax.Array  # (S, C), in (0, 1)
    pb: jax.Array  # (S, P), in (0, 1)
    taught: jax.Array  # (S,) bool


def teacher_targets(teacher: Teacher, inputs: jax.Array, noise: jax.Array) -> jax.Array:
    """The learning targets (S, T-1, I): ``teacher``'s predictions from ``inputs[:, :-1] +
    noise`` for its taught sequences, the next steps ``inputs[:, 1:]`` for the others."""
    forced = inputs[:, :-1] + noise
    pbs = jnp.broadcast_to(teacher.pb[:, None, :], (*forced.shape[:2], teacher.pb.shape[-1]))
    predictions, _ = open_loop(
        teacher.params,
        teacher.initial_context,
        jnp.swapaxes(forced, 0, 1),
        jnp.swapaxes(pbs, 0, 1),
    )
    predicted = jax.lax.stop_gradient(jnp.swapaxes(predictions, 0, 1))
    return jnp.where(teacher.taught[:, None, None], predicted, inputs[:, 1:])


ChunkRunner = Callable[..., TrainState]
"""``run_chunk(state, inputs, valid, n_iterations, pb_learning, teacher=None) -> state``."""


def chunk_runner(config: TrainConfig, native: bool = True) -> ChunkRunner:
    """The compiled function ``run_chunk(state, inputs, valid, n_iterations, pb_learning,
    teacher=None) -> state`` that runs ``n_iterations`` learning iterations (``inputs`` (S, T,
    I), ``valid`` (S, T-1)); ``pb_learning`` (S,) bool says whose PB profile learns (eqs. 1–2):
    a sequence with False keeps its ``rho`` exactly, and its momentum stays zero. One function
    for every mask: the mask is an argument, not a setting compiled in. ``teacher``
    (:class:`Teacher`) gives the sequences it flags its predictions as their targets.

    The iterations run in native code (:mod:`rnnpb.model.native_learning`) where it runs;
    ``native=False``, ``RNNPB_NATIVE=0`` or a missing llvmlite give the compiled JAX chunk,
    the reference."""
    # Settings that do not enter the compiled update are normalized away so that runs that
    # differ only in them share one compiled function.
    normal = replace(config, iterations=0, seed=0, checkpoint_every=1)
    normal = normal.with_tuning(chunk_iterations=1)
    return _runner(normal) if native else _compiled_chunk(normal)


@functools.lru_cache(maxsize=16)
def _runner(config: TrainConfig) -> ChunkRunner:
    """The native chunk (:mod:`rnnpb.model.native_learning`) where it runs, else the compiled
    JAX chunk: the reference, and what the native one falls back to."""
    compiled = _compiled_chunk(config)
    from rnnpb.model import _ir, native_learning

    if not _ir.enabled():
        return compiled
    return native_learning.NativeChunk(config, compiled)


def seeds_chunk_runner(config: TrainConfig) -> ChunkRunner:
    """:func:`chunk_runner` over a batch of training states (one per seed, stacked on a first
    axis) that learn the same ``inputs`` and ``valid`` together: ``run_chunk(states, inputs,
    valid, n_iterations, pb_learning) -> states``. Each state's arithmetic is its own
    iteration's, so each seed learns what it learns alone."""
    normal = replace(config, iterations=0, seed=0, checkpoint_every=1)
    return _seeds_runner(normal.with_tuning(chunk_iterations=1))


@functools.lru_cache(maxsize=8)
def _seeds_runner(config: TrainConfig) -> ChunkRunner:
    from rnnpb.model.native_learning import NativeChunk

    run_chunk = _runner(config)
    if not isinstance(run_chunk, NativeChunk):
        return jax.jit(jax.vmap(run_chunk, in_axes=(0, None, None, None, None)))

    def each_seed(
        states: TrainState,
        inputs: jax.Array,
        valid: jax.Array,
        n_iterations: jax.Array,
        pb_learning: jax.Array,
    ) -> TrainState:
        # The native chunk runs one network at a time: each seed's state in turn.
        count = int(states.iteration.shape[0])
        learned = [
            run_chunk(
                jax.tree_util.tree_map(lambda leaf, i=i: leaf[i], states),
                inputs,
                valid,
                n_iterations,
                pb_learning,
            )
            for i in range(count)
        ]
        return jax.tree_util.tree_map(lambda *leaves: jnp.stack(leaves), *learned)

    return each_seed


@functools.lru_cache(maxsize=16)
def _compiled_chunk(config: TrainConfig) -> ChunkRunner:
    optimizer = optimizer_for(config)

    def one_iteration(
        state: TrainState,
        inputs: jax.Array,
        valid: jax.Array,
        pb_learning: jax.Array,
        teacher: Teacher | None,
    ) -> TrainState:
        key, noise_key = jax.random.split(state.key)
        if config.input_noise:
            noise = config.input_noise * jax.random.normal(noise_key, inputs[:, :-1].shape)
        else:  # the paper's learning: no noise to draw (the same zeros, without the draw)
            noise = jnp.zeros(inputs[:, :-1].shape, inputs.dtype)
        trainable = (state.params, state.initial_context_logit)
        targets = None if teacher is None else teacher_targets(teacher, inputs, noise)
        grad_trainable, grad_rho = learning_gradients(
            trainable, state.rho, inputs, valid, noise, targets
        )
        # Weights see the mean error per prediction step so their step size does not depend on
        # how much data there is; each PB profile sees its own sequence's summed error (eq. 1).
        n_valid = jnp.maximum(jnp.sum(valid), 1)
        grad_trainable = jax.tree_util.tree_map(lambda g: g / n_valid, grad_trainable)
        if not config.learn_initial_context:
            grad_trainable = (grad_trainable[0], jnp.zeros_like(grad_trainable[1]))
        updates, opt_state = optimizer.update(grad_trainable, state.opt_state, trainable)
        # optax types its result as any tree; it has the structure of ``trainable``.
        params, context_logit = cast(
            "tuple[Params, jax.Array]", optax.apply_updates(trainable, updates)
        )
        rho, rho_velocity = jax.vmap(lambda r, v, g, m: pb_update(r, v, g, config.pb, m))(
            state.rho, state.rho_velocity, grad_rho, valid
        )
        # A held PB profile keeps its values bit for bit (a select, not a zero step).
        learns = pb_learning[:, None, None]
        rho = jnp.where(learns, rho, state.rho)
        rho_velocity = jnp.where(learns, rho_velocity, state.rho_velocity)
        return TrainState(
            params, context_logit, opt_state, rho, rho_velocity, key, state.iteration + 1
        )

    @jax.jit
    def run_chunk(
        state: TrainState,
        inputs: jax.Array,
        valid: jax.Array,
        n_iterations: jax.Array,
        pb_learning: jax.Array,
        teacher: Teacher | None = None,
    ) -> TrainState:
        return jax.lax.fori_loop(
            0,
            n_iterations,
            lambda _, s: one_iteration(s, inputs, valid, pb_learning, teacher),
            state,
        )

    return run_chunk


@jax.jit
def per_output_mse(
    trainable: tuple[Params, jax.Array], rho: jax.Array, inputs: jax.Array, valid: jax.Array
) -> jax.Array:
    """The mean squared prediction error of each output over all valid steps, shape (I,)."""
    params, context_logit = trainable
    predictions, _ = open_loop(
        params,
        jax.nn.sigmoid(context_logit),
        jnp.swapaxes(inputs[:, :-1], 0, 1),
        jnp.swapaxes(jax.nn.sigmoid(rho), 0, 1),
    )
    error = (jnp.swapaxes(predictions, 0, 1) - inputs[:, 1:]) ** 2 * valid[..., None]
    return jnp.sum(error, axis=(0, 1)) / jnp.sum(valid)


@dataclass(frozen=True)
class WarmStart:
    """Where learning starts when it continues from a learned model (incremental learning,
    :mod:`rnnpb.model.consolidation`) instead of from random weights.

    Attributes
    ----------
    params : Params
        The weights to start from.
    initial_context : array, shape (S, C)
        Each training sequence's starting initial context, in (0, 1).
    pb : array, shape (S, P)
        Each training sequence's starting PB, in (0, 1): its whole PB profile starts there.
    fingerprint : str
        Names the start (the model's fingerprint and the method); :attr:`identity` adds the
        PB hold, so that a checkpoint of one start never resumes another.
    pb_held : array of bool, shape (S,), optional
        Sequences whose PB stays at ``pb`` (their ``rho`` profile does not learn) for the
        first ``hold_iterations`` iterations. None: every PB learns.
    hold_iterations : int or None
        How long the held PBs stay held; None: for the whole learning.
    taught : array of bool, shape (S,), optional
        Sequences that learn the start's function rather than their own next steps: towards
        what ``params``, from the sequence's starting ``initial_context`` and ``pb``, predicts
        from the same noisy inputs (:class:`Teacher`). None: every sequence learns its next
        steps.
    """

    params: Params
    initial_context: np.ndarray
    pb: np.ndarray
    fingerprint: str
    pb_held: np.ndarray | None = None
    hold_iterations: int | None = None
    taught: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.hold_iterations is not None and self.hold_iterations < 0:
            raise ConfigError(f"hold_iterations must be >= 0, got {self.hold_iterations}")
        if self.pb_held is not None and np.shape(self.pb_held) != (np.shape(self.pb)[0],):
            raise ConfigError(
                f"pb_held must have one flag per sequence ({np.shape(self.pb)[0]}), "
                f"got shape {np.shape(self.pb_held)}"
            )
        if self.taught is not None and np.shape(self.taught) != (np.shape(self.pb)[0],):
            raise ConfigError(
                f"taught must have one flag per sequence ({np.shape(self.pb)[0]}), "
                f"got shape {np.shape(self.taught)}"
            )

    @property
    def identity(self) -> str:
        """The start, its PB hold and its taught sequences, as a checkpoint records it."""
        name = self.fingerprint
        if self.pb_held is not None and np.any(self.pb_held):
            until = "end" if self.hold_iterations is None else str(self.hold_iterations)
            name += f":pb-held={_flags(self.pb_held)}:until={until}"
        if self.taught is not None and np.any(self.taught):
            name += f":taught={_flags(self.taught)}"
        return name

    def teacher(self) -> Teacher | None:
        """The start's network as the :class:`Teacher` of its taught sequences, if any."""
        if self.taught is None or not np.any(self.taught):
            return None
        return Teacher(
            Params(*(jnp.asarray(v, jnp.float32) for v in self.params)),
            jnp.asarray(self.initial_context, jnp.float32),
            jnp.asarray(self.pb, jnp.float32),
            jnp.asarray(self.taught, bool),
        )

    def pb_learning(self, iteration: int) -> np.ndarray:
        """The (S,) bool mask of PBs that learn at ``iteration`` (0-based)."""
        n_seq = np.shape(self.pb)[0]
        held = (
            np.zeros(n_seq, dtype=bool)
            if self.pb_held is None
            else np.asarray(self.pb_held, dtype=bool)
        )
        if self.hold_iterations is not None and iteration >= self.hold_iterations:
            held = np.zeros(n_seq, dtype=bool)
        return ~held

    def next_release(self, iteration: int) -> int | None:
        """The iteration at which the held PBs are released, if it is still ahead."""
        if self.pb_held is None or self.hold_iterations is None:
            return None
        return self.hold_iterations if iteration < self.hold_iterations else None


def _flags(mask: np.ndarray) -> str:
    return "".join("1" if f else "0" for f in np.asarray(mask, dtype=bool))


def init_state(
    data: TrainingData,
    network: NetworkConfig,
    config: TrainConfig,
    warm_start: WarmStart | None = None,
) -> TrainState:
    """The state before the first iteration: random weights from ``config.seed``, initial
    contexts at 0.5 and every PB profile at 0.5; or, with ``warm_start``, its weights,
    initial contexts and PBs (the optimizer's state starts afresh either way)."""
    key = jax.random.PRNGKey(config.seed)
    key, params_key = jax.random.split(key)
    params = init_params(network, params_key)
    n_seq, n_pred = data.valid.shape
    context_logit = jnp.zeros((n_seq, network.context_size), jnp.float32)
    rho = jnp.zeros((n_seq, n_pred, network.pb_size), jnp.float32)
    if warm_start is not None:
        if np.shape(warm_start.initial_context) != (n_seq, network.context_size) or np.shape(
            warm_start.pb
        ) != (n_seq, network.pb_size):
            raise ConfigError(
                "the warm start's initial contexts or PBs do not match the "
                f"{n_seq} training sequences and the network's sizes"
            )
        params = Params(*(jnp.asarray(v, jnp.float32) for v in warm_start.params))
        context_logit = jnp.asarray(
            logit_numpy(np.asarray(warm_start.initial_context)), jnp.float32
        )
        rho = jnp.broadcast_to(
            jnp.asarray(logit_numpy(np.asarray(warm_start.pb)), jnp.float32)[:, None, :], rho.shape
        )
    opt_state = optimizer_for(config).init((params, context_logit))
    return TrainState(
        params, context_logit, opt_state, rho, jnp.zeros_like(rho), key, jnp.asarray(0, jnp.int32)
    )
