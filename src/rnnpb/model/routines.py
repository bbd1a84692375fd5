"""Routines: a higher-level RNNPB that learns sequences of the lower level's PB (Ito & Tani
2004, section 4; Tani 2003).

The lower level (:class:`~rnnpb.model.MirrorSystem`) follows single movement patterns; over a
routine — pattern 1 for three cycles, then 3 for two, then 2 for four — its PB moves from one
learned value to the next. The higher level is a network of the same family
(:func:`rnnpb.model.network.step`, learned by the same compiled chunk of
:mod:`rnnpb.model.learning`, with its own PB for each routine) that steps once per *segment*
of the lower PB stream (Tani 2003: the lower level segments the flow into primitives, the
higher level learns their order). Its input at segment ``j`` is

* the *segment code*: the lower PB the segment holds (P values);
* the previous segment's *duration*, in steps divided by :data:`DURATION_STEPS` (one value);

and it predicts the next input: the next segment's code and this segment's duration — which
movement comes next, and when. A neutral start event (every code value 0.5, duration 0)
precedes the first segment, so a routine's PB also predicts how it begins.

Segments come from the lower level's own PB, not from labels (:func:`segment_pb`): a segment
begins where the learned PB nearest the lower PB changes and then stays the nearest for
``hold`` steps; a segment shorter than ``min_length`` is no segment. A segment's code is that
learned PB (the lower PB itself wanders within a movement: a code that wanders with it would
make one movement look like several).

On-line, :class:`RoutineFollower` keeps the stream of lower PBs, segments it as it comes,
regresses the higher PB over the segments seen (eqs. 1-2, the same update as the lower
level's) and runs each learned routine's PB over them: the routine recognised is the one whose
own dynamics predict the codes seen best, when well enough; its prediction says the next
movement and when the current one ends. :class:`TwoLevelMirror` passes the predicted next PB
down as a prior from the predicted switch on: the lower regression also tries it as a restart
(``MirrorSystem.step(..., prior_pb=)``); the evidence in the window decides, so a person who
leaves the routine is followed.

A routine file (``rnnpb-routines``, version 1) holds the higher network, each routine's PB and
initial context, the segmentation settings, and the lower model's
:attr:`~rnnpb.model.TrainedModel.fingerprint`: it is refused for any other lower model.
"""

from __future__ import annotations

import math
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
from rnnpb.model.archive import load_archive, save_archive
from rnnpb.model.batched import BatchedMirror
from rnnpb.model.io import TrainedModel
from rnnpb.model.learning import TrainConfig, TrainingData, chunk_runner, init_state
from rnnpb.model.meta import MetaParams
from rnnpb.model.mirror import MirrorSystem, StepResult
from rnnpb.model.network import (
    NetworkConfig,
    Params,
    closed_loop,
    logit_numpy,
    open_loop,
    params_from_numpy,
    params_to_numpy,
    step,
)
from rnnpb.model.online_config import OnlineConfig
from rnnpb.model.parametric_bias import PBUpdateConfig, pb_update
from rnnpb.model.recognition import RecognitionConfig

ROUTINES_FORMAT = "rnnpb-routines"
ROUTINES_FORMAT_VERSION = 1
DURATION_STEPS = 80.0
"""Steps a duration of 1 stands for (longer than any part of a routine one expects: six
and a half of the demonstrator's 12-step cycles)."""


@dataclass(frozen=True)
class SegmentConfig:
    """Where the lower PB stream is cut into segments (defaults with their reasons).

    hold : int
        Steps the lower PB must stay nearest one learned pattern's PB to begin a segment of
        it: half a cycle, so a PB passing by on its way is none.
    min_length : int
        Steps a segment must last: one cycle of the demonstrator's patterns.
    """

    hold: int = 6
    min_length: int = 12

    def __post_init__(self) -> None:
        if self.hold < 1 or self.min_length < 1:
            raise ConfigError("segment hold and min_length must be >= 1")


@dataclass(frozen=True)
class Segment:
    """A stretch of the lower PB stream: steps ``start`` to ``stop - 1``; ``pb`` its code,
    the learned PB (index ``pattern`` in the lower model's order) it stays nearest."""

    start: int
    stop: int
    pb: np.ndarray
    pattern: int = -1


def segment_pb(
    pbs: np.ndarray, learned: np.ndarray, config: SegmentConfig | None = None
) -> list[Segment]:
    """Cut a lower PB stream (T, P) into segments: where the learned PB (``learned`` (K, P),
    the lower model's) nearest the PB changes and then stays the nearest for ``hold`` steps, a
    segment of it begins; one shorter than ``min_length`` is taken back (the segment before
    goes on). Causal: the segments of the first ``t`` steps are those of the whole stream cut
    at ``t``, except the last, which grows. Steps before the first held PB belong to the first
    segment."""
    config = config or SegmentConfig()
    pbs = np.asarray(pbs, dtype=np.float64)
    learned = np.asarray(learned, dtype=np.float64)
    n = len(pbs)
    if n == 0:
        return []
    nearest = np.argmin(np.linalg.norm(pbs[:, None, :] - learned[None], axis=2), axis=1)
    starts: list[int] = [0]
    labels: list[int] = [-1]
    for t in range(n - config.hold + 1):
        k = int(nearest[t])
        if k == labels[-1] or not np.all(nearest[t : t + config.hold] == k):
            continue
        if labels[-1] < 0:
            labels[-1] = k
        elif t - starts[-1] >= config.min_length:
            starts.append(t)
            labels.append(k)
        elif len(starts) > 1 and labels[-2] == k:  # a short excursion: the one before goes on
            starts.pop()
            labels.pop()
        else:
            labels[-1] = k
    if labels[-1] < 0:
        labels[-1] = int(nearest[-1])
    bounds = [*starts, n]
    return [
        Segment(a, b, learned[k].copy(), k)
        for a, b, k in zip(bounds[:-1], bounds[1:], labels, strict=True)
    ]


def routine_events(segments: SequenceABC[Segment], start: bool = True) -> np.ndarray:
    """The higher level's inputs for segments: one row per segment, ``[code, previous
    duration]`` (P + 1), after the start event (every code value 0.5, duration 0) when
    ``start``. Shape (len(segments) + start, P + 1)."""
    if not segments:
        return np.zeros((0, 0))
    p = len(segments[0].pb)
    rows = [np.concatenate([np.full(p, 0.5), [0.0]])] if start else []
    previous = 0.0
    for segment in segments:
        rows.append(np.concatenate([segment.pb, [previous]]))
        previous = min((segment.stop - segment.start) / DURATION_STEPS, 1.0)
    return np.clip(np.array(rows), 0.0, 1.0)


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
    codes : array, shape (K, P)
        The lower model's learned PBs, in its order: the segments' codes.
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
    codes: np.ndarray
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
            "lower_patterns": len(self.codes),
            "segments": asdict(self.segments),
            "recognition_error": self.recognition_error,
            **{k: v for k, v in self.meta.items() if k not in _META_KEYS},
        }
        arrays = {f"params/{k}": v for k, v in params_to_numpy(self.params).items()}
        arrays["routine_pb"] = np.array([self.routine_pb[n] for n in names])
        arrays["routine_context"] = np.array([self.routine_context[n] for n in names])
        arrays["codes"] = np.asarray(self.codes)
        save_archive(path, meta, arrays)

    @classmethod
    def load(cls, path: str | os.PathLike[str], lower: TrainedModel | None = None) -> RoutineModel:
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
                codes=np.asarray(arrays["codes"], dtype=np.float64),
                segments=SegmentConfig(**meta["segments"]),
                recognition_error=float(meta["recognition_error"]),
                meta={k: v for k, v in meta.items() if k not in _META_KEYS},
            )
        except (KeyError, TypeError, ValueError, IndexError) as error:
            raise ModelFileError(f"{path}: not a valid routine file ({error})") from None
        finite = all(np.all(np.isfinite(arrays[k])) for k in ("routine_pb", "codes"))
        if not finite or not (
            math.isfinite(routines.recognition_error) and routines.recognition_error > 0
        ):
            raise ModelFileError(
                f"{path}: routine PBs, codes and recognition_error must be finite "
                "(recognition_error > 0)"
            )
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
    "lower_patterns",
    "segments",
    "recognition_error",
)


def _members(path: Path, meta: dict[str, Any]) -> dict[str, tuple[int, ...] | None]:
    try:
        network = NetworkConfig(**meta["network"])
        k = len(meta["routines"])
        int(meta["lower_patterns"])
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
        "codes": (int(meta["lower_patterns"]), network.sensory_size),
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
    recordings' hands (each (T, 4) in [0, 1], a routine performed once or more in a row);
    each recording is run through the lower level on-line and its PB stream segmented into
    the higher level's events."""
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
            takes.append(sensory)
            names.append(name)
    codes = np.array(list(lower.pattern_pb.values()))
    events = []
    for name, pbs in zip(names, lower_pb_streams(lower, takes), strict=True):
        found = segment_pb(pbs, codes, segments)
        if len(found) < 2:
            raise DataFileError(
                f"routine {name!r}: a recording holds {len(found)} segment of the lower "
                "level's PB; a routine needs at least two movements"
            )
        events.append(routine_events(found))
    return learn_from_events(lower.fingerprint, codes, names, events, learning, segments)


def learn_from_events(
    lower_fingerprint: str,
    codes: np.ndarray,
    names: SequenceABC[str],
    events: SequenceABC[np.ndarray],
    learning: RoutineLearning,
    segments: SegmentConfig,
) -> RoutineModel:
    """The learning itself, from each recording's events (each (E_i, P + 1), the start event
    first: :func:`routine_events`)."""
    p_lower = events[0].shape[1] - 1
    network = NetworkConfig(
        sensory_size=p_lower,
        motor_size=1,
        pb_size=learning.pb_size,
        hidden_size=learning.hidden_size,
        context_size=learning.context_size,
    )
    n_steps = max(len(e) for e in events)
    inputs = np.full((len(events), n_steps, network.io_size), 0.5)
    valid = np.zeros((len(events), n_steps - 1), dtype=bool)
    for i, sequence in enumerate(events):
        inputs[i, : len(sequence)] = sequence
        valid[i, : len(sequence) - 1] = True
    data = TrainingData(
        inputs, valid, tuple(names), np.zeros(network.io_size), np.ones(network.io_size)
    )
    # Eq. 1's sum over the whole sequence: each sequence's PB stays one value (the routine's),
    # not a profile that could itself carry the order.
    # One initial context for all (the start event's): the routine's PB alone must say how it
    # begins, as it must on-line, where nothing else tells routines apart.
    config = TrainConfig.fast(iterations=learning.iterations, seed=learning.seed).with_tuning(
        pb={"integration_length": 2 * n_steps}, learn_initial_context=False
    )
    state = init_state(data, network, config)
    state = chunk_runner(config)(
        state,
        jnp.asarray(inputs, jnp.float32),
        jnp.asarray(valid),
        jnp.asarray(learning.iterations, jnp.int32),
        jnp.ones(len(events), bool),
    )
    pb = np.asarray(jax.nn.sigmoid(state.rho), dtype=np.float64)  # (S, E-1, Q)
    sequence_pb = np.array([pb[i][valid[i]].mean(axis=0) for i in range(len(events))])
    labels = np.asarray(names)
    order = list(dict.fromkeys(names))
    routine_pb = {n: sequence_pb[labels == n].mean(axis=0) for n in order}
    params = jax.tree_util.tree_map(lambda a: jnp.asarray(a, jnp.float32), state.params)
    # Every routine starts from one context (the start event's), so that the follower can
    # compare them from the same onset: the mean of the learned ones.
    context = np.asarray(jax.nn.sigmoid(state.initial_context_logit), dtype=np.float64)
    context = context.mean(axis=0)
    errors = [
        _code_errors(params, context, routine_pb[names[i]], sequence).mean()
        for i, sequence in enumerate(events)
    ]
    return RoutineModel(
        network=network,
        params=params,
        routine_pb=routine_pb,
        routine_context={n: context for n in order},
        lower_fingerprint=lower_fingerprint,
        codes=np.asarray(codes, dtype=np.float64),
        segments=segments,
        recognition_error=max(RECOGNITION_FLOOR, 2.0 * float(max(errors))),
        meta={"learning": asdict(learning), "sequences": list(names)},
    )


RECOGNITION_FLOOR = 0.01
"""The least error a routine is refused at (mean squared per code value): codes of different
learned patterns lie farther apart than this (0.5 or more in PB distance)."""
MAX_EVENTS = 24
"""Segments the follower runs over (the most recent); older ones are forgotten."""


def _code_errors(params: Params, context: np.ndarray, pb: np.ndarray, events: np.ndarray):
    """Squared error of each predicted segment code (mean over the code values), (E-1,)."""
    predictions, _ = _open(
        params,
        jnp.asarray(context, jnp.float32),
        jnp.asarray(events[:-1], jnp.float32),
        jnp.broadcast_to(jnp.asarray(pb, jnp.float32), (len(events) - 1, len(pb))),
    )
    p = events.shape[1] - 1
    return np.mean((np.asarray(predictions)[:, :p] - events[1:, :p]) ** 2, axis=1)


_open = jax.jit(open_loop)


_FOLLOW_PB = PBUpdateConfig(
    learning_rate=0.5, momentum=0.8, k_bp=1.0, k_nb=0.0, integration_length=2 * MAX_EVENTS
)


@partial(jax.jit, static_argnames=("iterations",))
def _regress(
    params: Params,
    context: jax.Array,
    inputs: jax.Array,
    valid: jax.Array,
    rho: jax.Array,
    routine_rho: jax.Array,
    iterations: int,
) -> tuple[jax.Array, jax.Array, jax.Array]:
    """Regress a constant higher PB over the events seen (eqs. 1-2, summed over them):
    ``inputs`` (W, I), ``valid`` (W-1,) the steps that predict a real event, ``rho`` (Q,);
    and run each learned routine's PB (``routine_rho`` (K, Q), logits) over the same events.
    Returns the PB's logit, the predictions (K + 1, W, I) (the routines', then the regressed
    PB's), and the mean squared code error of each (K + 1,)."""
    p = inputs.shape[1] - 1
    n_valid = jnp.maximum(valid.sum(), 1)

    def run(r: jax.Array) -> tuple[jax.Array, jax.Array]:
        pbs = jnp.broadcast_to(jax.nn.sigmoid(r), (inputs.shape[0], r.shape[0]))
        predictions, _ = open_loop(params, context, inputs, pbs)
        e = ((predictions[:-1, :p] - inputs[1:, :p]) ** 2).sum(axis=1)
        return predictions, 0.5 * jnp.sum(e * valid)

    grad = jax.grad(lambda r: run(r)[1])

    def iteration(_, carry):
        r, v = carry
        g = grad(r)[None]
        r2, v2 = pb_update(r[None], v[None], g, _FOLLOW_PB)
        return r2[0], v2[0]

    rho, _ = jax.lax.fori_loop(0, iterations, iteration, (rho, jnp.zeros_like(rho)))
    predictions, errors = jax.lax.map(run, jnp.concatenate([routine_rho, rho[None]]))
    return rho, predictions, 2.0 * errors / (n_valid * p)


@dataclass(frozen=True)
class FollowStep:
    """What the higher level says after a step.

    Attributes
    ----------
    routine : str or None
        The learned routine being performed, or None (none fits well enough).
    pb : array, shape (Q,)
        The regressed higher PB.
    predicted_pb : array, shape (P,)
        The lower PB the routine predicts for the next movement.
    steps_left : float
        Steps until the current movement ends, as predicted (negative: overdue; NaN when
        no routine is recognised).
    switch_due : bool
        A routine is recognised and its predicted switch is at most ``lead`` steps away.
    error : float
        The chosen PB's mean squared code error over the segments seen (NaN before any).
    """

    routine: str | None
    pb: np.ndarray
    predicted_pb: np.ndarray
    steps_left: float
    switch_due: bool
    error: float


class RoutineFollower:
    """The higher level on-line: fed the lower PB each step (:meth:`observe`), it segments
    the stream, regresses its PB over the segments seen, says which routine it sees, and
    predicts the next movement and when it starts.

    ``lead``: steps before the predicted switch from which it counts as due (the lower
    level needs a step or two of the new movement's evidence). ``iterations``: regression
    iterations per step.
    """

    def __init__(self, routines: RoutineModel, lead: int = 1, iterations: int = 30) -> None:
        if iterations < 1 or lead < 0:
            raise ConfigError("the follower needs iterations >= 1 and lead >= 0")
        self.routines = routines
        self.lead = lead
        self.iterations = iterations
        self._params = jax.tree_util.tree_map(
            lambda a: jnp.asarray(a, jnp.float32), routines.params
        )
        self._names = routines.routines
        self._routine_rho = jnp.asarray(
            logit_numpy(np.array([routines.routine_pb[n] for n in self._names])), jnp.float32
        )
        self._context = jnp.asarray(
            np.mean(list(routines.routine_context.values()), axis=0), jnp.float32
        )
        self.reset()

    def reset(self) -> None:
        self._stream: list[np.ndarray] = []
        self._offset = 0  # the step the kept stream starts at
        self._done: list[Segment] = []  # finished segments (absolute steps)
        self._rho = jnp.zeros(self.routines.network.pb_size, jnp.float32)
        self.steps = 0

    def observe(self, lower_pb: np.ndarray) -> FollowStep:
        """Take the lower level's PB of this step; return what the higher level says."""
        self._stream.append(np.asarray(lower_pb, dtype=np.float64))
        self.steps += 1
        found = segment_pb(np.array(self._stream), self.routines.codes, self.routines.segments)
        if len(found) > 1:  # finished segments leave the stream
            for segment in found[:-1]:
                self._done.append(
                    Segment(segment.start + self._offset, segment.stop + self._offset, segment.pb)
                )
            cut = found[-1].start
            self._stream = self._stream[cut:]
            self._offset += cut
            found = segment_pb(np.array(self._stream), self.routines.codes, self.routines.segments)
        current = Segment(found[-1].start + self._offset, self.steps, found[-1].pb)
        del self._done[: -MAX_EVENTS + 1]
        segments = [*self._done, current]
        events = routine_events(segments)
        w = MAX_EVENTS + 1
        padded = np.full((w, events.shape[1]), 0.5)
        padded[: len(events)] = events
        valid = np.arange(w - 1) < len(events) - 1
        self._rho, predictions, errors = _regress(
            self._params,
            self._context,
            jnp.asarray(padded, jnp.float32),
            jnp.asarray(valid),
            self._rho,
            self._routine_rho,
            self.iterations,
        )
        pb = np.asarray(jax.nn.sigmoid(self._rho), dtype=np.float64)
        errors = np.asarray(errors, dtype=np.float64)
        best = int(np.argmin(errors[:-1]))
        # A segment is known once it has held: before that the code is still moving.
        known = bool(errors[best] <= self.routines.recognition_error)
        routine = self._names[best] if known else None
        chosen = best if known else len(self._names)
        predicted = np.asarray(predictions[chosen, len(events) - 1], dtype=np.float64)
        p = self.routines.network.sensory_size
        steps_left = math.nan
        due = False
        if known:
            duration = float(predicted[p]) * DURATION_STEPS
            steps_left = current.start + duration - self.steps
            codes = self.routines.codes
            following = int(np.argmin(np.linalg.norm(codes - predicted[:p], axis=1)))
            due = steps_left <= self.lead and following != current.pattern
        return FollowStep(
            routine, pb, np.clip(predicted[:p], 0.0, 1.0), steps_left, due, float(errors[chosen])
        )


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
        meta: MetaParams | None = None,
        recognition: RecognitionConfig | None = None,
        **options: Any,
    ) -> None:
        """``config``, ``meta``, ``recognition`` and ``options`` (the meta-level's
        ``steering`` and ``inhibition``): the lower mirror system's (:class:`MirrorSystem`);
        ``use_prior`` False: the higher level only watches."""
        routines.check_lower(lower)
        self.lower = lower
        self.mirror = MirrorSystem(
            lower, config or OnlineConfig.for_model(lower).config, meta, recognition, **options
        )
        self.follower = RoutineFollower(routines)
        self.use_prior = use_prior
        self._last: FollowStep | None = None

    def step(self, observed_hands: np.ndarray) -> TwoLevelStep:
        """One step of both levels (``observed_hands`` as :meth:`MirrorSystem.step`)."""
        prior = None
        last = self._last
        if self.use_prior and last is not None and last.switch_due:
            prior = last.predicted_pb
        result = self.mirror.step(observed_hands, prior_pb=prior)
        self._last = higher = self.follower.observe(result.pb)
        anticipated = None
        if higher.routine is not None:
            anticipated = self.lower.nearest_pattern(higher.predicted_pb)[0]
        return TwoLevelStep(result, higher, anticipated)


def generate_routine(
    lower: TrainedModel, routines: RoutineModel, name: str, n_steps: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Perform a routine alone, top-down: the higher level in closed loop from the start
    event with the routine's PB gives each movement's PB and duration, and the lower level in
    closed loop generates the movements with them, one after the other. Returns the lower PB
    (n, P), the imagined hands (n, 4) and the joint angles (n, 8), radians."""
    routines.check_lower(lower)
    if name not in routines.routine_pb:
        raise ConfigError(f"unknown routine {name!r} (known: {', '.join(routines.routines)})")
    if n_steps < 1:
        raise ConfigError(f"number of steps must be >= 1, got {n_steps}")
    net = routines.network
    p = net.sensory_size
    params = jax.tree_util.tree_map(lambda a: jnp.asarray(a, jnp.float32), routines.params)
    context = jnp.asarray(routines.routine_context[name], jnp.float32)
    pb = jnp.asarray(routines.routine_pb[name], jnp.float32)
    # Enough events for n_steps: every part lasts at least min_length steps.
    n_events = n_steps // routines.segments.min_length + 2
    x = jnp.asarray(np.concatenate([np.full(p, 0.5), [0.0]]), jnp.float32)
    codes, durations = [], []
    for _ in range(n_events):
        context, y = step(params, context, x, pb)
        codes.append(np.clip(np.asarray(y[:p], dtype=np.float64), 0.0, 1.0))
        durations.append(float(y[p]))
        x = y
    # Event j's code lasts the duration predicted with event j + 1.
    lower_pb = []
    for j, code in enumerate(codes[:-1]):
        length = max(routines.segments.min_length, round(durations[j + 1] * DURATION_STEPS))
        lower_pb += [code] * length
        if len(lower_pb) >= n_steps:
            break
    lower_pb = np.array(lower_pb[:n_steps])
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
    "DURATION_STEPS",
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
    "learn_from_events",
    "learn_routines",
    "routine_events",
    "segment_pb",
]
