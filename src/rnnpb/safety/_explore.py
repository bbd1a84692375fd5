"""Experience: the robot explores its PB space and labels each PB by the safety of the
behaviour it generates on its own (Ito & Tani 2004, section 4.1: the meta-level learns "safe
or unsafe regions in the PB space from experience").

Closed-loop generation (:func:`rnnpb.model.network.closed_loop`) runs from many PB values at
once (one batched, compiled call), each from several starts: an initial context (a learned
pattern's, or the mean one, perturbed) and a first input (a random posture and hand
position). Each run's motor sequence after its transient (the first ``transient`` steps, in
which the network leaves an odd start for the PB's own behaviour) goes through
:class:`SafetyChecker`; a PB is unsafe when the share of its starts whose generation is
unsafe reaches ``unsafe_share``. PBs visited in interactions, with whether the command at that
step was unsafe, join the experience as they are.
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
    (normal, ``spread`` wide, clipped); each generates ``steps`` closed-loop steps from each
    of ``starts`` starts (an initial context perturbed by ``start_noise``, a random first
    input); a start's generation is unsafe when a step after its first ``transient`` steps is;
    a PB is unsafe when at least ``unsafe_share`` of its starts are; ``batch`` runs per
    compiled call."""

    samples: int = 2000
    steps: int = 80
    starts: int = 4
    transient: int = 10
    unsafe_share: float = 0.5
    start_noise: float = 0.5
    spread: float = 0.15
    batch: int = 500
    seed: int = 0

    def __post_init__(self) -> None:
        if self.samples < 1 or self.batch < 1 or self.starts < 1:
            raise ConfigError("samples, starts and batch must be >= 1")
        if not 0 <= self.transient <= self.steps - 2:
            raise ConfigError(
                f"steps must be at least the transient + 2 ({max(self.transient, 0) + 2}) "
                f"and the transient >= 0: got steps {self.steps}, transient {self.transient}"
            )
        if not 0 < self.unsafe_share <= 1:
            raise ConfigError(f"unsafe_share must be in (0, 1], got {self.unsafe_share}")
        if self.spread <= 0 or self.start_noise < 0:
            raise ConfigError("spread must be > 0 and start_noise >= 0")


@dataclass(frozen=True)
class Experience:
    """Labelled PBs. ``pb`` (N, P); ``unsafe`` (N,) bool (the PB's label); ``share`` (N,) the
    share of its starts whose generation was unsafe after the transient (for a visited PB:
    1.0 or 0.0, the command sent there); ``unsettled`` (N,) bool; ``source`` (N,)
    "explored" or "visited"; ``counts``: how many explored PBs had each kind of reason after
    the transient, and ``transient_only``: how many had one only within it."""

    pb: np.ndarray
    unsafe: np.ndarray
    share: np.ndarray
    unsettled: np.ndarray
    source: np.ndarray
    counts: dict[str, int]

    def joined(self, other: Experience) -> Experience:
        return Experience(
            np.concatenate([self.pb, other.pb]),
            np.concatenate([self.unsafe, other.unsafe]),
            np.concatenate([self.share, other.share]),
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


def sample_starts(
    model: TrainedModel, count: int, config: ExplorationConfig, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """``count`` starts: initial contexts (count, C), a learned pattern's or the mean one
    with uniform noise of ``start_noise`` (clipped to (0, 1)), and first inputs (count, I),
    uniform in [0.1, 0.9] (a posture and hand position anywhere in the range)."""
    net = model.network
    contexts = np.array(
        [model.pattern_initial_context(name) for name in model.pattern_pb]
        + [model.mean_initial_context]
    )
    chosen = contexts[rng.integers(len(contexts), size=count)]
    noise = rng.uniform(-config.start_noise, config.start_noise, chosen.shape)
    return np.clip(chosen + noise, 0.01, 0.99), rng.uniform(0.1, 0.9, (count, net.io_size))


def generate_from(
    model: TrainedModel,
    pbs: np.ndarray,
    contexts: np.ndarray,
    inputs: np.ndarray,
    steps: int,
    sensory: bool = False,
) -> np.ndarray:
    """Closed-loop generation of each row: the motor commands (steps, n, M), radians (with
    ``sensory``: the predicted hands (steps, n, S) instead)."""
    net = model.network
    params = jax.tree_util.tree_map(lambda a: jnp.asarray(a, jnp.float32), model.params)
    predictions, _ = _closed_loop(
        params,
        jnp.asarray(contexts, jnp.float32),
        jnp.asarray(inputs, jnp.float32),
        jnp.broadcast_to(jnp.asarray(pbs, jnp.float32), (steps, *pbs.shape)),
    )
    values = model.denormalize(np.asarray(predictions, dtype=np.float64))
    return values[..., : net.sensory_size] if sensory else values[..., net.sensory_size :]


def explore(
    model: TrainedModel,
    config: ExplorationConfig | None = None,
    checker: SafetyChecker | None = None,
    progress: Callable[[int, int], None] | None = None,
    pbs: np.ndarray | None = None,
) -> Experience:
    """Generate from many PBs, each from ``config.starts`` starts, and label each PB by the
    safety of its own behaviour after the transient (``pbs``: these PBs instead of
    :func:`sample_pbs`'s).

    ``progress(done, total)`` is called after each PB is checked.
    """
    config = config or ExplorationConfig()
    checker = checker or SafetyChecker()
    pbs = sample_pbs(model, config) if pbs is None else np.asarray(pbs, dtype=np.float64)
    rng = np.random.default_rng([config.seed, 1])
    starts = config.starts
    runs = np.repeat(pbs, starts, axis=0)
    contexts, inputs = sample_starts(model, len(runs), config, rng)
    unsafe_runs = np.zeros(len(runs), bool)
    early_runs = np.zeros(len(runs), bool)
    unsettled_runs = np.zeros(len(runs), bool)
    kind_runs = np.zeros((len(runs), 4), bool)
    skip = config.transient
    for first in range(0, len(runs), config.batch):
        last = min(first + config.batch, len(runs))
        motor = generate_from(
            model, runs[first:last], contexts[first:last], inputs[first:last], config.steps
        )
        for i in range(last - first):
            sequence = motor[:, i]
            report = checker.check(sequence[skip:], previous=sequence[skip - 1] if skip else None)
            k = first + i
            unsafe_runs[k] = bool(report.unsafe.any())
            unsettled_runs[k] = bool(report.kinds[:, 3].any())
            kind_runs[k] = report.kinds.any(axis=0)
            if skip and not unsafe_runs[k]:
                early_runs[k] = bool(checker.check(sequence[: skip + 1]).unsafe.any())
            if progress is not None and (k + 1) % starts == 0:
                progress((k + 1) // starts, len(pbs))
    share = unsafe_runs.reshape(-1, starts).mean(axis=1)
    unsafe = share >= config.unsafe_share - 1e-9
    per_pb = np.asarray(kind_runs.reshape(-1, starts, 4).any(axis=1), bool)
    counts = {
        kind: int(per_pb[:, j].sum())
        for j, kind in enumerate(("collision", "speed", "limit", "unsettled"))
    }
    counts["transient_only"] = int(early_runs.reshape(-1, starts).any(axis=1).sum())
    counts["unsafe"] = int(unsafe.sum())
    return Experience(
        pbs,
        unsafe,
        share,
        np.asarray(unsettled_runs.reshape(-1, starts).any(axis=1), bool),
        np.array(["explored"] * len(pbs)),
        counts,
    )


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
        unsafe.astype(np.float64),
        np.zeros(len(pbs), bool),
        np.array(["visited"] * len(pbs)),
        {"visited_unsafe": int(unsafe.sum())},
    )
