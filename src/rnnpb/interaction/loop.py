"""The real-time interaction loop: user source → mirror system → robot, every step.

Each step is timed by sections — ``perceive`` (read the source: a camera frame and the
tracker, or the next scripted observation), ``mirror`` (the PB regression and the motor
generation: one compiled call), ``act`` (send the command to the robot) and ``record`` (write
the session row, notify subscribers). Run paced (one step every ``dt`` seconds, as a robot
would) the loop counts the steps whose work overran ``dt`` as missed deadlines; run as fast as
possible it just measures.

Subscribers (the dashboard, a live plot) receive every :class:`StepRecord`; they observe the
loop and never drive it.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.interaction.recorder import SessionRecorder
from rnnpb.interaction.source import UserSource
from rnnpb.model.mirror import MirrorSystem

SECTIONS = ("perceive", "mirror", "act", "record")
TIMING_WINDOW = 10_000


@dataclass(frozen=True)
class LoopConfig:
    """``dt``: seconds per network step (the paper: 0.4). ``paced``: wait for each step's
    deadline (real time) instead of running as fast as possible. ``max_steps``: stop after
    this many steps (``None``: when the source ends)."""

    dt: float = 0.4
    paced: bool = False
    max_steps: int | None = None

    def __post_init__(self) -> None:
        if not self.dt > 0:
            raise ConfigError(f"dt must be > 0 seconds, got {self.dt}")
        if self.max_steps is not None and self.max_steps < 0:
            raise ConfigError(f"max_steps must be >= 0, got {self.max_steps}")


@dataclass
class StepRecord:
    """One step of an interaction.

    ``observed`` (4,) the hands seen (NaN where lost); ``predicted`` (4,) what the network had
    predicted for this step one step before (NaN on the first step); ``motor`` (8,) the command
    sent, radians; ``pb`` (P,); ``timings`` seconds per section.
    """

    step: int
    time_s: float
    observed: np.ndarray
    predicted: np.ndarray
    predicted_next: np.ndarray
    motor: np.ndarray
    pb: np.ndarray
    prediction_error: float
    window_error: float
    held: bool
    truth: dict[str, Any] = field(default_factory=dict)
    timings: dict[str, float] = field(default_factory=dict)
    frame: np.ndarray | None = None
    context: np.ndarray | None = None


@dataclass
class LoopSummary:
    steps: int
    missed_deadlines: int
    section_ms: dict[str, dict[str, float]]
    lost_steps: int
    held_steps: int

    def to_dict(self) -> dict[str, Any]:
        return {"steps": self.steps, "missed_deadlines": self.missed_deadlines,
                "section_ms": self.section_ms, "lost_steps": self.lost_steps,
                "held_steps": self.held_steps}

    def describe(self) -> str:
        parts = [f"{name} {v['median']:.2f} ms (p99 {v['p99']:.2f})"
                 for name, v in self.section_ms.items()]
        return (f"{self.steps} steps; per step: " + ", ".join(parts)
                + f"; missed deadlines: {self.missed_deadlines}; steps with a hand lost: "
                f"{self.lost_steps}")


class InteractionLoop:
    """Runs the interaction. The source, robot and recorder are opened and closed by the
    caller (they are context managers); the loop only uses them.

    Parameters
    ----------
    mirror : MirrorSystem
    source : UserSource
    robot : object with ``send(joints)``, optional
    recorder : SessionRecorder, optional
    """

    def __init__(self, mirror: MirrorSystem, source: UserSource, robot: Any | None = None,
                 recorder: SessionRecorder | None = None, config: LoopConfig | None = None
                 ) -> None:
        self.mirror = mirror
        self.source = source
        self.robot = robot
        self.recorder = recorder
        self.config = config or LoopConfig()
        self._subscribers: list[Callable[[StepRecord], None]] = []
        # Bounded: the summary covers the last TIMING_WINDOW steps of a long run.
        self._timings: dict[str, deque[float]] = {name: deque(maxlen=TIMING_WINDOW)
                                                  for name in SECTIONS}
        self._predicted = np.full(mirror.model.network.sensory_size, math.nan)
        self.steps = 0
        self.missed_deadlines = 0
        self.lost_steps = 0
        self.held_steps = 0
        self._start: float | None = None

    def subscribe(self, callback: Callable[[StepRecord], None]) -> Callable[[], None]:
        """Call ``callback(record)`` after every step; returns a function that unsubscribes."""
        self._subscribers.append(callback)
        return lambda: self._subscribers.remove(callback) if callback in self._subscribers \
            else None

    def step(self) -> StepRecord | None:
        """Run one step; ``None`` when the source has ended."""
        if self._start is None:
            self._start = time.perf_counter()
        t0 = time.perf_counter()
        observation = self.source.read()
        if observation is None:
            return None
        t1 = time.perf_counter()
        result = self.mirror.step(observation.sensory)
        t2 = time.perf_counter()
        if self.robot is not None:
            self.robot.send(result.motor)
        t3 = time.perf_counter()
        record = StepRecord(
            step=self.steps, time_s=t0 - self._start, observed=observation.sensory.copy(),
            predicted=self._predicted.copy(), predicted_next=result.predicted_hands,
            motor=result.motor, pb=result.pb, prediction_error=result.prediction_error,
            window_error=result.window_error, held=result.held, truth=observation.truth,
            frame=observation.frame, context=result.context)
        self._predicted = result.predicted_hands.copy()
        # Subscribers see this step's timings so far; "record" is filled in after them.
        record.timings = {"perceive": t1 - t0, "mirror": t2 - t1, "act": t3 - t2,
                          "record": 0.0}
        if self.recorder is not None:
            self.recorder.write(record)
        for callback in list(self._subscribers):
            callback(record)
        t4 = time.perf_counter()
        record.timings["record"] = t4 - t3
        for name, value in record.timings.items():
            self._timings[name].append(value)
        self.steps += 1
        self.lost_steps += int(not np.all(np.isfinite(observation.sensory)))
        self.held_steps += int(result.held)
        if t4 - t0 > self.config.dt:
            self.missed_deadlines += 1
        return record

    def run(self, on_step: Callable[[StepRecord], None] | None = None) -> LoopSummary:
        """Run until the source ends or ``max_steps``; paced at ``dt`` if configured."""
        deadline = time.perf_counter()
        while self.config.max_steps is None or self.steps < self.config.max_steps:
            record = self.step()
            if record is None:
                break
            if on_step is not None:
                on_step(record)
            if self.config.paced:
                deadline += self.config.dt
                delay = deadline - time.perf_counter()
                if delay > 0:
                    time.sleep(delay)
                else:
                    deadline = time.perf_counter()
        return self.summary()

    def summary(self) -> LoopSummary:
        stats = {}
        for name, values in self._timings.items():
            values = list(values)
            if len(values) > 1 and len(values) == self.steps:
                values = values[1:]  # the first step includes compilation
            array = np.asarray(values) * 1e3
            if array.size:
                stats[name] = {"median": float(np.median(array)),
                               "p99": float(np.percentile(array, 99)), "max": float(array.max())}
            else:
                stats[name] = {"median": math.nan, "p99": math.nan, "max": math.nan}
        return LoopSummary(self.steps, self.missed_deadlines, stats, self.lost_steps,
                           self.held_steps)
