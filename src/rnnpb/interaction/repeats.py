"""Repeats: whether a movement just kept is another performance of one the short-term memory
holds already, so that a shape shown twice becomes one pattern learned from both performances,
never two patterns (docs/teaching.md).

Two movements are compared by their shape, as the novelty detector compares what it sees with
the hands a pattern was taught with (:func:`rnnpb.model.recognition.taught_stretches` and
:func:`~rnnpb.model.recognition.taught_distances`): every ``template_steps``-long window of one
is matched against the other's stretches at every template speed, at any phase and size. The
distance of the two is the median window's, taken both ways and the larger kept (a movement
that is a part of another — one arm of a two-armed shape — is near it one way only). Below the
recognition's ``template_level``, the distance at which the detector finds a taught shape and
"none learned" as likely, the two are the same movement.

NumPy only; the memory is read, never written.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rnnpb.model.recognition import RecognitionConfig, taught_distances, taught_stretches

REPEAT_STATUSES = ("kept", "learned")
"""The episodes a new one may be a repeat of: those waiting to be learned and those learned
(a discarded episode was refused by the person)."""
COMPARED_PER_MOVEMENT = 2
"""Newest episodes of each movement a new one is compared with: two performances show its
shape, and the cost stays a few milliseconds per movement however often it was performed."""


@dataclass(frozen=True)
class Repeat:
    """The kept episode a new movement repeats: its ``episode_id``, ``pattern`` and the two
    shapes' ``distance`` (0 the same shape; 1 nothing in common)."""

    episode_id: int
    pattern: str
    distance: float

    def describe(self) -> str:
        return f"shape distance {self.distance:.2f}"


def _window_distances(seen: np.ndarray, stretches, config: RecognitionConfig) -> np.ndarray:
    """The distance to the stretches' shape of each ``template_steps`` window of ``seen``, by
    the window's first step."""
    windows = np.lib.stride_tricks.sliding_window_view(seen, config.template_steps, axis=0)
    return np.array([taught_distances(w.T, stretches)[0] for w in windows])  # w: (S, W)


def _one_way(seen: np.ndarray, kept: np.ndarray, config: RecognitionConfig) -> float:
    """The median distance of ``seen``'s windows to ``kept``'s shape (1 when either is too
    short or does not move)."""
    stretches = taught_stretches({"kept": [kept]}, ("kept",), config)
    if stretches is None or len(seen) < config.template_steps:
        return 1.0
    return float(np.median(_window_distances(seen, stretches, config)))


def shape_distance(a: np.ndarray, b: np.ndarray, config: RecognitionConfig | None = None) -> float:
    """How unlike two movements' shapes are, in [0, 1] (module doc): ``a`` and ``b`` are the
    hands seen, (T_a, 4) and (T_b, 4), sensory values in [0, 1] with no missing step."""
    config = config or RecognitionConfig()
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    return max(_one_way(a, b, config), _one_way(b, a, config))


def same_cycles(
    sensory: np.ndarray,
    cycles: Sequence[tuple[int, int]],
    kept: np.ndarray,
    config: RecognitionConfig | None = None,
) -> int:
    """How many of ``sensory``'s whole ``cycles`` (``(start, stop)`` steps, in order), from
    the first, repeat ``kept``'s shape: every ``template_steps`` window within the cycle (the
    one ending at its stop when it is shorter) nearer it than ``template_level``, as
    :func:`find_repeat` decides a repeat. A performance that went on is the same movement up
    to the first cycle unlike it (the detector calls a switch novel for a few steps)."""
    config = config or RecognitionConfig()
    sensory = np.asarray(sensory, dtype=np.float64)
    stretches = taught_stretches({"kept": [np.asarray(kept, dtype=np.float64)]}, ("kept",), config)
    steps = config.template_steps
    if stretches is None or len(sensory) < steps:
        return 0
    distances = _window_distances(sensory, stretches, config)
    count = 0
    for start, stop in cycles:
        # the windows that begin in the cycle and end by its stop (the one ending at its stop
        # when it is shorter than a window)
        first = max(0, min(start, stop - steps))
        within = distances[first : max(first, stop - steps) + 1]
        if not within.size or within.max() >= config.template_level:
            break
        count += 1
    return count


def find_repeat(
    memory,
    sensory: np.ndarray,
    config: RecognitionConfig | None = None,
) -> Repeat | None:
    """The memory's episode (kept or learned; the newest
    :data:`COMPARED_PER_MOVEMENT` of each movement) whose movement ``sensory`` repeats — the
    nearest shape, when it is nearer than ``config.template_level`` — or None."""
    config = config or RecognitionConfig()
    best: Repeat | None = None
    newest: dict[str, list] = {}
    for summary in reversed(memory.episodes()):
        if summary.status not in REPEAT_STATUSES:
            continue
        group = newest.setdefault(summary.pattern, [])
        if len(group) < COMPARED_PER_MOVEMENT:
            group.append(summary)
    for summary in (s for group in newest.values() for s in group):
        distance = shape_distance(sensory, memory.episode(summary.id).sensory, config)
        if distance < config.template_level and (best is None or distance < best.distance):
            best = Repeat(summary.id, summary.pattern, distance)
    return best
