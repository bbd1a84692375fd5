"""The learning phase: from a person's performance to sequences the network learns.

The same steps for every source (docs/design.md, "One learning phase"):

1. **The step.** The performance is played ``time_scale`` times slower and averaged over each
   step of ``dt`` (:func:`._performance.resampled`).
2. **Faster than the step can hold.** A cycle needs at least 4 steps (its up, its down and both
   turns). The repeating parts of the movement are found at a quarter of the step; where the
   fastest of them has fewer than 4 steps a cycle, the whole performance is played slower by
   the least factor that gives it 4 (*retimed*, and said so). At that step the robot cannot
   follow this movement in step with the person: a smaller step can (the report names it).
3. **Framing** (:mod:`._framing`): a source that knows the person's body is placed where the
   robot's camera sees all of it; a hand outside the view is put on its edge.
4. **The robot's joints** (:mod:`._servos`): the mirror mapping and the safe retargeting, the
   movement made smaller where the servos could not follow it at the person's tempo.
5. **Whole cycles** (:mod:`._cycles`): the repeating stretches, cut into cycles; what lies
   between them (a raise before a wave, rests, joins between takes) is left out, and said.
6. **Sequences**: runs of consecutive cycles, ``cycles`` at a time (None: as many as make
   about :data:`SEQUENCE_STEPS` steps, at least 2); or, with ``cut="length"``, stretches of
   ``length`` steps, or each stretch seen whole (``cut="whole"``, a routine).
7. **The one check** (:func:`rnnpb.safety.check_data`) on the values as they will be written:
   what the learning phase gives, ``rnnpb train`` learns.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from rnnpb.demonstrator import MirrorMapping, UserBody
from rnnpb.errors import ConfigError, RnnpbError
from rnnpb.learning_phase._cycles import MAX_PERIOD, MIN_PERIOD, CycleCut, whole_cycles
from rnnpb.learning_phase._framing import FRAMINGS, Framing, framed, placed_body, resolve
from rnnpb.learning_phase._performance import Performance, Steps, resampled, sensory_at
from rnnpb.learning_phase._servos import ServoFit, fit_to_servos
from rnnpb.robot.camera import RobotCamera
from rnnpb.safety import DataSafety, as_written, check_data
from rnnpb.sequences import Sequence
from rnnpb.structure import repeating_stretches

CUT_MODES = ("cycles", "length", "whole")
SEQUENCE_STEPS = 48
"""Steps a sequence of whole cycles is made up to (the paper's sequences are 50 steps)."""
SUBSTEPS = 4
"""Samples per step at which the fastest cycle is looked for (step 2)."""


@dataclass(frozen=True)
class PhaseOptions:
    """The learning phase's options, the same for every source.

    Attributes
    ----------
    dt : float
        Seconds per step of the data (and the model learned from them).
    time_scale : float
        Play the recording this many times slower (0.5: twice as fast).
    framing : str or float
        Where the person's body is placed in the robot camera's view: ``"reach"`` (the whole
        reach of the body in view), ``"fit"`` (the nearest that keeps this recording in view)
        or metres from the robot. Sources that do not know the body ignore it.
    cut : str
        ``cycles``, ``length`` or ``whole``.
    cycles : int or None
        Whole cycles per sequence; None: as many as make about :data:`SEQUENCE_STEPS` steps.
    length : int
        Steps per sequence with ``cut="length"``.
    """

    dt: float = 0.4
    time_scale: float = 1.0
    framing: float | str = "reach"
    cut: str = "cycles"
    cycles: int | None = None
    length: int = 50

    def __post_init__(self) -> None:
        if not (math.isfinite(self.dt) and self.dt > 0):
            raise ConfigError(f"--dt must be a positive number of seconds, got {self.dt}")
        if not (math.isfinite(self.time_scale) and 0.01 <= self.time_scale <= 100):
            raise ConfigError(f"--time-scale must be from 0.01 to 100, got {self.time_scale}")
        if isinstance(self.framing, str):
            if self.framing not in FRAMINGS:
                raise ConfigError(f"--framing must be reach, fit or metres, got {self.framing!r}")
        else:
            placed_body(self.framing)
        if self.cut not in CUT_MODES:
            raise ConfigError(f"cut mode must be one of {', '.join(CUT_MODES)}, got {self.cut!r}")
        if self.cycles is not None and self.cycles < 1:
            raise ConfigError(f"--cycles must be >= 1, got {self.cycles}")
        if self.length < 2:
            raise ConfigError(f"sequence length must be >= 2, got {self.length}")


@dataclass(frozen=True)
class Retiming:
    """Whether the performance was played slower than asked, to give its fastest cycle 4
    steps: ``asked`` and ``played`` time scales, the fastest cycle (seconds of the
    recording, None when nothing repeats)."""

    asked: float
    played: float
    fastest_s: float | None

    @property
    def retimed(self) -> bool:
        return self.played > self.asked + 1e-9

    @property
    def step_in_tempo(self) -> float:
        """The longest step (seconds) at which the fastest cycle keeps 4 steps at the asked
        time scale (NaN when nothing repeats)."""
        if self.fastest_s is None:
            return math.nan
        return math.floor(self.fastest_s * self.asked / MIN_PERIOD * 1000) / 1000

    def describe(self, dt: float) -> str:
        if self.fastest_s is None:
            return f"played at time scale {self.played:g}"
        steps = self.fastest_s * self.played / dt
        if not self.retimed:
            return (
                f"the fastest cycle is {self.fastest_s:.2f} s, {steps:.1f} steps of {dt:g} s: "
                "kept at the person's tempo"
            )
        return (
            f"the fastest cycle is {self.fastest_s:.2f} s, fewer than {MIN_PERIOD} steps of "
            f"{dt:g} s at time scale {self.asked:g}: played {self.played:g} times slower "
            f"({steps:.1f} steps a cycle); at this step the robot moves slower than the person "
            f"— learn at --dt {self.step_in_tempo:g} or less to follow it in step"
        )

    def to_json(self) -> dict:
        return {
            "asked_time_scale": self.asked,
            "played_time_scale": round(self.played, 4),
            "retimed": self.retimed,
            "fastest_cycle_s": None if self.fastest_s is None else round(self.fastest_s, 4),
        }


@dataclass(frozen=True)
class Recording:
    """What the learning phase made of a performance.

    Attributes
    ----------
    sequences : list of Sequence
        The training sequences, values as written.
    sensory : array, shape (n, 4)
        Every step's sensory values as framed (NaN where a hand was not seen).
    hands : array, shape (n, 2, 3)
        The person's hands (robot frame; on the standard body at 1 m for body sources).
    motor : array, shape (n, 8)
        The robot's joint angles, radians (NaN where the hands were not known).
    cycles : CycleCut
    framing, retiming, servos, safety
        What each step changed, and the one check's verdict on the sequences.
    """

    sequences: list[Sequence]
    sensory: np.ndarray
    hands: np.ndarray
    motor: np.ndarray
    cycles: CycleCut
    framing: Framing
    retiming: Retiming
    servos: ServoFit
    safety: DataSafety
    depth: str
    source: str
    capture: dict | None = field(default=None, compare=False)

    @property
    def n_steps(self) -> int:
        return len(self.sensory)

    @property
    def seen(self) -> np.ndarray:
        """(n,) steps with both hands and the joints known."""
        return np.asarray(
            np.isfinite(self.sensory).all(axis=1) & np.isfinite(self.motor).all(axis=1)
        )

    def report(self, dt: float) -> list[str]:
        """What the learning phase did, a line a step, for a person."""
        seen = int(self.seen.sum())
        inside = self.cycles.covered
        periods = sorted({s.period for s in self.cycles.stretches})
        lines = [
            f"time: {self.retiming.describe(dt)}",
            f"framing: {self.framing.describe()}",
            f"robot: {self.servos.describe()}",
        ]
        if self.cycles.cycles:
            lines.append(
                f"cycles: {len(self.cycles.cycles)} whole cycles of {self.cycles.period:.0f} steps "
                f"(median; stretches repeating every {', '.join(map(str, periods))} steps) hold "
                f"{inside} of the {seen} steps seen; the rest (before, between and after the "
                "repeating parts) is left out"
            )
        lines.append(f"check: {self.safety.describe()}")
        return lines

    def to_json(self) -> dict:
        return {
            "steps": self.n_steps,
            "steps_seen": int(self.seen.sum()),
            "depth": self.depth,
            "framing": self.framing.to_json(),
            "time": self.retiming.to_json(),
            "servos": self.servos.to_json(),
            "cycles": {
                "count": len(self.cycles.cycles),
                "median_steps": self.cycles.period,
                "steps_in_cycles": self.cycles.covered,
                "stretches": [
                    {"start": s.start, "stop": s.stop, "period": s.period}
                    for s in self.cycles.stretches
                ],
            },
            "safety": self.safety.to_json(),
        }


def fastest_cycle(performance: Performance, dt: float, time_scale: float) -> float | None:
    """Seconds of the recording per cycle of the fastest repeating part of the performance
    (looked for at a quarter of the step), None when nothing repeats."""
    fine = resampled(performance, dt / SUBSTEPS, time_scale)
    values = fine.offsets.reshape(len(fine), -1) if fine.offsets is not None else None
    if values is None:
        values = fine.sensory if fine.sensory is not None else fine.hands.reshape(len(fine), -1)
    periods: list[int] = []
    seen = np.isfinite(values).all(axis=1)
    edges = np.diff(np.concatenate([[0], seen.astype(int), [0]]))
    for a, b in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True):
        for stretch in repeating_stretches(values[a:b], MIN_PERIOD, MAX_PERIOD * SUBSTEPS):
            if stretch.stop - stretch.start >= 2 * stretch.period:
                periods.append(stretch.period)
    if not periods:
        return None
    return min(periods) * dt / SUBSTEPS / time_scale


def _frame(steps: Steps, performance: Performance, framing: float | str, camera: RobotCamera):
    if not performance.body:
        assert steps.sensory is not None
        sensory, outside = framed(steps.sensory)
        return sensory, Framing(None, "camera", int(outside.sum()))
    distance, rule = resolve(framing, lambda d: sensory_at(steps, performance, d, camera), camera)
    sensory, outside = framed(sensory_at(steps, performance, distance, camera))
    return sensory, Framing(distance, rule, int(outside.sum()))


def learning_phase(
    performance: Performance,
    pattern: str,
    options: PhaseOptions | None = None,
    camera: RobotCamera | None = None,
) -> Recording:
    """The learning phase of ``performance`` as training sequences of ``pattern`` (module
    doc). Raises :class:`RnnpbError` when nothing whole is left to learn (no repeating
    movement, every stretch shorter than asked)."""
    options = options or PhaseOptions()
    camera = camera or RobotCamera()
    fastest = fastest_cycle(performance, options.dt, options.time_scale)
    played = options.time_scale
    if fastest is not None and fastest * played < MIN_PERIOD * options.dt:
        played = math.ceil(MIN_PERIOD * options.dt / fastest * 100) / 100
    retiming = Retiming(options.time_scale, played, fastest)
    steps = resampled(performance, options.dt, played)
    sensory, framing = _frame(steps, performance, options.framing, camera)
    cut = whole_cycles(sensory)
    window = int(round(cut.period)) if cut.period else max(2, round(1.0 / options.dt))
    mapping = MirrorMapping(UserBody(), dt=options.dt)
    servos = fit_to_servos(steps.hands, mapping, window)
    sequences = _sequences(
        sensory, servos.motor, steps.hands, cut, pattern, performance.source, options
    )
    written = [as_written(s) for s in sequences]
    safety = check_data(written, dt=options.dt)
    if safety.unsafe:
        raise RnnpbError(
            f"{performance.source}: the learning phase made data its own check refuses "
            f"({safety.first}); nothing was written — please report this"
        )
    return Recording(
        written,
        sensory,
        steps.hands,
        servos.motor,
        cut,
        framing,
        retiming,
        servos,
        safety,
        performance.depth,
        performance.source,
        performance.capture,
    )


def _runs(valid: np.ndarray) -> list[tuple[int, int]]:
    edges = np.diff(np.concatenate([[0], np.asarray(valid, dtype=int), [0]]))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    return [(int(a), int(b)) for a, b in zip(starts, stops, strict=True)]


def _chunks(
    run: tuple[tuple[int, int], ...], per: int | None, period: float
) -> list[tuple[int, int]]:
    """A run of consecutive cycles as sequences of ``per`` cycles (None: about
    :data:`SEQUENCE_STEPS` steps, at least 2, the last taking what is left)."""
    if per is not None:
        return [(run[i][0], run[i + per - 1][1]) for i in range(0, len(run) - per + 1, per)]
    size = max(2, round(SEQUENCE_STEPS / period))
    if len(run) < 2:
        return []
    starts = list(range(0, len(run), size))
    if len(starts) > 1 and len(run) - starts[-1] < 2:
        starts.pop()  # a last single cycle joins the sequence before
    bounds = starts + [len(run)]
    return [(run[a][0], run[b - 1][1]) for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


def _sequences(
    sensory: np.ndarray,
    motor: np.ndarray,
    hands: np.ndarray,
    cut: CycleCut,
    pattern: str,
    source: str,
    options: PhaseOptions,
) -> list[Sequence]:
    valid = np.asarray(np.isfinite(sensory).all(axis=1) & np.isfinite(motor).all(axis=1))
    pieces: list[tuple[int, int]] = []
    if options.cut == "whole":
        pieces = [(a, b) for a, b in _runs(valid) if b - a >= 2]
    elif options.cut == "length":
        for a, b in _runs(valid):
            pieces += [
                (s, s + options.length) for s in range(a, b - options.length + 1, options.length)
            ]
    else:
        runs = [run for run in cut.runs if all(valid[a:b].all() for a, b in run)]
        period = cut.period or 1.0
        for run in runs:
            pieces += _chunks(run, options.cycles, period)
        if not pieces and options.cycles is None and sum(len(r) for r in runs) >= 2:
            # The movement repeats, but with something between each cycle (long rests):
            # each cycle is a sequence.
            pieces = [cycle for run in runs for cycle in run]
    if not pieces:
        raise RnnpbError(_nothing_whole(source, sensory, valid, cut, options))
    return [
        Sequence(
            sensory[a:b],
            motor[a:b],
            pattern,
            f"{source} steps {a}-{b - 1}",
            meta={"hands": hands[a:b], "first_step": int(a)},
        )
        for a, b in pieces
    ]


def _nothing_whole(source: str, sensory, valid, cut: CycleCut, options: PhaseOptions) -> str:
    seen = int(valid.sum())
    if options.cut == "length":
        return (
            f"{source}: no stretch of {options.length} steps with both hands seen in "
            f"{len(sensory)} steps ({seen} seen)"
        )
    if options.cut == "whole":
        return f"{source}: no stretch with both hands seen in {len(sensory)} steps"
    if not cut.cycles:
        return (
            f"{source}: the movement does not repeat in {len(sensory)} steps ({seen} with both "
            f"hands seen): no stretch of it comes back to itself within {MIN_PERIOD} to "
            f"{MAX_PERIOD} steps of {options.dt:g} s (perform it a few times, or use --cut length)"
        )
    longest = max(len(r) for r in cut.runs)
    return (
        f"{source}: at most {longest} whole cycles follow one another, fewer than --cycles "
        f"{options.cycles} (leave --cycles out to take what there is)"
    )
