"""Routines: a higher-level RNNPB that learns sequences of the lower level's PB (Ito & Tani
2004, section 4; Tani 2003).

The lower level (:class:`~rnnpb.model.MirrorSystem`) follows single movement patterns; over a
routine — pattern 1 for three cycles, then 3 for two, then 2 for four — its PB moves from one
learned value to the next. The higher level is a network of the same family
(:func:`rnnpb.model.network.step`, learned by the same compiled chunk of
:mod:`rnnpb.model.learning`, with its own PB for each routine) whose input each step is

* the *segment code*: the mean lower PB of the segment the step belongs to (P values);
* the *segment clock*: the steps since that segment began, divided by :data:`CLOCK_STEPS` and
  capped at 1 (one value: when in a segment the next switch is due).

Segments come from the lower level's own PB, not from labels (:func:`segment_pb`): a segment
begins where the PB has moved more than ``change`` away from the last segment's and then holds
(within ``tolerance``) for ``hold`` steps; a segment shorter than ``min_length`` is no
segment.

On-line, :class:`RoutineFollower` keeps the stream of lower PBs, segments it as it comes,
regresses the higher PB over its last ``window`` steps (eqs. 1-2, the same update as the lower
level's) and predicts the next lower PB; the routine recognised is the learned routine whose
PB is nearest, when its own dynamics predict the window well enough. :class:`TwoLevelMirror`
passes that prediction down as a prior: the lower regression also tries it as a restart
(``MirrorSystem.step(..., prior_pb=)``); the evidence in the window decides, so a person who
leaves the routine is followed.

A routine file (``rnnpb-routines``, version 1) holds the higher network, each routine's PB and
initial context, the segmentation settings, and the lower model's
:attr:`~rnnpb.model.TrainedModel.fingerprint`: it is refused for any other lower model.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from collections.abc import Sequence as SequenceABC
from dataclasses import asdict, dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from rnnpb import __version__
from rnnpb.errors import ConfigError, DataFileError, ModelFileError
from rnnpb.model.batched import BatchedMirror
from rnnpb.model.io import TrainedModel, load_archive, save_archive
from rnnpb.model.learning import TrainConfig, TrainingData, chunk_runner, init_state
from rnnpb.model.mirror import MirrorSystem, StepResult
from rnnpb.model.network import (
    NetworkConfig,
    Params,
    closed_loop,
    open_loop,
    params_from_numpy,
    params_to_numpy,
)
from rnnpb.model.online_config import OnlineConfig
from rnnpb.model.parametric_bias import PBUpdateConfig, pb_update

ROUTINES_FORMAT = "rnnpb-routines"
ROUTINES_FORMAT_VERSION = 1
CLOCK_STEPS = 60.0
"""Steps at which the segment clock reaches 1 (longer than any learned part, five cycles)."""


@dataclass(frozen=True)
class SegmentConfig:
    """Where the lower PB stream is cut into segments (defaults with their reasons).

    change : float
        A new segment's PB is at least this far (Euclidean) from the last one's: learned
        patterns' PBs lie 0.5-1 apart, a PB wandering within one pattern less than 0.1.
    tolerance : float
        Held means every PB of ``hold`` steps within this distance of their mean.
    hold : int
        Steps the PB must hold to begin a segment: half a cycle, so a passing PB is none.
    min_length : int
        Steps a segment must last: one cycle of the demonstrator's patterns.
    """

    change: float = 0.25
    tolerance: float = 0.08
    hold: int = 6
    min_length: int = 12

    def __post_init__(self) -> None:
        if self.change <= 0 or self.tolerance <= 0:
            raise ConfigError("segment change and tolerance must be > 0")
        if self.hold < 1 or self.min_length < 1:
            raise ConfigError("segment hold and min_length must be >= 1")


@dataclass(frozen=True)
class Segment:
    """A stretch of the lower PB stream: steps ``start`` to ``stop - 1``, its mean PB."""

    start: int
    stop: int
    pb: np.ndarray


def segment_pb(pbs: np.ndarray, config: SegmentConfig | None = None) -> list[Segment]:
    """Cut a lower PB stream (T, P) into segments (see the module doc). Causal: the
    segments of the first ``t`` steps are those of the whole stream cut at ``t``, except the
    last one, which grows. Steps before the first held PB belong to the first segment."""
    config = config or SegmentConfig()
    pbs = np.asarray(pbs, dtype=np.float64)
    n = len(pbs)
    if n == 0:
        return []
    starts: list[int] = [0]
    reference: np.ndarray | None = None
    for t in range(n - config.hold + 1):
        block = pbs[t : t + config.hold]
        centre = block.mean(axis=0)
        if np.max(np.linalg.norm(block - centre, axis=1)) > config.tolerance:
            continue
        if reference is None:
            reference = centre
            continue
        if np.linalg.norm(centre - reference) > config.change:
            if t - starts[-1] >= config.min_length:
                starts.append(t)
            else:  # too short to be a segment: the previous one goes on from here
                starts[-1] = t if len(starts) > 1 else 0
        reference = centre if np.linalg.norm(centre - reference) > config.change else reference
    bounds = [*starts, n]
    segments = []
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        # The segment's code: the PB it holds (its second half: the start may still blend).
        held = pbs[a + (b - a) // 2 : b] if b - a >= 2 else pbs[a:b]
        segments.append(Segment(a, b, held.mean(axis=0)))
    return segments


def routine_inputs(pbs: np.ndarray, config: SegmentConfig | None = None) -> np.ndarray:
    """The higher level's inputs (T, P + 1) for a lower PB stream (T, P): each step's segment
    code and segment clock (module doc)."""
    pbs = np.asarray(pbs, dtype=np.float64)
    x = np.zeros((len(pbs), pbs.shape[1] + 1))
    for segment in segment_pb(pbs, config):
        x[segment.start : segment.stop, :-1] = segment.pb
        clock = np.arange(segment.stop - segment.start) / CLOCK_STEPS
        x[segment.start : segment.stop, -1] = np.minimum(clock, 1.0)
    return np.clip(x, 0.0, 1.0)


def lower_pb_streams(model: TrainedModel, recordings: SequenceABC[np.ndarray]) -> list[np.ndarray]:
    """The lower level's PB (T_i, P) run on-line over each recording's hands (T_i, 4), all
    recordings in one batched run (:class:`~rnnpb.model.BatchedMirror`)."""
    if not recordings:
        return []
    n = max(len(r) for r in recordings)
    hands = np.full((len(recordings), n, model.network.sensory_size), 0.5)
    for i, r in enumerate(recordings):
        hands[i, : len(r)] = r
    mirror = BatchedMirror(model, len(recordings), OnlineConfig.for_model(model).config)
    pbs = np.array([[result.pb for result in mirror.step(hands[:, t])] for t in range(n)])
    return [pbs[: len(r), i] for i, r in enumerate(recordings)]


@dataclass(frozen=True)
class RoutineModel:
    """A learned higher level.

    Attributes
    ----------
    network : NetworkConfig
        Sizes: ``sensory_size`` = the lower PB size (the segment code), ``motor_size`` = 1
        (the segment clock), ``pb_size`` the higher PB.
    params : Params
    routine_pb : dict of str to array, shape (Q,)
        Each routine's PB.
    routine_context : dict of str to array, shape (C,)
        Each routine's learned initial context.
    lower_fingerprint : str
        :attr:`TrainedModel.fingerprint` of the lower model it was learned over.
    segments : SegmentConfig
    recognition_error : float
        A routine is recognised only where its own PB predicts the window with at most this
        mean squared error (chosen at learning: the largest error over the learned data,
        times two).
    meta : dict
    """

    network: NetworkConfig
    params: Params
    routine_pb: dict[str, np.ndarray]
    routine_context: dict[str, np.ndarray]
    lower_fingerprint: str
    segments: SegmentConfig = field(default_factory=SegmentConfig)
    recognition_error: float = 0.01
    meta: dict[str, Any] = field(default_factory=dict)

    @property
    def routines(self) -> tuple[str, ...]:
        return tuple(self.routine_pb)

    def check_lower(self, lower: TrainedModel, path: str | os.PathLike[str] = "") -> None:
        """Refuse a lower model other than the one these routines were learned over."""
        if lower.fingerprint != self.lower_fingerprint:
            where = f"{path}: " if path else ""
            raise ModelFileError(
                f"{where}these routines were learned over another lower model (fingerprint "
                f"{self.lower_fingerprint[:12]}, this model's is {lower.fingerprint[:12]}); "
                "learn them again with `rnnpb train-routines --model` this model"
            )

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write the routines to ``path`` (``.npz``) atomically."""
        names = list(self.routine_pb)
        meta = {
            "format": ROUTINES_FORMAT,
            "format_version": ROUTINES_FORMAT_VERSION,
            "rnnpb_version": __version__,
            "network": asdict(self.network),
            "routines": names,
            "lower_fingerprint": self.lower_fingerprint,
            "segments": asdict(self.segments),
            "recognition_error": self.recognition_error,
            **{k: v for k, v in self.meta.items() if k not in _META_KEYS},
        }
        arrays = {f"params/{k}": v for k, v in params_to_numpy(self.params).items()}
        arrays["routine_pb"] = np.array([self.routine_pb[n] for n in names])
        arrays["routine_context"] = np.array([self.routine_context[n] for n in names])
        save_archive(path, meta, arrays)

    @classmethod
    def load(
        cls, path: str | os.PathLike[str], lower: TrainedModel | None = None
    ) -> RoutineModel:
        """Read a routine file; with ``lower``, refuse it unless it was learned over that
        model. Any problem raises :class:`ModelFileError` naming the file."""
        meta, arrays = load_archive(path, ROUTINES_FORMAT, ROUTINES_FORMAT_VERSION, _members)
        try:
            network = NetworkConfig(**meta["network"])
            names = [str(n) for n in meta["routines"]]
            routines = cls(
                network=network,
                params=params_from_numpy(
                    {k.removeprefix("params/"): v for k, v in arrays.items() if "/" in k}
                ),
                routine_pb={n: np.asarray(arrays["routine_pb"][i]) for i, n in enumerate(names)},
                routine_context={
                    n: np.asarray(arrays["routine_context"][i]) for i, n in enumerate(names)
                },
                lower_fingerprint=str(meta["lower_fingerprint"]),
                segments=SegmentConfig(**meta["segments"]),
                recognition_error=float(meta["recognition_error"]),
                meta={k: v for k, v in meta.items() if k not in _META_KEYS},
            )
        except (KeyError, TypeError, ValueError, IndexError) as error:
            raise ModelFileError(f"{path}: not a valid routine file ({error})") from None
        if not np.all(np.isfinite(arrays["routine_pb"])):
            raise ModelFileError(f"{path}: routine PBs are not finite")
        if lower is not None:
            routines.check_lower(lower, path)
        return routines


_META_KEYS = (
    "format",
    "format_version",
    "rnnpb_version",
    "network",
    "routines",
    "lower_fingerprint",
    "segments",
    "recognition_error",
)


def _members(path: Path, meta: dict[str, Any]) -> dict[str, tuple[int, ...] | None]:
    try:
        network = NetworkConfig(**meta["network"])
        k = len(meta["routines"])
    except (KeyError, TypeError, ValueError) as error:
        raise ModelFileError(f"{path}: not a valid routine file ({error})") from None
    i, p, c, h = network.io_size, network.pb_size, network.context_size, network.hidden_size
    return {
        "params/w_in": (i + p + c, h),
        "params/b_h": (h,),
        "params/w_out": (h, i + c),
        "params/b_out": (i + c,),
        "routine_pb": (k, p),
        "routine_context": (k, c),
    }


@dataclass(frozen=True)
class RoutineLearning:
    """How the higher level learns (defaults with their reasons).

    pb_size : int
        Higher PB units: two hold a handful of routines apart.
    hidden_size, context_size : int
        Small: the inputs change only at switches.
    iterations : int
        Adam iterations: the error is flat by then on the demonstrator's routines.
    seed : int
    """

    pb_size: int = 2
    hidden_size: int = 24
    context_size: int = 12
    iterations: int = 1500
    seed: int = 0


def learn_routines(
    lower: TrainedModel,
    recordings: Mapping[str, SequenceABC[np.ndarray]],
    learning: RoutineLearning | None = None,
    segments: SegmentConfig | None = None,
) -> RoutineModel:
    """Learn routines over ``lower``: ``recordings`` maps each routine's name to its
    recordings' hands (each (T, 4) in [0, 1]); each recording is run through the lower level
    on-line and its PB stream segmented into the higher level's inputs."""
    learning = learning or RoutineLearning()
    segments = segments or SegmentConfig()
    if not recordings or any(len(r) == 0 for r in recordings.values()):
        raise DataFileError("every routine needs at least one recording")
    takes, names = [], []
    for name, recorded in recordings.items():
        for sensory in recorded:
            sensory = np.asarray(sensory, dtype=np.float64)
            if sensory.ndim != 2 or sensory.shape[1] != lower.network.sensory_size:
                raise DataFileError(f"routine {name!r}: a recording's hands must be (T, 4)")
            if len(sensory) < 2 * segments.min_length:
                raise DataFileError(
                    f"routine {name!r}: a recording of {len(sensory)} steps is too short "
                    f"(at least {2 * segments.min_length})"
                )
            takes.append(sensory)
            names.append(name)
    streams = [routine_inputs(pbs, segments) for pbs in lower_pb_streams(lower, takes)]
    return learn_from_inputs(lower.fingerprint, names, streams, learning, segments)


def learn_from_inputs(
    lower_fingerprint: str,
    names: SequenceABC[str],
    streams: SequenceABC[np.ndarray],
    learning: RoutineLearning,
    segments: SegmentConfig,
) -> RoutineModel:
    """The learning itself, from the higher level's inputs (each (T_i, P + 1))."""
    p_lower = streams[0].shape[1] - 1
    network = NetworkConfig(
        sensory_size=p_lower,
        motor_size=1,
        pb_size=learning.pb_size,
        hidden_size=learning.hidden_size,
        context_size=learning.context_size,
    )
    n_steps = max(len(s) for s in streams)
    inputs = np.full((len(streams), n_steps, network.io_size), 0.5)
    valid = np.zeros((len(streams), n_steps - 1), dtype=bool)
    for i, stream in enumerate(streams):
        inputs[i, : len(stream)] = stream
        valid[i, : len(stream) - 1] = True
    data = TrainingData(
        inputs, valid, tuple(names), np.zeros(network.io_size), np.ones(network.io_size)
    )
    # Eq. 1's sum over the whole sequence: each sequence's PB stays one value (the routine's),
    # not a profile that could itself signal the switches.
    config = TrainConfig.fast(iterations=learning.iterations, seed=learning.seed).with_tuning(
        pb={"integration_length": 2 * n_steps}
    )
    state = init_state(data, network, config)
    run = chunk_runner(config)
    state = run(
        state,
        jnp.asarray(inputs, jnp.float32),
        jnp.asarray(valid),
        jnp.asarray(learning.iterations, jnp.int32),
        jnp.ones(len(streams), bool),
    )
    pb = np.asarray(jax.nn.sigmoid(state.rho), dtype=np.float64)  # (S, T-1, Q)
    sequence_pb = np.array([pb[i][valid[i]].mean(axis=0) for i in range(len(streams))])
    contexts = np.asarray(jax.nn.sigmoid(state.initial_context_logit), dtype=np.float64)
    labels = np.asarray(names)
    routine_pb = {n: sequence_pb[labels == n].mean(axis=0) for n in dict.fromkeys(names)}
    routine_context = {n: contexts[labels == n].mean(axis=0) for n in dict.fromkeys(names)}
    params = jax.tree_util.tree_map(lambda a: jnp.asarray(a, jnp.float32), state.params)
    # The error a learned routine's own PB leaves on its learned data, per window: where the
    # on-line window does twice worse, the routine is not recognised.
    errors = []
    for i, stream in enumerate(streams):
        errors.append(
            _window_errors(
                params, routine_context[names[i]], routine_pb[names[i]], stream, _WINDOW
            ).max()
        )
    return RoutineModel(
        network=network,
        params=params,
        routine_pb=routine_pb,
        routine_context=routine_context,
        lower_fingerprint=lower_fingerprint,
        segments=segments,
        recognition_error=2.0 * float(max(errors)),
        meta={"learning": asdict(learning), "sequences": list(names)},
    )


_WINDOW = 40
"""Steps of the on-line higher window: more than a part of a routine, so a window sees a
switch."""


def _window_errors(
    params: Params, context: np.ndarray, pb: np.ndarray, stream: np.ndarray, window: int
) -> np.ndarray:
    """Mean squared one-step error of the segment code over each window of ``stream`` ending
    at step t (from step ``window`` on), with a constant PB, run from the start."""
    predictions, _ = _open(
        params,
        jnp.asarray(context, jnp.float32),
        jnp.asarray(stream[:-1], jnp.float32),
        jnp.broadcast_to(jnp.asarray(pb, jnp.float32), (len(stream) - 1, len(pb))),
    )
    p = stream.shape[1] - 1
    e = np.mean((np.asarray(predictions)[:, :p] - stream[1:, :p]) ** 2, axis=1)
    if len(e) <= window:
        return np.array([e.mean()])
    c = np.concatenate([[0.0], np.cumsum(e)])
    return (c[window:] - c[:-window]) / window


_open = jax.jit(open_loop)


_FOLLOW_PB = PBUpdateConfig(
    learning_rate=0.5, momentum=0.8, k_bp=1.0, k_nb=0.0, integration_length=_WINDOW
)


@partial(jax.jit, static_argnames=("iterations",))
def _regress(
    params: Params,
    context: jax.Array,
    inputs: jax.Array,
    valid: jax.Array,
    rho: jax.Array,
    iterations: int,
) -> tuple[jax.Array, jax.Array, jax.Array]:
    """Regress a constant higher PB over the window (eqs. 1-2 with the window summed):
    ``inputs`` (W, I), ``valid`` (W-1,) the steps that predict a real step, ``rho`` (Q,).
    Returns the PB's logit, the next-step prediction (I,) from the last input, and the
    window's mean squared code error."""
    p = inputs.shape[1] - 1

    def error(r: jax.Array) -> jax.Array:
        pbs = jnp.broadcast_to(jax.nn.sigmoid(r), (inputs.shape[0] - 1, r.shape[0]))
        predictions, _ = open_loop(params, context, inputs[:-1], pbs)
        e = ((predictions[:, :p] - inputs[1:, :p]) ** 2).sum(axis=1)
        return 0.5 * jnp.sum(e * valid)

    grad = jax.grad(error)

    def iteration(_, carry):
        r, v = carry
        g = grad(r)[None]
        r2, v2 = pb_update(r[None], v[None], g, _FOLLOW_PB)
        return r2[0], v2[0]

    rho, _ = jax.lax.fori_loop(0, iterations, iteration, (rho, jnp.zeros_like(rho)))
    pbs = jnp.broadcast_to(jax.nn.sigmoid(rho), (inputs.shape[0], rho.shape[0]))
    predictions, _ = open_loop(params, context, inputs, pbs)
    n_valid = jnp.maximum(valid.sum(), 1)
    mse = 2.0 * error(rho) / (n_valid * p)
    return rho, predictions, mse


@dataclass(frozen=True)
class FollowStep:
    """What the higher level says after a step.

    Attributes
    ----------
    routine : str or None
        The learned routine being performed, or None (none fits, or too little seen).
    pb : array, shape (Q,)
        The regressed higher PB.
    predicted_pb : array, shape (P,)
        The lower PB the routine predicts for the next step.
    switch_due : bool
        The prediction leaves the current segment (a switch is anticipated).
    error : float
        The recognised routine's mean squared error over the window (NaN before any).
    """

    routine: str | None
    pb: np.ndarray
    predicted_pb: np.ndarray
    switch_due: bool
    error: float


class RoutineFollower:
    """The higher level on-line: fed the lower PB each step (:meth:`observe`), it segments
    the stream, regresses its PB over the last ``window`` steps, says which routine it sees and
    predicts the next lower PB."""

    def __init__(
        self, routines: RoutineModel, window: int = _WINDOW, iterations: int = 30
    ) -> None:
        if window < 4 or iterations < 1:
            raise ConfigError("the routine window must be >= 4 steps and iterations >= 1")
        self.routines = routines
        self.window = window
        self.iterations = iterations
        self._params = jax.tree_util.tree_map(
            lambda a: jnp.asarray(a, jnp.float32), routines.params
        )
        self._names = routines.routines
        self._pbs = np.array([routines.routine_pb[n] for n in self._names])
        self.reset()

    def reset(self) -> None:
        self._stream: list[np.ndarray] = []
        self._rho = jnp.zeros(self.routines.network.pb_size, jnp.float32)
        self._mean_context = np.mean(list(self.routines.routine_context.values()), axis=0)

    def observe(self, lower_pb: np.ndarray) -> FollowStep:
        """Take the lower level's PB of this step; return what the higher level says."""
        self._stream.append(np.asarray(lower_pb, dtype=np.float64))
        stream = np.array(self._stream)
        n = len(stream)
        start = max(0, n - self.window)
        # Segments over the whole stream (a segment's start may lie before the window).
        inputs = routine_inputs(stream, self.routines.segments)[start:]
        w = self.window
        padded = np.full((w, inputs.shape[1]), 0.5)
        padded[: len(inputs)] = inputs
        valid = np.arange(w - 1) < len(inputs) - 1
        # The window's onset: the learned routines' mean initial context. The clock and the
        # code carry where in the routine the window starts.
        context = jnp.asarray(self._mean_context, jnp.float32)
        self._rho, predictions, mse = _regress(
            self._params,
            context,
            jnp.asarray(padded, jnp.float32),
            jnp.asarray(valid),
            self._rho,
            self.iterations,
        )
        pb = np.asarray(jax.nn.sigmoid(self._rho), dtype=np.float64)
        predicted = np.asarray(predictions[len(inputs) - 1], dtype=np.float64)
        p = self.routines.network.sensory_size
        distances = np.linalg.norm(self._pbs - pb, axis=1)
        best = int(np.argmin(distances))
        error = float(mse)
        enough = len(inputs) > self.routines.segments.min_length
        routine = (
            self._names[best]
            if enough and error <= self.routines.recognition_error
            else None
        )
        switch_due = bool(
            np.linalg.norm(predicted[:p] - inputs[-1, :p]) > 0.5 * self.routines.segments.change
        )
        return FollowStep(routine, pb, np.clip(predicted[:p], 0.0, 1.0), switch_due, error)


@dataclass(frozen=True)
class TwoLevelStep:
    """A step of the two levels: the lower level's result and what the higher level says."""

    lower: StepResult
    higher: FollowStep
    anticipated: str | None
    """The lower pattern the routine says comes next, when it anticipates a switch."""


class TwoLevelMirror:
    """The mirror system with a routine level above it: each step the higher level's
    prediction of the lower PB goes down as a prior (``MirrorSystem.step(prior_pb=)``), then
    the lower level's PB goes up (:meth:`RoutineFollower.observe`)."""

    def __init__(
        self,
        lower: TrainedModel,
        routines: RoutineModel,
        config: OnlineConfig | None = None,
        use_prior: bool = True,
    ) -> None:
        routines.check_lower(lower)
        self.lower = lower
        self.mirror = MirrorSystem(lower, config or OnlineConfig.for_model(lower).config)
        self.follower = RoutineFollower(routines)
        self.use_prior = use_prior
        self._last: FollowStep | None = None

    def step(self, observed_hands: np.ndarray) -> TwoLevelStep:
        prior = None
        last = self._last
        if self.use_prior and last is not None and last.routine is not None:
            prior = last.predicted_pb
        result = self.mirror.step(observed_hands, prior_pb=prior)
        self._last = higher = self.follower.observe(result.pb)
        anticipated = None
        if higher.routine is not None and higher.switch_due:
            anticipated = self.lower.nearest_pattern(higher.predicted_pb)[0]
        return TwoLevelStep(result, higher, anticipated)


def generate_routine(
    lower: TrainedModel, routines: RoutineModel, name: str, n_steps: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Perform a routine alone, top-down: the higher level in closed loop from the routine's
    PB and initial context gives the lower PB each step, and the lower level in closed loop
    generates the movement with it. Returns the lower PB (n, P), the imagined hands (n, 4)
    and the joint angles (n, 8), radians."""
    routines.check_lower(lower)
    if name not in routines.routine_pb:
        raise ConfigError(f"unknown routine {name!r} (known: {', '.join(routines.routines)})")
    if n_steps < 1:
        raise ConfigError(f"number of steps must be >= 1, got {n_steps}")
    net = routines.network
    code = np.mean(list(lower.pattern_pb.values()), axis=0)
    x = np.zeros(net.io_size)
    x[: net.sensory_size] = code
    params = jax.tree_util.tree_map(lambda a: jnp.asarray(a, jnp.float32), routines.params)
    predictions, _ = _closed(
        params,
        jnp.asarray(routines.routine_context[name], jnp.float32),
        jnp.asarray(x, jnp.float32),
        jnp.broadcast_to(
            jnp.asarray(routines.routine_pb[name], jnp.float32), (n_steps, net.pb_size)
        ),
    )
    lower_pb = np.clip(np.asarray(predictions, dtype=np.float64)[:, : net.sensory_size], 0, 1)
    lower_params = jax.tree_util.tree_map(lambda a: jnp.asarray(a, jnp.float32), lower.params)
    out, _ = _closed(
        lower_params,
        jnp.asarray(lower.mean_initial_context, jnp.float32),
        jnp.full(lower.network.io_size, 0.5, jnp.float32),
        jnp.asarray(lower_pb, jnp.float32),
    )
    raw = lower.denormalize(np.asarray(out, dtype=np.float64))
    s = lower.network.sensory_size
    return lower_pb, raw[:, :s], raw[:, s:]


_closed = jax.jit(closed_loop)

__all__ = [
    "ROUTINES_FORMAT",
    "ROUTINES_FORMAT_VERSION",
    "FollowStep",
    "RoutineFollower",
    "RoutineLearning",
    "RoutineModel",
    "Segment",
    "SegmentConfig",
    "TwoLevelMirror",
    "TwoLevelStep",
    "generate_routine",
    "learn_from_inputs",
    "learn_routines",
    "routine_inputs",
    "segment_pb",
]
