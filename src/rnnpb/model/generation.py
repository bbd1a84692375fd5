"""Generation from a PB alone: the network in closed loop (Ito & Tani 2004, section 3.3).

All outputs are fed back as inputs; nothing comes from outside. For a learned pattern's PB the
network falls onto that pattern's limit cycle after a transient.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.model.io import TrainedModel
from rnnpb.model.network import closed_loop


@dataclass(frozen=True)
class Generated:
    """A closed-loop run.

    Attributes
    ----------
    sensory : array, shape (n_steps, 4)
        Generated (imagined) user hands, [0, 1].
    motor : array, shape (n_steps, 8)
        Generated joint angles, radians.
    context : array, shape (n_steps, C)
        The context units, for phase-space plots.
    """

    sensory: np.ndarray
    motor: np.ndarray
    context: np.ndarray


def generate(
    model: TrainedModel,
    pb: np.ndarray,
    n_steps: int,
    initial_context: np.ndarray | None = None,
    first_input: np.ndarray | None = None,
) -> Generated:
    """Run the network in closed loop with a constant PB for ``n_steps`` steps.

    Parameters
    ----------
    pb : array, shape (P,)
        The parametric bias, each value in [0, 1].
    initial_context : array, shape (C,), optional
        Default: the mean of the learned initial contexts.
    first_input : array, shape (I,), optional
        The first (normalized) sensory-motor input. Default: all 0.5.
    """
    net = model.network
    pb = np.asarray(pb, dtype=np.float64).reshape(-1)
    if pb.shape != (net.pb_size,):
        raise ConfigError(f"PB must have {net.pb_size} values, got {pb.shape[0]}")
    if not np.all(np.isfinite(pb)) or np.any(pb < 0) or np.any(pb > 1):
        raise ConfigError(f"PB values must be in [0, 1], got {pb.tolist()}")
    if n_steps < 1:
        raise ConfigError(f"number of steps must be >= 1, got {n_steps}")
    context = model.mean_initial_context if initial_context is None else initial_context
    x0 = np.full(net.io_size, 0.5) if first_input is None else np.asarray(first_input)
    pbs = jnp.broadcast_to(jnp.asarray(pb, jnp.float32), (n_steps, net.pb_size))
    predictions, contexts = _closed_loop(
        model.params, jnp.asarray(context, jnp.float32), jnp.asarray(x0, jnp.float32), pbs
    )
    raw = model.denormalize(np.asarray(predictions, dtype=np.float64))
    s = net.sensory_size
    return Generated(
        sensory=raw[:, :s], motor=raw[:, s:], context=np.asarray(contexts, dtype=np.float64)
    )


_closed_loop = jax.jit(closed_loop)
