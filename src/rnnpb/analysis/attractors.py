"""The plane in which attractors are compared (the paper's Figure 9): the context units that
vary most, and the context's principal components over the learned attractors."""

from __future__ import annotations

from typing import Protocol

import numpy as np


class ClosedLoopRun(Protocol):
    """What Figure 9 reads of a learned pattern's closed-loop attractor
    (:class:`rnnpb.experiments.paper.Attractor`)."""

    context: np.ndarray  # (T, C)


def context_units(attractors: dict[str, ClosedLoopRun]) -> tuple[int, int]:
    """The two context units that vary most over the learned attractors (for phase plots)."""
    stacked = np.concatenate([a.context for a in attractors.values()])
    order = np.argsort(stacked.var(axis=0))[::-1]
    return int(order[0]), int(order[1])


def context_plane(
    attractors: dict[str, ClosedLoopRun],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The plane of Figure 9: the first two principal components of the context over the
    learned attractors.

    The context units that vary most move together (their plane shows each attractor as a
    thin ellipse on the diagonal); the principal components separate the common swing from
    what differs, and so show each attractor's shape.

    Returns
    -------
    mean : array, shape (C,)
    axes : array, shape (2, C)
        The two components, unit vectors, each signed so that its largest entry is positive.
    explained : array, shape (2,)
        The share of the context's variance over the attractors each explains.
    """
    stacked = np.concatenate([a.context for a in attractors.values()])
    mean = stacked.mean(axis=0)
    _, singular, vt = np.linalg.svd(stacked - mean, full_matrices=False)
    components = np.zeros((2, stacked.shape[1]))
    components[: len(vt[:2])] = vt[:2]
    largest = components[np.arange(2), np.argmax(np.abs(components), axis=1)]
    components *= np.where(largest < 0, -1.0, 1.0)[:, None]
    singular = np.pad(singular[:2], (0, max(0, 2 - len(singular))))
    total = float(((stacked - mean) ** 2).sum())
    return mean, components, singular**2 / max(total, 1e-300)
