"""The synthetic user: the four movement patterns of the paper as 3-D hand trajectories.

The user kneels facing the robot about 1 m in front of it. Positions are in the robot frame
(``x`` forward from the robot towards the user, ``y`` to the robot's left, ``z`` up; metres).
The user's LEFT hand (index 0) is on the robot's right, at negative ``y``.

Each pattern moves the two hands in the plane the robot's camera looks at (``y``, ``z``), about
their centres, with a phase ``theta`` that advances ``2 pi / period`` per step:

=====  =====================  ===================================================================
name   alias                  hands (offsets in the robot camera's view: Y to the right, Z up)
=====  =====================  ===================================================================
1      horizontal-opposite    horizontal swing, opposite phase: the hands move apart and together
                              (LHY and RHY anti-correlated, no vertical motion)
2      vertical-in-phase      vertical swing, in phase: both hands up and down together
3      rotation-opposite      both hands circle counter-clockwise (as the robot sees them), half a
                              cycle apart, like hands on a steering wheel
4      rotation-in-phase      both hands circle counter-clockwise together, like wiping a window
=====  =====================  ===================================================================

Beyond the paper's four, the user knows more movements (:data:`MOVEMENTS`): new cyclic shapes
(:data:`NEW_SHAPES`) to test what a robot does with a structured movement it never learned,
and unstructured movement (:data:`UNSTRUCTURED`) to test that it tells such a movement from
noise:

============  ===================================================================================
name          hands
============  ===================================================================================
one-arm       the user's left hand swings up and down; the right hand stays at its centre
asymmetric    the left hand swings sideways while the right hand swings up and down
figure-eight  both hands trace a figure-eight (sideways once, up and down twice a cycle), mirrored
diagonal      both hands swing along the same diagonal (up-right to down-left), in phase
random-walk   each hand wanders in the view plane as a bounded random walk (no cycle)
jerky         each hand jumps to a random target every few steps and holds it (no cycle)
============  ===================================================================================

``direction=-1`` turns the circles clockwise. "Phase" is that of each view-plane coordinate:
in phase means LHY follows RHY and LHZ follows RHZ; opposite phase means they mirror each other.

Human imperfection (:class:`Imperfection`): the period changes from cycle to cycle, so does the
size of the movement, the hands' centres drift slowly, and the measurement of the 3-D hand
positions is noisy. All randomness comes from a seeded ``numpy.random.Generator``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rnnpb.errors import ConfigError

PATTERNS: tuple[str, ...] = ("1", "2", "3", "4")
PATTERN_ALIASES: dict[str, str] = {
    "horizontal-opposite": "1",
    "vertical-in-phase": "2",
    "rotation-opposite": "3",
    "rotation-in-phase": "4",
}
PATTERN_DESCRIPTIONS: dict[str, str] = {
    "1": "horizontal swing, opposite phase",
    "2": "vertical swing, in phase",
    "3": "rotation, opposite phase",
    "4": "rotation, in phase",
}
NEW_SHAPES: tuple[str, ...] = ("one-arm", "asymmetric", "figure-eight", "diagonal")
"""Cyclic movements beyond the paper's four (none of them is in a learning set)."""
UNSTRUCTURED: tuple[str, ...] = ("random-walk", "jerky")
"""Movements without repeating structure."""
SHAPES: tuple[str, ...] = PATTERNS + NEW_SHAPES
"""Every cyclic movement the user can perform."""
MOVEMENTS: tuple[str, ...] = SHAPES + UNSTRUCTURED
"""Every movement the user can perform (a pause is none of them)."""
MOVEMENT_DESCRIPTIONS: dict[str, str] = {
    **PATTERN_DESCRIPTIONS,
    "one-arm": "one arm only: the left hand swings up and down",
    "asymmetric": "asymmetric arms: left hand sideways, right hand up and down",
    "figure-eight": "figure-eight, mirrored hands",
    "diagonal": "diagonal swing, in phase",
    "random-walk": "random walk of both hands (unstructured)",
    "jerky": "jerky random targets (unstructured)",
}
PAUSE = "pause"


def resolve_pattern(name: str) -> str:
    """A movement name or alias → its name: ``"1"`` … ``"4"`` for the paper's patterns
    (aliases such as ``horizontal-opposite`` allowed), else one of :data:`NEW_SHAPES` or
    :data:`UNSTRUCTURED`."""
    key = str(name).strip().lower()
    if key in MOVEMENTS:
        return key
    if key in PATTERN_ALIASES:
        return PATTERN_ALIASES[key]
    known = ", ".join([*PATTERNS, *PATTERN_ALIASES, *NEW_SHAPES, *UNSTRUCTURED])
    raise ConfigError(f"unknown movement pattern {name!r} (known: {known})")


@dataclass(frozen=True)
class UserBody:
    """Where the user is and where the hands move about (robot frame, metres).

    Attributes
    ----------
    distance : float
        ``x`` of the user's shoulders (the user faces the robot, about 1 m away).
    shoulder_height, shoulder_half_width : float
        The user's shoulders are at ``(distance, -+shoulder_half_width, shoulder_height)``
        (left shoulder at negative ``y``). Kneeling adult: about 0.95 m high.
    arm_reach : float
        Shoulder to hand centre of the outstretched arm.
    hand_depth : float
        ``x`` of the plane the hands move in (the arms reach forward towards the robot).
    hand_height : float
        ``z`` of the centres the hands move about.
    hand_half_spacing : float
        The centres are at ``y = -+hand_half_spacing`` (left hand negative).
    """

    distance: float = 1.0
    shoulder_height: float = 0.95
    shoulder_half_width: float = 0.19
    arm_reach: float = 0.62
    hand_depth: float = 0.68
    hand_height: float = 0.80
    hand_half_spacing: float = 0.22

    def __post_init__(self) -> None:
        if not 0.3 <= self.distance <= 3.0:
            raise ConfigError(f"user distance must be in [0.3, 3] m, got {self.distance}")
        if not 0.1 <= self.hand_depth < self.distance:
            raise ConfigError(
                f"user hand_depth must be in [0.1, distance) m, got {self.hand_depth}"
            )
        if self.arm_reach <= 0 or self.shoulder_half_width <= 0 or self.hand_half_spacing <= 0:
            raise ConfigError("user arm_reach, shoulder_half_width, hand_half_spacing must be > 0")

    @property
    def shoulders(self) -> np.ndarray:
        """Shoulder centres (left, right), shape (2, 3)."""
        return np.array(
            [
                [self.distance, -self.shoulder_half_width, self.shoulder_height],
                [self.distance, self.shoulder_half_width, self.shoulder_height],
            ]
        )

    @property
    def hand_centres(self) -> np.ndarray:
        """Centres the hands move about (left, right), shape (2, 3)."""
        return np.array(
            [
                [self.hand_depth, -self.hand_half_spacing, self.hand_height],
                [self.hand_depth, self.hand_half_spacing, self.hand_height],
            ]
        )


@dataclass(frozen=True)
class Imperfection:
    """How far a human demonstration is from a perfect cycle.

    Attributes
    ----------
    sensor_noise : float
        Standard deviation (m) of the measurement noise on each hand coordinate, every step.
    drift : float
        Standard deviation (m) of the slow wandering of the hands' centres.
    drift_steps : float
        Correlation time (steps) of that drift.
    period_jitter : float
        Relative standard deviation of the period from one cycle to the next.
    amplitude_jitter : float
        Relative standard deviation of the movement's size from one cycle to the next.
    shape_jitter : float
        Relative standard deviation of each hand's own size change per cycle (the two hands
        are not exact copies of each other).
    """

    sensor_noise: float = 0.004
    drift: float = 0.012
    drift_steps: float = 25.0
    period_jitter: float = 0.06
    amplitude_jitter: float = 0.08
    shape_jitter: float = 0.05

    def __post_init__(self) -> None:
        for name in ("sensor_noise", "drift", "period_jitter", "amplitude_jitter", "shape_jitter"):
            if getattr(self, name) < 0:
                raise ConfigError(f"imperfection {name} must be >= 0, got {getattr(self, name)}")
        if self.period_jitter >= 0.5:
            raise ConfigError("imperfection period_jitter must be < 0.5")
        if self.drift_steps <= 0:
            raise ConfigError("imperfection drift_steps must be > 0")

    @classmethod
    def none(cls) -> Imperfection:
        """A perfect, noise-free, exactly periodic user."""
        return cls(0.0, 0.0, 25.0, 0.0, 0.0, 0.0)


@dataclass(frozen=True)
class PatternConfig:
    """The movement patterns' parameters.

    Attributes
    ----------
    period_steps : float
        Steps per cycle (12 steps of 0.4 s: a 4.8 s cycle, close to the paper's integration
        length of 20 steps, as the paper asks).
    dt : float
        Seconds per step (paper: 0.4 s).
    horizontal_amplitude, vertical_amplitude : float
        Half the extent (m) of the horizontal (pattern 1) and vertical (pattern 2) swings.
    rotation_radius : float
        Radius (m) of the circles of patterns 3 and 4.
    direction : int
        +1: circles counter-clockwise as the robot sees them; -1: clockwise.
    body : UserBody
    imperfection : Imperfection
    """

    period_steps: float = 12.0
    dt: float = 0.4
    horizontal_amplitude: float = 0.12
    vertical_amplitude: float = 0.12
    rotation_radius: float = 0.10
    direction: int = 1
    body: UserBody = field(default_factory=UserBody)
    imperfection: Imperfection = field(default_factory=Imperfection)

    def __post_init__(self) -> None:
        if not 3.0 <= self.period_steps <= 200.0:
            raise ConfigError(f"period_steps must be in [3, 200], got {self.period_steps}")
        if self.dt <= 0:
            raise ConfigError(f"dt must be > 0, got {self.dt}")
        for name in ("horizontal_amplitude", "vertical_amplitude", "rotation_radius"):
            value = getattr(self, name)
            if not 0.0 < value <= 0.3:
                raise ConfigError(f"{name} must be in (0, 0.3] m, got {value}")
        if self.direction not in (1, -1):
            raise ConfigError(f"direction must be +1 or -1, got {self.direction}")


def pattern_offsets(pattern: str, theta: np.ndarray, config: PatternConfig) -> np.ndarray:
    """Hand offsets from their centres for phases ``theta`` (n,), shape (n, 2, 3).

    The offsets of the ideal cyclic movement (one of :data:`SHAPES`), without imperfection.
    ``theta`` in radians.
    """
    pattern = resolve_pattern(pattern)
    if pattern in UNSTRUCTURED:
        raise ConfigError(f"movement {pattern!r} has no cycle: it has no offsets per phase")
    theta = np.asarray(theta, dtype=np.float64)
    out = np.zeros((*theta.shape, 2, 3))
    a_h, a_v = config.horizontal_amplitude, config.vertical_amplitude
    # View-plane Y grows to the robot's right, i.e. along -y of the robot frame.
    if pattern == "one-arm":
        out[..., 0, 2] = a_v * np.sin(theta)
    elif pattern == "asymmetric":
        out[..., 0, 1] = -a_h * np.sin(theta)
        out[..., 1, 2] = a_v * np.sin(theta)
    elif pattern == "figure-eight":
        sideways = a_h * np.sin(theta)
        out[..., 0, 1] = sideways
        out[..., 1, 1] = -sideways
        out[..., 0, 2] = out[..., 1, 2] = 0.6 * a_v * np.sin(2 * theta)
    elif pattern == "diagonal":
        swing = np.sin(theta) / np.sqrt(2.0)
        out[..., 0, 1] = out[..., 1, 1] = -a_h * swing  # view Y to the right
        out[..., 0, 2] = out[..., 1, 2] = a_v * swing  # and up
    elif pattern == "1":
        swing = config.horizontal_amplitude * np.sin(theta)
        out[..., 0, 1] = swing
        out[..., 1, 1] = -swing
    elif pattern == "2":
        swing = config.vertical_amplitude * np.sin(theta)
        out[..., 0, 2] = swing
        out[..., 1, 2] = swing
    else:
        r, s = config.rotation_radius, config.direction
        second = theta + np.pi if pattern == "3" else theta
        for hand, angle in ((0, theta), (1, second)):
            out[..., hand, 1] = -r * np.cos(angle)  # view Y = r cos
            out[..., hand, 2] = s * r * np.sin(angle)  # view Z = r sin (CCW for s=+1)
    return out


def _smooth_noise(rng: np.random.Generator, n: int, steps: float, shape: tuple) -> np.ndarray:
    """Unit-variance noise low-pass filtered with correlation time ``steps``, (n, *shape)."""
    a = np.exp(-1.0 / steps)
    white = rng.standard_normal((n, *shape))
    out = np.empty_like(white)
    out[0] = white[0]
    for t in range(1, n):
        out[t] = a * out[t - 1] + np.sqrt(1 - a * a) * white[t]
    return out


def unstructured_offsets(
    movement: str, n_steps: int, config: PatternConfig, rng: np.random.Generator
) -> np.ndarray:
    """Hand offsets of an unstructured movement (one of :data:`UNSTRUCTURED`), shape
    (n_steps, 2, 3), within the pattern amplitudes about the hands' centres.

    ``random-walk``: each view-plane coordinate takes steps of a fifth of the amplitude
    (normal), reflected at the amplitude; ``jerky``: each hand holds a random target for 2–5
    steps (uniform in the amplitude box), then jumps to the next within one step.
    """
    movement = resolve_pattern(movement)
    box = np.array([config.horizontal_amplitude, config.vertical_amplitude])
    out = np.zeros((n_steps, 2, 3))
    if movement == "random-walk":
        position = rng.uniform(-0.5, 0.5, (2, 2)) * box
        for t in range(n_steps):
            position = position + 0.2 * box * rng.standard_normal((2, 2))
            # Reflect at the box's walls so the walk stays in view.
            position = np.where(position > box, 2 * box - position, position)
            position = np.where(position < -box, -2 * box - position, position)
            out[t, :, 1:] = np.clip(position, -box, box)
    elif movement == "jerky":
        for hand in range(2):
            t = 0
            while t < n_steps:
                hold = int(rng.integers(2, 6))
                out[t : t + hold, hand, 1:] = rng.uniform(-1.0, 1.0, 2) * box
                t += hold
    else:
        raise ConfigError(
            f"movement {movement!r} is not unstructured (unstructured: {', '.join(UNSTRUCTURED)})"
        )
    return out


@dataclass(frozen=True)
class HandMotion:
    """A performed hand trajectory with its ground truth.

    Attributes
    ----------
    hands : array, shape (n_steps, 2, 3)
        The hands as the user moved them (robot frame, metres), without measurement noise.
    measured : array, shape (n_steps, 2, 3)
        The hands as measured (with sensor noise): what the sensory and motor data come from.
    labels : tuple of str, length n_steps
        Pattern name per step, or ``"pause"``.
    phase : array, shape (n_steps,)
        The movement phase (radians, unwrapped) per step.
    """

    hands: np.ndarray
    measured: np.ndarray
    labels: tuple[str, ...]
    phase: np.ndarray


def perform(
    segments: list[tuple[str, int]],
    config: PatternConfig,
    rng: np.random.Generator,
    phase: float | None = None,
    transition_steps: int = 2,
) -> HandMotion:
    """The user performs patterns and pauses one after another.

    Parameters
    ----------
    segments : list of (label, n_steps)
        Movement names (:data:`MOVEMENTS`, or aliases) or ``"pause"`` (hands held still where
        they are), in order.
    config : PatternConfig
    rng : numpy.random.Generator
    phase : float, optional
        Phase at the first step (radians); drawn uniformly when None.
    transition_steps : int
        Steps over which the hands blend from one pattern into the next (a person does not
        jump); the label switches at the segment boundary.
    """
    labels: list[str] = []
    for label, n in segments:
        if n < 0:
            raise ConfigError(f"segment {label!r} has a negative length {n}")
        labels.extend([PAUSE if label == PAUSE else resolve_pattern(label)] * int(n))
    n_steps = len(labels)
    if n_steps < 1:
        raise ConfigError("a performance needs at least one step")
    imp = config.imperfection
    theta0 = rng.uniform(0.0, 2 * np.pi) if phase is None else float(phase)

    # Period and size change from cycle to cycle: draw one value per (possible) cycle and
    # interpolate smoothly in phase, so each cycle differs from the last.
    n_cycles = int(np.ceil(n_steps / (0.5 * config.period_steps))) + 3  # periods >= P / 2
    period_per_cycle = config.period_steps * np.clip(
        1 + imp.period_jitter * rng.standard_normal(n_cycles), 0.5, 1.5
    )
    size_per_cycle = np.clip(1 + imp.amplitude_jitter * rng.standard_normal(n_cycles), 0.5, 1.5)
    hand_size_per_cycle = np.clip(
        1 + imp.shape_jitter * rng.standard_normal((n_cycles, 2)), 0.5, 1.5
    )
    drift = imp.drift * _smooth_noise(rng, n_steps, imp.drift_steps, (2, 3))
    drift[..., 0] *= 0.5  # people wander less in depth than across the view
    noise = imp.sensor_noise * rng.standard_normal((n_steps, 2, 3))
    # Drawn after everything else, and only when needed, so that a performance of the paper's
    # patterns draws the same numbers as before these movements existed.
    tracks = {m: unstructured_offsets(m, n_steps, config, rng) for m in UNSTRUCTURED if m in labels}

    def per_cycle(values: np.ndarray, theta: float) -> np.ndarray:
        c = (theta - theta0) / (2 * np.pi)
        i = int(np.clip(np.floor(c), 0, len(values) - 2))
        f = float(np.clip(c - i, 0.0, 1.0))
        w = 0.5 - 0.5 * np.cos(np.pi * f)
        return (1 - w) * values[i] + w * values[i + 1]

    thetas = np.empty(n_steps)
    offsets = np.zeros((n_steps, 2, 3))
    theta = theta0
    previous = np.zeros((2, 3))
    blend_from: np.ndarray | None = None
    since_switch = transition_steps
    for t, label in enumerate(labels):
        if t > 0 and label != labels[t - 1]:
            blend_from, since_switch = previous.copy(), 0
        thetas[t] = theta
        if label == PAUSE:
            current = previous
        elif label in tracks:
            current = tracks[label][t]
            if blend_from is not None and since_switch < transition_steps:
                w = (since_switch + 1) / (transition_steps + 1)
                current = (1 - w) * blend_from + w * current
        else:
            size = per_cycle(size_per_cycle, theta) * per_cycle(hand_size_per_cycle, theta)
            current = pattern_offsets(label, np.array(theta), config) * size[:, None]
            if blend_from is not None and since_switch < transition_steps:
                w = (since_switch + 1) / (transition_steps + 1)
                current = (1 - w) * blend_from + w * current
            theta += 2 * np.pi / per_cycle(period_per_cycle, theta)
        offsets[t] = current
        previous = current
        since_switch += 1
    hands = config.body.hand_centres + offsets + drift
    return HandMotion(hands=hands, measured=hands + noise, labels=tuple(labels), phase=thetas)
