"""Experience: the robot explores its PB space and labels each PB by the safety of the
behaviour it generates (Ito & Tani 2004, section 4.1: the meta-level learns "safe or unsafe
regions in the PB space from experience").

Closed-loop generation (:func:`rnnpb.model.network.closed_loop`) runs from many PB values at
once (one batched, compiled call); each run's motor sequence goes through
:class:`SafetyChecker`. PBs visited in interactions, with whether the command at that step was
unsafe, join the experience as they are.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.model import TrainedModel
from rnnpb.model.network import closed_loop
from rnnpb.safety._check import SafetyChecker


@dataclass(frozen=True)
class ExplorationConfig:
    """``samples`` PBs: half drawn uniformly from [0, 1]^P, half around the learned PBs
    (normal, ``spread`` wide, clipped); each generates ``steps`` closed-loop steps from the
    mean learned initial context; ``batch`` PBs per compiled call."""

    samples: int = 2000
    steps: int = 80
    spread: float = 0.15
    batch: int = 250
    seed: int = 0

    def __post_init__(self) -> None:
        if self.samples < 1 or self.steps < 2 or self.batch < 1:
            raise ConfigError("samples and batch must be >= 1 and steps >= 2")
        if self.spread <= 0:
            raise ConfigError(f"spread must be > 0, got {self.spread}")


@dataclass(frozen=True)
class Experience:
    """Labelled PBs. ``pb`` (N, P); ``unsafe`` (N,) bool (a physical reason at any step);
    ``unsettled`` (N,) bool; ``source`` (N,) "explored" or "visited"; ``counts``: how many
    explored PBs had each kind of reason."""

    pb: np.ndarray
    unsafe: np.ndarray
    unsettled: np.ndarray
    source: np.ndarray
    counts: dict[str, int]

    def joined(self, other: Experience) -> Experience:
        return Experience(
            np.concatenate([self.pb, other.pb]),
            np.concatenate([self.unsafe, other.unsafe]),
            np.concatenate([self.unsettled, other.unsettled]),
            np.concatenate([self.source, other.source]),
            {
                k: self.counts.get(k, 0) + other.counts.get(k, 0)
                for k in {*self.counts, *other.counts}
            },
        )


_closed_loop = jax.jit(closed_loop)


def sample_pbs(model: TrainedModel, config: ExplorationConfig) -> np.ndarray:
    """The PBs to explore, (samples, P): uniform, and near the learned PBs."""
    rng = np.random.default_rng(config.seed)
    p = model.network.pb_size
    learned = np.array(list(model.pattern_pb.values()))
    n_uniform = config.samples - config.samples // 2
    uniform = rng.uniform(size=(n_uniform, p))
    centres = learned[rng.integers(len(learned), size=config.samples // 2)]
    near = np.clip(centres + rng.normal(0.0, config.spread, centres.shape), 0.0, 1.0)
    return np.concatenate([uniform, near])


def explore(
    model: TrainedModel,
    config: ExplorationConfig | None = None,
    checker: SafetyChecker | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> Experience:
    """Generate from many PBs and label each by the safety of its behaviour.

    ``progress(done, total)`` is called after each PB is checked.
    """
    config = config or ExplorationConfig()
    checker = checker or SafetyChecker()
    pbs = sample_pbs(model, config)
    net = model.network
    params = jax.tree_util.tree_map(lambda a: jnp.asarray(a, jnp.float32), model.params)
    unsafe = np.zeros(len(pbs), bool)
    unsettled = np.zeros(len(pbs), bool)
    counts = dict.fromkeys(("collision", "speed", "limit", "unsettled"), 0)
    done = 0
    for start in range(0, len(pbs), config.batch):
        chunk = pbs[start : start + config.batch]
        n = len(chunk)
        predictions, _ = _closed_loop(
            params,
            jnp.broadcast_to(
                jnp.asarray(model.mean_initial_context, jnp.float32), (n, net.context_size)
            ),
            jnp.full((n, net.io_size), 0.5, jnp.float32),
            jnp.broadcast_to(jnp.asarray(chunk, jnp.float32), (config.steps, n, net.pb_size)),
        )
        motor = model.denormalize(np.asarray(predictions, dtype=np.float64))[
            ..., net.sensory_size :
        ]
        for i in range(n):
            report = checker.check(motor[:, i])
            unsafe[start + i] = bool(report.unsafe.any())
            unsettled[start + i] = bool(report.kinds[:, 3].any())
            for k, kind in enumerate(report.KINDS):
                counts[kind] += int(report.kinds[:, k].any())
            done += 1
            if progress is not None:
                progress(done, len(pbs))
    return Experience(pbs, unsafe, unsettled, np.array(["explored"] * len(pbs)), counts)


def visited(
    pbs: Sequence[np.ndarray] | np.ndarray, unsafe: Sequence[bool] | np.ndarray
) -> Experience:
    """PBs visited in an interaction, (n, P), each labelled by whether the command sent at
    that step was unsafe (n,)."""
    pbs = np.asarray(pbs, dtype=np.float64)
    unsafe = np.asarray(unsafe, bool)
    if pbs.ndim != 2 or len(pbs) != len(unsafe):
        raise ConfigError(
            f"visited PBs (n, P) and labels (n,) disagree: {pbs.shape}, {unsafe.shape}"
        )
    return Experience(
        pbs,
        unsafe,
        np.zeros(len(pbs), bool),
        np.array(["visited"] * len(pbs)),
        {"visited_unsafe": int(unsafe.sum())},
    )
