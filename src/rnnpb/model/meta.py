"""The meta-level of the PB space (Ito & Tani 2004, section 4.1): a small network that maps a
PB vector to the risk that the behaviour it generates is unsafe.

"Another network is prepared which learns safe or unsafe regions in the PB space from
experience. The network can be used to prevent the PB values from coming too close to the
learned undesired regions." This module holds the pure function of that network (the barrier it
puts into eq. 1 and the projection are the compiled step's: :mod:`rnnpb.model.equations`), so
that the on-line step (:mod:`rnnpb.model.online`) can use it without knowing where its weights
came from; :mod:`rnnpb.safety` learns the weights from the robot's experience and stores them.

The network: ``risk_logit(p) = w3 · tanh(W2 tanh(W1 p + b1) + b2) + b3``; ``risk = σ(risk_logit)``.

The barrier: with ``c`` the risk level the PB should stay below, the regression adds
``barrier · softplus(risk_logit(p) − logit(c))`` per step of the window to the error of eq. 1,
so its gradient pushes ``ρ`` away from the learned unsafe region (and is ≈ 0 far from it).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from rnnpb.errors import ConfigError


class MetaParams(NamedTuple):
    """Weights of the risk network. Shapes: P PB, H hidden. JAX arrays for the JAX functions
    below, NumPy arrays for the compiled step (:func:`rnnpb.model.online.meta_arrays`)."""

    w1: jax.Array | np.ndarray  # (P, H)
    b1: jax.Array | np.ndarray  # (H,)
    w2: jax.Array | np.ndarray  # (H, H)
    b2: jax.Array | np.ndarray  # (H,)
    w3: jax.Array | np.ndarray  # (H,)
    b3: jax.Array | np.ndarray  # ()


def risk_logit(params: MetaParams, pb: jax.Array) -> jax.Array:
    """The logit of the risk of the behaviour a PB generates.

    Parameters
    ----------
    pb : array, shape (..., P)
        PB values in [0, 1].

    Returns
    -------
    array, shape (...)
    """
    hidden = jnp.tanh(pb @ params.w1 + params.b1)
    hidden = jnp.tanh(hidden @ params.w2 + params.b2)
    return hidden @ params.w3 + params.b3


# --- the meta-level on the host: regimes, steering and inhibition ------------------------------

REGIMES: tuple[str, ...] = ("following", "lost", "still", "novel", "unstructured")
"""What drives the robot's motion at a step. ``following``: the robot imitates what it sees
(a learned pattern, or no evidence yet); the others are *PB-driven* — the robot generates on
its own from its PB: ``lost`` (no hand seen), ``still`` (the hands at rest), ``novel`` (a new
movement: the paper's cases 2 and 3), ``unstructured`` (movement without repeating
structure)."""

PB_DRIVEN = frozenset(REGIMES[1:])

STEERING = ("pb_driven", "always")


def regime_of(seen: np.ndarray, novelty: str) -> str:
    """The regime of a step from which hands were seen and what recognition says."""
    if not np.any(seen):
        return "lost"
    return novelty if novelty in PB_DRIVEN else "following"


def risk_numpy(params: MetaParams, pb: np.ndarray) -> float:
    """The risk of one PB (P,) by the risk network, on the host (float64)."""
    pb = np.asarray(pb, dtype=np.float64)
    hidden = np.tanh(pb @ np.asarray(params.w1) + np.asarray(params.b1))
    hidden = np.tanh(hidden @ np.asarray(params.w2) + np.asarray(params.b2))
    logit = float(hidden @ np.asarray(params.w3) + np.asarray(params.b3))
    return float(1.0 / (1.0 + np.exp(-logit))) if logit > -700 else 0.0


class MetaLevel:
    """The meta-level's part of each on-line step (host side, for
    :class:`rnnpb.model.MirrorSystem` and its float64 twin).

    ``steering``: ``"pb_driven"`` — the guard in the regression (``OnlineConfig.
    safety_guard``) acts only where the previous step was PB-driven (:data:`PB_DRIVEN`) and
    leaves following alone; ``"always"`` — at every step. ``inhibition``: while following, a
    PB whose risk exceeds ``risk_level`` is recognised as usual but its command is not sent:
    the command before is held (recognise but suppress, paper section 4.1).
    """

    def __init__(
        self, params: MetaParams, risk_level: float, steering: str, inhibition: bool
    ) -> None:
        if steering not in STEERING:
            raise ConfigError(f"steering must be 'pb_driven' or 'always', got {steering!r}")
        self.params = MetaParams(*(np.asarray(a, dtype=np.float64) for a in params))
        self.risk_level = float(risk_level)
        self.steering = steering
        self.inhibition = bool(inhibition)
        self.reset()

    def reset(self) -> None:
        self.regime = ""
        self.sent: np.ndarray | None = None

    def steers(self) -> bool:
        """Whether the guard acts in this step's regression."""
        return self.steering == "always" or self.regime in PB_DRIVEN

    def inhibit(self, regime: str, pb: np.ndarray, motor: np.ndarray) -> tuple[np.ndarray, str]:
        """The command to send and why it was inhibited (``""``: sent as generated); keeps
        the regime for the next step's steering."""
        self.regime = regime
        why = ""
        if self.inhibition and regime == "following" and self.sent is not None:
            level = risk_numpy(self.params, pb)
            if level > self.risk_level:
                why = f"risk {level:.2f} > {self.risk_level:g} while following"
                motor = self.sent
        self.sent = np.array(motor, dtype=np.float64)
        return motor, why
