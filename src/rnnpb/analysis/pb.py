"""The PB's path through a session: its columns, its jumps, and the learned pattern it lies
nearest at each step."""

from __future__ import annotations

import numpy as np

from rnnpb.vectors import STEP_COLUMN, pb_column

#: A PB change larger than this in one step (any unit) is marked as a jump: the on-line
#: regression restarted from a learned pattern's PB or from a state on a learned cycle. Between
#: restarts the PB moves by less than about 0.08 a step (measured on the demo's sessions).
PB_JUMP = 0.15


def pb_matrix(session: dict[str, np.ndarray]) -> np.ndarray:
    """The session's PB columns as one array, shape (T, P)."""
    columns = []
    while pb_column(len(columns)) in session:
        columns.append(np.asarray(session[pb_column(len(columns))], dtype=np.float64))
    return np.stack(columns, axis=1) if columns else np.zeros((len(session[STEP_COLUMN]), 0))


def pb_jumps(pb: np.ndarray, threshold: float = PB_JUMP) -> np.ndarray:
    """Indices of the steps where the PB (T, P) moved by more than ``threshold`` in some unit
    since the step before (the first step is never one)."""
    if len(pb) < 2:
        return np.zeros(0, dtype=int)
    change = np.nanmax(np.abs(np.diff(pb, axis=0)), axis=1, initial=0.0)
    return np.flatnonzero(change > threshold) + 1


def nearest_patterns(pb: np.ndarray, pattern_pb: dict[str, np.ndarray]) -> list[str]:
    """Per step, the learned pattern whose PB is nearest the PB (T, P) (Euclidean)."""
    names = list(pattern_pb)
    learned = np.stack([np.asarray(pattern_pb[n], dtype=np.float64) for n in names])
    distance = np.linalg.norm(pb[:, None, :] - learned[None, :, :], axis=2)
    return [names[i] for i in np.argmin(distance, axis=1)]
