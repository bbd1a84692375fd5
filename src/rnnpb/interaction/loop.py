"""The real-time interaction loop: user source → mirror system → robot, every step.

Each step is timed by sections — ``perceive`` (read the source: a camera frame and the
tracker, or the next scripted observation), ``mirror`` (the PB regression and the motor
generation: one compiled call), ``act`` (send the command to the robot) and ``record`` (write
the session row). A step whose sections together overran ``dt`` counts as a missed deadline;
run as fast as possible the loop just measures.

The loop owns its pacing (:class:`rnnpb.interaction.pacing.Pacer`): :meth:`InteractionLoop.run`
paced (one step every ``dt`` seconds, as a robot would) starts each step at its deadline, and a
step that overran makes the next one start at once (missed steps are not made up). A controller
— the dashboard — passes ``between_steps``: the loop calls it while it waits for the next step,
and there the controller applies its commands (:meth:`~InteractionLoop.set_dt`,
:meth:`~InteractionLoop.stop`, a new source); it never steps the loop itself.

A source that perceives in a worker thread (the pose tracker:
:class:`rnnpb.perception.TrackedUserSource` with ``in_worker``) is given a deadline by a paced
loop: :data:`PERCEPTION_SHARE` of the step. A frame whose perception has not finished by then
does not hold the step up: the step takes the latest observation again, marked ``reused``
(counted in :attr:`LoopSummary.reused_observations`), and the frame's perception goes on beside
the network's step.

Subscribers (the dashboard, the session video) receive every :class:`StepRecord` once the step
is complete: its four timings and the loop's counters are filled in before they are called, so
what they publish is this step's. Their own time is outside the sections and the deadline
check (they run on the loop's thread, so they should be quick; a paced run absorbs them in its
wait).
"""

from __future__ import annotations

import math
import numbers
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.interaction.pacing import Pacer
from rnnpb.interaction.recorder import SessionRecorder
from rnnpb.sources import UserSource

if TYPE_CHECKING:  # only annotated here: importing the loop does not import JAX
    from rnnpb.model.mirror import MirrorSystem

SECTIONS = ("perceive", "mirror", "act", "record")
TIMING_WINDOW = 10_000
PERCEPTION_SHARE = 0.5
"""The share of a paced step that the loop waits for a source perceiving in a worker thread;
the other half is the network's, the robot's and the recording's (a few ms each)."""


@dataclass(frozen=True)
class LoopConfig:
    """``dt``: seconds per network step (the paper: 0.4). ``paced``: wait for each step's
    deadline (real time) instead of running as fast as possible. ``max_steps``: stop after
    this many steps (``None``: when the source ends)."""

    dt: float = 0.4
    paced: bool = False
    max_steps: int | None = None

    def __post_init__(self) -> None:
        dt = self.dt
        # The type first: a bool is no duration, and float() of a 309-digit integer raises
        # OverflowError; then finiteness, since inf or NaN would stall or never pace the loop.
        if isinstance(dt, bool) or not isinstance(dt, numbers.Real):
            raise ConfigError(f"dt must be a number of seconds, got {dt!r:.40}")
        try:
            finite = math.isfinite(dt)
        except OverflowError:
            finite = False
        if not finite or not dt > 0:
            raise ConfigError(f"dt must be a finite number of seconds > 0, got {dt!r:.40}")
        object.__setattr__(self, "dt", float(dt))
        if not isinstance(self.paced, bool):
            raise ConfigError(f"paced must be True or False, got {self.paced!r:.40}")
        steps = self.max_steps
        if steps is not None:
            if isinstance(steps, bool) or not isinstance(steps, numbers.Integral):
                raise ConfigError(f"max_steps must be a whole number or None, got {steps!r:.40}")
            if steps < 0:
                raise ConfigError(f"max_steps must be >= 0, got {steps}")
            object.__setattr__(self, "max_steps", int(steps))


@dataclass
class StepRecord:
    """One step of an interaction.

    ``observed`` (4,) the hands seen (NaN where lost); ``predicted`` (4,) what the network had
    predicted for this step one step before (NaN on the first step); ``motor`` (8,) the command
    sent, radians; ``pb`` (P,); ``timings`` seconds per section; ``recognised``,
    ``confidence``, ``novelty``, ``pattern_confidence``, ``repeating``: what the step
    recognised (:class:`rnnpb.model.mirror.StepResult`). ``reused``: the frame's perception was
    not finished by the paced step's deadline, and ``observed`` is the latest observation again.
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
    # With a command filter (rnnpb.safety.CommandFilter): why the generated command was unsafe
    # (empty when safe) and what the filter did ("", "slowed", "shortened", "held"); ``motor``
    # is then the command the robot was sent.
    unsafe: str = ""
    filtered: str = ""
    recognised: str | None = None
    confidence: float = 0.0
    novelty: str = ""
    pattern_confidence: dict[str, float] = field(default_factory=dict)
    repeating: int = 0
    # The meta-level (docs/safety.md): what drove the motion and why the generated command
    # was held (empty when sent; ``motor`` is then the command before).
    regime: str = ""
    inhibited: str = ""
    reused: bool = False


@dataclass
class LoopSummary:
    steps: int
    missed_deadlines: int
    section_ms: dict[str, dict[str, float]]
    lost_steps: int
    held_steps: int
    reused_observations: int = 0

    def to_dict(self) -> dict[str, Any]:
        return {
            "steps": self.steps,
            "missed_deadlines": self.missed_deadlines,
            "section_ms": self.section_ms,
            "lost_steps": self.lost_steps,
            "held_steps": self.held_steps,
            "reused_observations": self.reused_observations,
        }

    def describe(self) -> str:
        parts = [
            f"{name} {v['median']:.2f} ms (p99 {v['p99']:.2f})"
            for name, v in self.section_ms.items()
        ]
        reused = (
            f"; observations reused (perception late): {self.reused_observations}"
            if self.reused_observations
            else ""
        )
        return (
            f"{self.steps} steps; per step: "
            + ", ".join(parts)
            + f"; missed deadlines: {self.missed_deadlines}; steps with a hand lost: "
            f"{self.lost_steps}" + reused
        )


class InteractionLoop:
    """Runs the interaction. The source, robot and recorder are opened and closed by the
    caller (they are context managers); the loop only uses them.

    Parameters
    ----------
    mirror : MirrorSystem
    source : UserSource
    robot : rnnpb.robot.Robot, optional
        Its ``send(joints)`` returns what was actually sent; the recording holds that.
    recorder : SessionRecorder, optional
    command_filter : callable(command) -> FilterDecision, optional
        Checks each command in the act section, before it is sent
        (:class:`rnnpb.safety.CommandFilter`); ``prevented_commands`` counts what it changed.
    """

    def __init__(
        self,
        mirror: MirrorSystem,
        source: UserSource,
        robot: Any | None = None,
        recorder: SessionRecorder | None = None,
        config: LoopConfig | None = None,
        command_filter: Callable[[np.ndarray], Any] | None = None,
    ) -> None:
        self.mirror = mirror
        self.source = source
        self.robot = robot
        self.recorder = recorder
        self.config = config or LoopConfig()
        self._subscribers: list[Callable[[StepRecord], None]] = []
        # Bounded: the summary covers the last TIMING_WINDOW steps of a long run.
        self._timings: dict[str, deque[float]] = {
            name: deque(maxlen=TIMING_WINDOW) for name in SECTIONS
        }
        self._predicted = np.full(mirror.model.network.sensory_size, math.nan)
        self.steps = 0
        self._pacer = Pacer()
        self.lost_steps = 0
        self.held_steps = 0
        self.reused_observations = 0
        self.command_filter = command_filter
        self.prevented_commands = 0
        self.inhibited_commands = 0
        self.unsafe_commands = 0
        self._start: float | None = None
        self._stop_requested = False

    @property
    def missed_deadlines(self) -> int:
        """Steps whose sections together took longer than ``dt``."""
        return self._pacer.missed_deadlines

    def subscribe(self, callback: Callable[[StepRecord], None]) -> Callable[[], None]:
        """Call ``callback(record)`` after every step; returns a function that unsubscribes."""
        self._subscribers.append(callback)
        return lambda: self._subscribers.remove(callback) if callback in self._subscribers else None

    def step(self) -> StepRecord | None:
        """Run one step; ``None`` when the source has ended."""
        if self._start is None:
            self._start = time.perf_counter()
        t0 = time.perf_counter()
        self._give_perception_deadline(t0)
        observation = self.source.read()
        if observation is None:
            return None
        reused = getattr(observation, "reused", False) is True
        t1 = time.perf_counter()
        result = self.mirror.step(observation.sensory)
        t2 = time.perf_counter()
        motor, unsafe, filtered = result.motor, "", ""
        if self.command_filter is not None:
            decision = self.command_filter(result.motor)
            motor, unsafe, filtered = decision.command, decision.unsafe, decision.filtered
            self.unsafe_commands += int(bool(unsafe))
            self.prevented_commands += int(bool(filtered))
        if self.robot is not None:
            sent = self.robot.send(motor)
            if sent is not None:  # the robot contract returns what it actually sent
                motor = np.asarray(sent, dtype=np.float64)
        t3 = time.perf_counter()
        record = StepRecord(
            step=self.steps,
            time_s=t0 - self._start,
            observed=observation.sensory.copy(),
            predicted=self._predicted.copy(),
            predicted_next=result.predicted_hands,
            motor=motor,
            pb=result.pb,
            prediction_error=result.prediction_error,
            window_error=result.window_error,
            held=result.held,
            truth=observation.truth,
            frame=observation.frame,
            context=result.context,
            unsafe=unsafe,
            filtered=filtered,
            recognised=result.recognised,
            confidence=result.confidence,
            novelty=result.novelty,
            pattern_confidence=result.pattern_confidence,
            repeating=getattr(result, "repeating", 0),
            regime=getattr(result, "regime", ""),
            inhibited=getattr(result, "inhibited", ""),
            reused=reused,
        )
        self.inhibited_commands += int(bool(record.inhibited))
        self._predicted = result.predicted_hands.copy()
        if self.recorder is not None:
            self.recorder.write(record)
        t4 = time.perf_counter()
        record.timings = {"perceive": t1 - t0, "mirror": t2 - t1, "act": t3 - t2, "record": t4 - t3}
        for name, value in record.timings.items():
            self._timings[name].append(value)
        self.steps += 1
        self.lost_steps += int(not np.all(np.isfinite(observation.sensory)))
        self.held_steps += int(result.held)
        self.reused_observations += int(reused)
        self._pacer.took(t4 - t0, self.config.dt)
        # Last, so that subscribers publish this step's complete timings and counts.
        for callback in list(self._subscribers):
            callback(record)
        return record

    def _give_perception_deadline(self, t0: float) -> None:
        """Tell a source that perceives in a worker thread (``perceive_by``; also inside a
        ``FrameStepSource``) until when this step waits for it: paced, :data:`PERCEPTION_SHARE`
        of the step; otherwise for as long as it takes."""
        deadline = t0 + PERCEPTION_SHARE * self.config.dt if self.config.paced else None
        source = self.source
        for _ in range(4):  # a source wrapped by a few others at most
            perceive_by = getattr(source, "perceive_by", None)
            if callable(perceive_by):
                perceive_by(deadline)
                return
            source = getattr(source, "inner", None)
            if source is None:
                return

    def run(
        self,
        on_step: Callable[[StepRecord], None] | None = None,
        between_steps: Callable[[float], None] | None = None,
    ) -> LoopSummary:
        """Run until the source ends, ``max_steps`` or :meth:`stop`; paced at ``dt`` if
        configured.

        Parameters
        ----------
        on_step : callable(StepRecord), optional
            Called after every step (as a subscriber is, but for this run only).
        between_steps : callable(wait_s), optional
            Called before every step with the seconds left until that step is due (0 when the
            run is not paced or is late). It may block for up to ``wait_s`` — waiting for a
            command — and is called again until the step is due, so it should wait rather than
            return at once. In it a controller may :meth:`set_dt`, :meth:`stop` the run (to
            pause: stop, and call ``run`` again later; steps, window and timings carry on) or
            replace :attr:`source`. Without it a paced run sleeps until each deadline.
        """
        self._stop_requested = False
        self._pacer.start()
        while self.config.max_steps is None or self.steps < self.config.max_steps:
            self._pacer.wait(self.config.paced, between_steps, lambda: self._stop_requested)
            if self._stop_requested:
                break
            record = self.step()
            if record is None:
                break
            if on_step is not None:
                on_step(record)
            self._pacer.stepped(self.config.dt)
        return self.summary()

    def stop(self) -> None:
        """Make :meth:`run` return before its next step (from ``between_steps``, a subscriber
        or another thread while it runs)."""
        self._stop_requested = True

    def set_dt(self, dt: float) -> None:
        """Change the seconds per step from the next step on (the current wait keeps its
        deadline). Raises :class:`ConfigError` unless ``dt > 0``."""
        self.config = replace(self.config, dt=float(dt))

    def summary(self) -> LoopSummary:
        stats = {}
        for name, values in self._timings.items():
            values = list(values)
            if len(values) > 1 and len(values) == self.steps:
                values = values[1:]  # the first step includes compilation
            array = np.asarray(values) * 1e3
            if array.size:
                stats[name] = {
                    "median": float(np.median(array)),
                    "p99": float(np.percentile(array, 99)),
                    "max": float(array.max()),
                }
            else:
                stats[name] = {"median": math.nan, "p99": math.nan, "max": math.nan}
        return LoopSummary(
            self.steps,
            self.missed_deadlines,
            stats,
            self.lost_steps,
            self.held_steps,
            self.reused_observations,
        )
