"""Learning, driven: :func:`train` runs the compiled chunks of :mod:`rnnpb.model.learning`
until the iterations are done, and returns the trained model.

Unlike the rest of :mod:`rnnpb.model`, this driver reads a clock (the progress it reports and
the seconds the model records) and writes files: a checkpoint of the whole training state
every ``checkpoint_every`` iterations, atomically, so that an interrupted run resumes
(:func:`save_checkpoint`, :func:`load_checkpoint`). A sequence's learned PB is the mean of its
PB profile; a pattern's PB is the mean over its sequences
(:class:`rnnpb.model.io.TrainedModel`).
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable
from collections.abc import Sequence as SequenceABC
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from rnnpb import __version__
from rnnpb.errors import ConfigError, ModelFileError
from rnnpb.model.archive import MAX_MEMBERS, check_numeric, load_archive, save_archive
from rnnpb.model.io import TrainedModel
from rnnpb.model.learning import (
    TrainConfig,
    TrainingData,
    TrainState,
    WarmStart,
    chunk_runner,
    init_state,
    per_output_mse,
    prepare_data,
    preset_record,
    seeds_chunk_runner,
)
from rnnpb.model.network import NetworkConfig
from rnnpb.sequences import Sequence

CHECKPOINT_FORMAT = "rnnpb-checkpoint"
CHECKPOINT_FORMAT_VERSION = 1


@dataclass
class TrainingProgress:
    """Passed to the progress callback after each chunk of iterations."""

    iteration: int
    total: int
    mse: float
    elapsed_s: float


def train(
    sequences: SequenceABC[Sequence],
    joint_limits: np.ndarray,
    network: NetworkConfig | None = None,
    config: TrainConfig | None = None,
    *,
    progress: bool | Callable[[TrainingProgress], None] = False,
    checkpoint_path: str | os.PathLike[str] | None = None,
    resume: bool = False,
    warm_start: WarmStart | None = None,
) -> TrainedModel:
    """Learn the sequences; return the trained model.

    Parameters
    ----------
    sequences : list of Sequence
        Training demonstrations (sensory in [0, 1], motor in radians within ``joint_limits``).
    joint_limits : array, shape (8, 2)
        Lower and upper limit of each joint (radians), for the motor normalization.
    progress : bool or callable
        True shows a progress bar; a callable receives :class:`TrainingProgress` per chunk.
    checkpoint_path : path, optional
        Where to write a checkpoint every ``config.checkpoint_every`` iterations (atomically).
    resume : bool
        Continue from ``checkpoint_path`` if it exists (same data, config and warm start
        required).
    warm_start : WarmStart, optional
        Start from these weights, initial contexts and PBs instead of random weights
        (incremental learning, :mod:`rnnpb.model.consolidation`), holding the PBs it names and
        teaching the sequences it names its own function.
    """
    network = network or NetworkConfig()
    config = config or TrainConfig()
    data = prepare_data(sequences, joint_limits)
    if data.inputs.shape[-1] != network.io_size:
        raise ConfigError(
            f"sequences have {data.inputs.shape[-1]} values per step but the "
            f"network expects {network.io_size}"
        )
    state = init_state(data, network, config, warm_start)
    start_name = warm_start.identity if warm_start is not None else None
    if resume and checkpoint_path is not None and os.path.exists(checkpoint_path):
        state = load_checkpoint(checkpoint_path, state, data, network, config, start_name)
    run_chunk = chunk_runner(config)
    inputs = jnp.asarray(data.inputs, jnp.float32)
    valid = jnp.asarray(data.valid)
    every_pb_learns = np.ones(data.valid.shape[0], dtype=bool)
    teacher = warm_start.teacher() if warm_start is not None else None

    bar = None
    if progress is True:
        from tqdm.auto import tqdm

        bar = tqdm(
            total=config.iterations,
            initial=int(state.iteration),
            unit="it",
            desc="training",
            dynamic_ncols=True,
        )
    start = time.perf_counter()
    done = int(state.iteration)
    history: list[tuple[int, float]] = []
    if done == 0:
        history.append(
            (
                0,
                float(
                    jnp.mean(
                        per_output_mse(
                            (state.params, state.initial_context_logit), state.rho, inputs, valid
                        )
                    )
                ),
            )
        )
    try:
        while done < config.iterations:
            n = _chunk(config, done)
            pb_learning = every_pb_learns
            if warm_start is not None:
                pb_learning = warm_start.pb_learning(done)
                release = warm_start.next_release(done)
                if release is not None:  # a chunk ends where the held PBs are let go
                    n = min(n, release - done)
            state = run_chunk(
                state, inputs, valid, jnp.asarray(n, jnp.int32), jnp.asarray(pb_learning), teacher
            )
            done += n
            mse = float(
                jnp.mean(
                    per_output_mse(
                        (state.params, state.initial_context_logit), state.rho, inputs, valid
                    )
                )
            )
            if not math.isfinite(mse):
                raise ConfigError(
                    f"training diverged at iteration {done} (error is {mse}); "
                    "lower the learning rate"
                )
            history.append((done, mse))
            # The checkpoint first: a progress callback may end the run (a Ctrl-C taken at
            # this safe point), and the chunk just learned is then kept.
            if checkpoint_path is not None and (
                done % config.checkpoint_every == 0 or done == config.iterations
            ):
                save_checkpoint(checkpoint_path, state, data, network, config, start_name)
            if bar is not None:
                bar.update(n)
                bar.set_postfix(mse=f"{mse:.2e}")
            elif callable(progress):
                progress(
                    TrainingProgress(done, config.iterations, mse, time.perf_counter() - start)
                )
    finally:
        if bar is not None:
            bar.close()
    elapsed = time.perf_counter() - start
    code = _code(run_chunk, state, data, warm_start.teacher() if warm_start else None)
    return _finish(state, data, network, config, history, elapsed, code)


def train_seeds(
    sequences: SequenceABC[Sequence],
    joint_limits: np.ndarray,
    seeds: SequenceABC[int],
    network: NetworkConfig | None = None,
    config: TrainConfig | None = None,
    *,
    progress: Callable[[TrainingProgress], None] | None = None,
) -> list[TrainedModel]:
    """Learn the sequences once per seed; return the models in the order of ``seeds``.

    Each model is the one :func:`train` learns with ``config``'s seed replaced. The native
    iterations (:mod:`rnnpb.model.native_learning`) run the seeds one after the other, each
    the same numbers as :func:`train`'s; the JAX chunk runs them in one compiled call, for
    less CPU than a call per seed (one network's products are too small to keep the processor
    busy, a batch of networks fills it): the same numbers with the paper's gradient descent,
    the same to rounding with Adam, whose batched update rounds differently. Each model records
    the run's wall time as its ``seconds``. No checkpoints or warm starts: those are
    :func:`train`'s. ``progress`` receives the largest error over the seeds after each chunk.
    """
    network = network or NetworkConfig()
    config = config or TrainConfig()
    seeds = [int(s) for s in seeds]
    if not seeds or len(set(seeds)) != len(seeds):
        raise ConfigError(f"train_seeds needs one or more distinct seeds, got {seeds}")
    data = prepare_data(sequences, joint_limits)
    if data.inputs.shape[-1] != network.io_size:
        raise ConfigError(
            f"sequences have {data.inputs.shape[-1]} values per step but the "
            f"network expects {network.io_size}"
        )
    configs = [replace(config, seed=seed) for seed in seeds]
    states = [init_state(data, network, c, None) for c in configs]
    state = jax.tree_util.tree_map(lambda *leaves: jnp.stack(leaves), *states)
    run_chunk = seeds_chunk_runner(config)
    inputs = jnp.asarray(data.inputs, jnp.float32)
    valid = jnp.asarray(data.valid)
    every_pb_learns = jnp.ones(data.valid.shape[0], dtype=bool)
    errors = jax.vmap(per_output_mse, in_axes=((0, 0), 0, None, None))

    def mse_per_seed(state: TrainState) -> np.ndarray:
        per_output = errors((state.params, state.initial_context_logit), state.rho, inputs, valid)
        return np.asarray(jnp.mean(per_output, axis=1), dtype=np.float64)

    start = time.perf_counter()
    done = 0
    histories: list[list[tuple[int, float]]] = [[(0, float(m))] for m in mse_per_seed(state)]
    while done < config.iterations:
        n = _chunk(config, done)  # the chunks :func:`train` runs: the same history points
        state = run_chunk(state, inputs, valid, jnp.asarray(n, jnp.int32), every_pb_learns)
        done += n
        mse = mse_per_seed(state)
        diverged = [seed for seed, m in zip(seeds, mse, strict=True) if not math.isfinite(m)]
        if diverged:
            raise ConfigError(
                f"training diverged at iteration {done} for seed(s) "
                f"{', '.join(map(str, diverged))}; lower the learning rate"
            )
        for history, m in zip(histories, mse, strict=True):
            history.append((done, float(m)))
        if progress is not None:
            progress(
                TrainingProgress(
                    done, config.iterations, float(mse.max()), time.perf_counter() - start
                )
            )
    elapsed = time.perf_counter() - start
    code = _code(chunk_runner(config), states[0], data, None)
    return [
        _finish(
            jax.tree_util.tree_map(lambda leaf, i=i: leaf[i], state),
            data,
            network,
            configs[i],
            histories[i],
            elapsed,
            code,
        )
        for i in range(len(seeds))
    ]


def _chunk(config: TrainConfig, done: int) -> int:
    """How many iterations the next compiled chunk runs after ``done``: a chunk at most,
    ending at the next checkpoint and at the last iteration."""
    next_checkpoint = (done // config.checkpoint_every + 1) * config.checkpoint_every
    return min(config.chunk_iterations, config.iterations - done, next_checkpoint - done)


def _code(run_chunk: object, state: TrainState, data: TrainingData, teacher: object) -> str:
    """Which code ran the iterations: the native kernel (with llvmlite's version) or JAX's
    compiled chunk; models from the two agree to float32 rounding, not bit for bit."""
    from rnnpb.model import native_learning

    if isinstance(run_chunk, native_learning.NativeChunk) and run_chunk.runs_natively(
        state, data.valid, teacher
    ):
        return native_learning.code_version()
    return "jax"


def _finish(
    state: TrainState,
    data: TrainingData,
    network: NetworkConfig,
    config: TrainConfig,
    history: list[tuple[int, float]],
    elapsed: float,
    code: str,
) -> TrainedModel:
    inputs = jnp.asarray(data.inputs, jnp.float32)
    valid = jnp.asarray(data.valid)
    per_output = np.asarray(
        per_output_mse((state.params, state.initial_context_logit), state.rho, inputs, valid),
        dtype=np.float64,
    )
    pbs = np.asarray(jax.nn.sigmoid(state.rho), dtype=np.float64)
    weights = data.valid[..., None].astype(np.float64)
    sequence_pb = (pbs * weights).sum(axis=1) / weights.sum(axis=1)
    meta = {
        "train_config": config.to_dict(),
        "preset": preset_record(config),
        "training": {
            "iterations": int(state.iteration),
            "mse_per_output": per_output.tolist(),
            "mse_max": float(per_output.max()),
            "mse_mean": float(per_output.mean()),
            "rms_per_output": np.sqrt(per_output).tolist(),
            "history": history,
            "seconds": elapsed,
            "code": code,
            "data_fingerprint": data.fingerprint,
        },
        "rnnpb_version": __version__,
        "jax_version": jax.__version__,
    }
    # The hands as taught (normalized sensory inputs), NaN on the padding after each end:
    # step 0 is real, and step t + 1 where step t predicts a real step.
    real = np.concatenate([np.ones((len(data.valid), 1), bool), data.valid], axis=1)
    hands = np.clip(data.inputs[..., : network.sensory_size], 0.0, 1.0)
    taught = np.where(real[..., None], hands, np.nan)
    return TrainedModel(
        network=network,
        params=state.params,
        lower=data.lower,
        upper=data.upper,
        sequence_pb=sequence_pb,
        sequence_patterns=data.patterns,
        initial_context=np.asarray(jax.nn.sigmoid(state.initial_context_logit), dtype=np.float64),
        meta=meta,
        taught_sensory=taught.astype(np.float64),
    )


def save_checkpoint(
    path: str | os.PathLike[str],
    state: TrainState,
    data: TrainingData,
    network: NetworkConfig,
    config: TrainConfig,
    warm_start: str | None = None,
) -> None:
    """Write the whole training state atomically, to continue with ``resume=True``;
    ``warm_start`` names the start it continued from (:attr:`WarmStart.identity`)."""
    leaves = jax.tree_util.tree_leaves(state)
    arrays = {f"state/{i:04d}": np.asarray(leaf) for i, leaf in enumerate(leaves)}
    meta = {
        "format": CHECKPOINT_FORMAT,
        "format_version": CHECKPOINT_FORMAT_VERSION,
        "rnnpb_version": __version__,
        "network": asdict(network),
        "train_config": config.to_dict(),
        "data_fingerprint": data.fingerprint,
        "iteration": int(state.iteration),
        "n_leaves": len(leaves),
    }
    if warm_start is not None:
        meta["warm_start"] = warm_start
    save_archive(path, meta, arrays)


def _checkpoint_members(path: Path, meta: dict[str, Any]) -> dict[str, tuple[int, ...] | None]:
    """The arrays a checkpoint archive holds (:data:`rnnpb.model.archive.Members`): meta.json
    and the leaves of the training state as state/0000 …; their shapes depend on the training
    data, which the checkpoint does not record, so only names, count and the total size are
    bounded here."""
    n_leaves = meta.get("n_leaves")
    if (
        not isinstance(n_leaves, int)
        or isinstance(n_leaves, bool)
        or not (0 < n_leaves < MAX_MEMBERS)
    ):
        raise ModelFileError(f"{path}: checkpoint meta.json has no valid 'n_leaves' ({n_leaves!r})")
    return {f"state/{i:04d}": None for i in range(n_leaves)}


def load_checkpoint(
    path: str | os.PathLike[str],
    template: TrainState,
    data: TrainingData,
    network: NetworkConfig,
    config: TrainConfig,
    warm_start: str | None = None,
) -> TrainState:
    """Read a checkpoint into the structure of ``template``; it must match data, config and
    warm start."""
    meta, arrays = load_archive(
        path, CHECKPOINT_FORMAT, CHECKPOINT_FORMAT_VERSION, _checkpoint_members
    )
    if meta.get("data_fingerprint") != data.fingerprint:
        raise ModelFileError(f"{path}: checkpoint was made with other training data")
    if meta.get("warm_start") != warm_start:
        raise ModelFileError(f"{path}: checkpoint was made from another starting model or method")
    if meta.get("network") != asdict(network):
        raise ModelFileError(f"{path}: checkpoint was made with another network config")
    saved = meta.get("train_config")
    if not isinstance(saved, dict):
        raise ModelFileError(f"{path}: checkpoint has no training config")
    saved = dict(saved)
    current = config.to_dict()
    for key in ("iterations", "chunk_iterations", "checkpoint_every"):
        saved.pop(key, None)
        current.pop(key, None)
    if saved != current:
        raise ModelFileError(f"{path}: checkpoint was made with another training config")
    leaves, treedef = jax.tree_util.tree_flatten(template)
    if meta.get("n_leaves") != len(leaves):
        raise ModelFileError(f"{path}: checkpoint does not match this training state")
    restored = []
    for i, leaf in enumerate(leaves):
        value = arrays.get(f"state/{i:04d}")
        if value is None or value.shape != np.shape(leaf):
            raise ModelFileError(f"{path}: checkpoint array {i} is missing or has the wrong shape")
        check_numeric(Path(path), f"state/{i:04d}", value)
        restored.append(jnp.asarray(value, dtype=jnp.asarray(leaf).dtype))
    return jax.tree_util.tree_unflatten(treedef, restored)
