"""Shapes the demonstrator does not make: movements a person could show the robot, drawn by seed.

The demonstrator's own new shapes (:data:`rnnpb.demonstrator.NEW_SHAPES`) are four, of one
size and speed; a robot taught only those would be tested on what it was tuned on. A *free
shape* is drawn from a wider family: each hand traces a Lissajous figure in the view plane —
frequency ratios 1:1 (an ellipse or a tilted line), 1:2 and 2:1 (two-loop figures: an eight,
a lying eight) or 2:3 — of its own size (0.5 to 1.5 times the demonstrator's swing) about a
centre moved by up to 5 cm; the hands move mirrored, in step, in opposite phase, one still and
the other moving, or each its own figure; the period is the same in steps at every step time:
10 to 30 steps for a 1:1 figure (slow circles included), and for the others long enough that
their faster part turns in no fewer than 8 steps, as a person's arm does at a natural speed
(16 to 30 steps for 1:2 and 2:1, 24 to 39 for 2:3). A person's imperfection rides on it: each
cycle a little larger or smaller (±8 %) and longer or shorter (±5 %), and the camera's noise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rnnpb.demonstrator import UserBody

RATIOS = ((1, 1), (1, 2), (2, 1), (2, 3))
"""Frequency ratios (horizontal, vertical) of a hand's figure."""
COUPLINGS = ("mirrored", "in step", "opposite", "one hand", "each its own")
"""How the two hands' figures relate."""
SWING = 0.12
"""Metres: the demonstrator's swing (PatternConfig's amplitudes), the unit of a figure's size."""
PERIODS = {1: (10, 30), 2: (16, 30), 3: (24, 39)}
"""Steps per cycle, the shortest and the longest, by the figure's highest frequency."""


@dataclass(frozen=True)
class HandFigure:
    """One hand's Lissajous figure: ``ratio`` (horizontal, vertical frequency), amplitudes
    (metres), the vertical phase against the horizontal (radians) and the centre's offset
    (metres, horizontal and vertical)."""

    ratio: tuple[int, int]
    amplitude: tuple[float, float]
    phase: float
    offset: tuple[float, float]


@dataclass(frozen=True)
class FreeShape:
    """A free shape (module doc): its seed, coupling, period and each hand's figure (None:
    the hand is held still)."""

    seed: int
    coupling: str
    period: int
    left: HandFigure | None
    right: HandFigure | None

    @property
    def name(self) -> str:
        return f"free-{self.seed}"

    def describe(self) -> str:
        def hand(figure: HandFigure | None) -> str:
            if figure is None:
                return "still"
            return f"{figure.ratio[0]}:{figure.ratio[1]}"

        return (
            f"{self.name}: {self.coupling}, left {hand(self.left)}, right {hand(self.right)}, "
            f"{self.period} steps a cycle"
        )


def _figure(rng: np.random.Generator) -> HandFigure:
    ratio = RATIOS[int(rng.integers(len(RATIOS)))]
    amplitude = tuple(float(SWING * rng.uniform(0.5, 1.5)) for _ in range(2))
    return HandFigure(
        ratio,
        (amplitude[0], amplitude[1]),
        float(rng.uniform(0, 2 * np.pi)),
        (float(rng.uniform(-0.05, 0.05)), float(rng.uniform(-0.05, 0.05))),
    )


def free_shape(seed: int) -> FreeShape:
    """The free shape drawn by ``seed`` (module doc)."""
    rng = np.random.default_rng(seed)
    coupling = COUPLINGS[int(rng.integers(len(COUPLINGS)))]
    left = _figure(rng)
    if coupling == "each its own":
        right: HandFigure | None = _figure(rng)
    elif coupling == "one hand":
        left, right = (left, None) if rng.random() < 0.5 else (None, left)
    else:
        right = left
    fastest = max(max(f.ratio) for f in (left, right) if f is not None)
    low, high = PERIODS[fastest]
    return FreeShape(seed, coupling, int(rng.integers(low, high + 1)), left, right)


def perform_free(
    shape: FreeShape, steps: int, rng: np.random.Generator, start_phase: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """The shape performed for ``steps`` steps by a person (module doc): hands (steps, 2, 3),
    robot frame, metres, in the plane the demonstrator's hands move in; and the phase
    (radians, unwrapped)."""
    body = UserBody()
    cycles = int(np.ceil(steps / shape.period)) + 2
    lengths = shape.period * np.clip(1 + 0.05 * rng.standard_normal(cycles), 0.8, 1.2)
    sizes = np.clip(1 + 0.08 * rng.standard_normal(cycles), 0.7, 1.3)
    edges = np.concatenate([[0.0], np.cumsum(lengths)])
    t = np.arange(steps, dtype=np.float64)
    cycle = np.searchsorted(edges, t, side="right") - 1
    phase = start_phase + 2 * np.pi * (cycle + (t - edges[cycle]) / lengths[cycle])
    size = sizes[cycle]
    hands = np.repeat(body.hand_centres[None], steps, axis=0).astype(np.float64)
    figures = {"mirrored": (1, -1), "in step": (1, 1), "opposite": (1, 1)}
    for index, figure in enumerate((shape.left, shape.right)):
        if figure is None:
            continue
        theta = phase + (np.pi if shape.coupling == "opposite" and index == 1 else 0.0)
        mirror = figures.get(shape.coupling, (1, 1))[index]
        y = figure.offset[0] * mirror + mirror * figure.amplitude[0] * np.sin(
            figure.ratio[0] * theta
        )
        z = figure.offset[1] + figure.amplitude[1] * np.sin(figure.ratio[1] * theta + figure.phase)
        hands[:, index, 1] += size * y
        hands[:, index, 2] += size * z
    return hands, phase
