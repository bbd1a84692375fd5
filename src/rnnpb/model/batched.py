"""Many sessions in one call: :class:`BatchedMirror` steps ``B`` independent interactions with
the same trained model (users, draws, seeds) in one step.

Each session is what a :class:`rnnpb.model.MirrorSystem` of the same model and settings would
be: its own window, PB, onset and recognition, started from its own initial PB. The step is one
call of :func:`rnnpb.model.online.step_sessions` for all sessions (the weights, restarts and
settings shared), whose regression runs the sessions' windows a few at a time
(:data:`rnnpb.model.online.GROUP`), each loaded weight serving all of them; the outputs come
back as a (B, outputs) array, and recognition then runs on the host for each session, as in
``MirrorSystem``. ``tests/model/test_batched.py`` holds it to ``B`` separate mirror systems
step by step.

:func:`run_streams` runs many recorded streams (the runs of an experiment) through a pool of
batched sessions: a session that finishes its stream starts the next one afresh.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.model.io import TrainedModel
from rnnpb.model.meta import MetaParams
from rnnpb.model.mirror import MirrorSystem, StepResult, normalized_hands
from rnnpb.model.online import OnlineState, initial_state, step_sessions
from rnnpb.model.online_config import OnlineConfig
from rnnpb.model.recognition import (
    RecognitionConfig,
    RecognitionState,
    initial_recognition_state,
)


class BatchedMirror:
    """``sessions`` independent on-line interactions with one trained model, stepped together.

    >>> mirrors = BatchedMirror(model, sessions=16)               # doctest: +SKIP
    >>> results = mirrors.step(hands)   # hands (16, 4); a list of 16 StepResult  # doctest: +SKIP

    Parameters
    ----------
    model, config, meta, recognition
        As for :class:`rnnpb.model.MirrorSystem`; shared by every session.
    sessions : int
        B, the sessions stepped together.
    initial_pb : array, shape (B, P), optional
        Each session's PB at its start (default: the centre of the learned PBs, as
        ``MirrorSystem``).
    native : bool
        As for ``MirrorSystem``: the sessions' regression loops in native code, a few
        sessions to a kernel call (:data:`rnnpb.model.native.GROUP`).
    """

    def __init__(
        self,
        model: TrainedModel,
        sessions: int,
        config: OnlineConfig | None = None,
        meta: MetaParams | None = None,
        recognition: RecognitionConfig | None = None,
        initial_pb: np.ndarray | None = None,
        native: bool = True,
    ) -> None:
        if isinstance(sessions, bool) or not isinstance(sessions, int) or sessions < 1:
            raise ConfigError(f"sessions must be a whole number >= 1, got {sessions!r:.40}")
        # One mirror system holds what the sessions share (weights, restarts, settings) and
        # does each session's host side; the sessions' own state is kept here.
        self._shared = MirrorSystem(model, config, meta, recognition, native=native)
        self.model = model
        self.config = self._shared.config
        self.recognition = self._shared.recognition
        self.patterns = self._shared.patterns
        self.sessions = sessions
        self._states: OnlineState = self._initial_states(initial_pb)
        self._recognition: list[RecognitionState] = [
            self._fresh_recognition() for _ in range(sessions)
        ]
        self._predicted: list[np.ndarray | None] = [None] * sessions
        self.steps = 0

    def _fresh_recognition(self) -> RecognitionState:
        net = self.model.network
        return initial_recognition_state(net.sensory_size, net.pb_size, self.recognition)

    def _initial_states(self, initial_pb: np.ndarray | None) -> OnlineState:
        if initial_pb is None:
            starts: list[np.ndarray | None] = [None] * self.sessions
        else:
            pbs = np.asarray(initial_pb, dtype=np.float64)
            if pbs.shape != (self.sessions, self.model.network.pb_size):
                raise ConfigError(
                    f"initial_pb must have shape ({self.sessions}, "
                    f"{self.model.network.pb_size}), got {pbs.shape}"
                )
            starts = list(pbs)
        states = [initial_state(self.model, self.config, pb) for pb in starts]
        return OnlineState(*(np.concatenate(parts) for parts in zip(*states, strict=True)))

    def reset(self, initial_pb: np.ndarray | None = None) -> None:
        """Forget every session's window: the next step starts new interactions
        (``initial_pb`` as for the constructor)."""
        self._states = self._initial_states(initial_pb)
        self._recognition = [self._fresh_recognition() for _ in range(self.sessions)]
        self._predicted = [None] * self.sessions
        self.steps = 0

    def reset_session(self, index: int, initial_pb: np.ndarray | None = None) -> None:
        """Start session ``index`` afresh (a new user); the others go on."""
        if not 0 <= index < self.sessions:
            raise ConfigError(f"session {index} does not exist: there are {self.sessions}")
        self._states.put(index, initial_state(self.model, self.config, initial_pb))
        self._recognition[index] = self._fresh_recognition()
        self._predicted[index] = None

    @property
    def pb(self) -> np.ndarray:
        """Each session's current PB, shape (B, P)."""
        n = np.maximum(np.asarray(self._states.n) - 1, 0)
        rho = np.asarray(self._states.rho, dtype=np.float64)[np.arange(self.sessions), n]
        return 1.0 / (1.0 + np.exp(-rho))

    def step(self, observed_hands: np.ndarray) -> list[StepResult]:
        """Observe every session's hands for this step; regress each session's PB; return
        each session's result, in order.

        Parameters
        ----------
        observed_hands : array, shape (B, 4)
            Row ``b`` is session ``b``'s ``lhy lhz rhy rhz`` (NaN where not seen), as
            :meth:`rnnpb.model.MirrorSystem.step` takes it.
        """
        rows = np.asarray(observed_hands, dtype=np.float64)
        if rows.ndim != 2 or rows.shape[0] != self.sessions:
            raise ConfigError(
                f"observed hands must be one row per session ({self.sessions}), "
                f"got shape {rows.shape}"
            )
        size = self.model.network.sensory_size
        hands = [normalized_hands(row, size) for row in rows]
        u = np.stack([h[0] for h in hands])
        seen = np.stack([h[1] for h in hands])
        shared = self._shared
        out = np.empty((self.sessions, shared._layout.pattern_errors.stop), shared.dtype)
        step_sessions(
            shared._net,
            shared._meta,
            self._states,
            u.astype(shared.dtype),
            seen,
            np.full(self.sessions, shared._guarded),
            shared._candidates,
            shared._phase_candidates,
            shared._pattern_rho,
            shared._settings,
            out,
            shared._native,
        )
        packed = out.astype(np.float64)
        results = []
        for b in range(self.sessions):
            result, self._recognition[b], self._predicted[b] = shared._finish(
                packed[b], u[b], seen[b], self._recognition[b], self._predicted[b]
            )
            results.append(result)
        self.steps += 1
        return results


# Sessions stepped together by run_streams: beyond about 16 a session's share of the step
# hardly falls (notes/2026-12-06-batched-runs-step-limits.md).
POOL_SESSIONS = 16


def pool_size(streams: int, most: int = POOL_SESSIONS) -> int:
    """The sessions :func:`run_streams` steps together for ``streams`` streams: as few as
    run them in the same number of rounds as ``most`` sessions would (27 streams: 14, two
    rounds), since every session in the call costs its share whether it has a stream or not."""
    if streams <= 0:
        return 1
    rounds = math.ceil(streams / most)
    return math.ceil(streams / rounds)


def run_streams(
    model: TrainedModel,
    streams: Sequence[np.ndarray],
    config: OnlineConfig | None = None,
    meta: MetaParams | None = None,
    recognition: RecognitionConfig | None = None,
    sessions: int | None = None,
) -> list[list[StepResult]]:
    """Each stream of observed hands, (T, 4) as :meth:`BatchedMirror.step` takes a row, run
    from a fresh session to its end; returns each stream's step results, in order.

    The streams share one :class:`BatchedMirror` of ``sessions`` sessions (default
    :func:`pool_size`): the longest start first, and a session whose stream ends starts the
    next waiting one afresh (:meth:`BatchedMirror.reset_session`), so each stream's results are
    what a :class:`rnnpb.model.MirrorSystem` of its own gives (to the rounding of a batched
    product, ``tests/model/test_batched.py``). A session with no stream left observes nothing
    until the others end.
    """
    rows = [np.asarray(stream, dtype=np.float64) for stream in streams]
    size = model.network.sensory_size
    for i, stream in enumerate(rows):
        if stream.ndim != 2 or stream.shape[1] != size:
            raise ConfigError(
                f"stream {i} must be (steps, {size}) observed hands, got shape {stream.shape}"
            )
    results: list[list[StepResult]] = [[] for _ in rows]
    waiting = sorted((i for i, s in enumerate(rows) if len(s)), key=lambda i: -len(rows[i]))
    if not waiting:
        return results
    width = pool_size(len(waiting)) if sessions is None else min(sessions, len(waiting))
    mirror = BatchedMirror(model, width, config, meta, recognition)
    running: list[int | None] = list(waiting[:width])
    waiting = waiting[width:]
    position = [0] * width
    observed = np.full((width, size), np.nan)
    while any(i is not None for i in running):
        for slot, i in enumerate(running):
            observed[slot] = np.nan if i is None else rows[i][position[slot]]
        step = mirror.step(observed)
        for slot, i in enumerate(running):
            if i is None:
                continue
            results[i].append(step[slot])
            position[slot] += 1
            if position[slot] == len(rows[i]):
                running[slot] = waiting.pop(0) if waiting else None
                position[slot] = 0
                if running[slot] is not None:
                    mirror.reset_session(slot)
    return results
