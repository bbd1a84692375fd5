"""The experiments of Ito & Tani (2004), section 3, as functions over the library.

Each experiment takes a trained model and returns a frozen result object (its measures and
the arrays its figure needs); :mod:`rnnpb.experiments.jobs` runs them on each learned model,
:mod:`rnnpb.experiments.demo` draws the figures and :mod:`rnnpb.experiments.report` writes the
report. The measures, their definitions and the paper's targets are in
:mod:`rnnpb.analysis.metrics`. The results pickle, so the jobs run in worker processes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from itertools import permutations
from typing import Any

import numpy as np

from rnnpb.analysis import metrics
from rnnpb.model import (
    MirrorSystem,
    OnlineConfig,
    StepResult,
    TrainedModel,
    generate,
    run_streams,
)
from rnnpb.model.meta import MetaParams
from rnnpb.model.recognition import RecognitionConfig
from rnnpb.vectors import (
    MOTOR_NAMES,
    PREDICTED_PREFIX,
    SENSORY_NAMES,
    STEP_COLUMN,
    TRUTH_PATTERN_COLUMN,
    pb_column,
)

# The scripted interactions (paper 3.1, 3.2): the user's pause, and how long the user performs
# each pattern before switching.
PAUSE_STEPS = 5
SWITCH_STEPS_EACH = 50
# Runs are stepped together in one batched call (run_scenarios) only when they hold this many
# steps in all: each new number of sessions is compiled first (about 5 s), and a session's
# share of a batched step saves about half a plain step (rnnpb bench), so fewer steps lose.
BATCHED_STEPS = 2500


# --- running a scenario ------------------------------------------------------------------


@dataclass(frozen=True)
class Run:
    """One interaction with a scenario: what the robot saw, predicted and did."""

    name: str
    labels: list[str]
    switch_steps: list[int]
    observed: np.ndarray  # (T, 4)
    predicted: np.ndarray  # (T, 4) prediction of this step made one step before
    motor: np.ndarray  # (T, 8) rad
    truth_motor: np.ndarray  # (T, 8) rad: the joints that imitate the user
    pb: np.ndarray  # (T, P)
    context: np.ndarray  # (T, C)
    motor_error: np.ndarray  # (T,)
    sensory_error: np.ndarray  # (T,)
    # What each step's recognition said the user performs (None: nothing recognised).
    recognised: tuple[str | None, ...] = ()

    def session(self) -> dict[str, np.ndarray]:
        """The run as the columns of a session recording (for the plots)."""
        out: dict[str, Any] = {
            STEP_COLUMN: np.arange(len(self.labels)),
            TRUTH_PATTERN_COLUMN: np.array(self.labels, dtype=object),
        }
        for j, name in enumerate(SENSORY_NAMES):
            out[name] = self.observed[:, j]
            out[PREDICTED_PREFIX + name] = self.predicted[:, j]
        for j, name in enumerate(MOTOR_NAMES):
            out[name] = self.motor[:, j]
        for j in range(self.pb.shape[1]):
            out[pb_column(j)] = self.pb[:, j]
        return out


def run_scenario(
    model: TrainedModel,
    scenario,
    online: OnlineConfig,
    joint_limits: np.ndarray,
    meta: MetaParams | None = None,
    steering: str = "always",
    inhibition: bool = False,
) -> Run:
    """Drive the mirror system with a demonstrator scenario through the interaction loop.
    ``meta``: a safety map's risk network, for the guard ``online.safety_guard`` names
    (docs/safety.md); None runs unguarded. ``steering``, ``inhibition``: the meta-level's
    part of the step (:class:`rnnpb.model.MirrorSystem`)."""
    from rnnpb.demonstrator import ScenarioSource
    from rnnpb.interaction import InteractionLoop, LoopConfig

    records = []
    mirror = MirrorSystem(model, online, meta=meta, steering=steering, inhibition=inhibition)
    with ScenarioSource(scenario) as source:
        InteractionLoop(mirror, source, config=LoopConfig(dt=scenario.dt)).run(
            on_step=records.append
        )
    return _run(
        scenario,
        np.array([r.predicted for r in records]),
        [r.motor for r in records],
        [r.pb for r in records],
        [r.context for r in records],
        tuple(r.recognised for r in records),
        joint_limits,
    )


def run_scenarios(
    model: TrainedModel,
    scenarios: Sequence[Any],
    online: OnlineConfig,
    joint_limits: np.ndarray,
    meta: MetaParams | None = None,
    steering: str = "always",
    inhibition: bool = False,
) -> list[Run]:
    """:func:`run_scenario` for each of ``scenarios``, stepped by :func:`step_streams`: each
    run is what it would be alone (to the rounding of a batched product when they run
    together)."""
    streams = step_streams(
        model, [s.sensory for s in scenarios], online, meta, None, steering, inhibition
    )
    return [
        _run(
            scenario,
            _predictions(results, model.network.sensory_size),
            [r.motor for r in results],
            [r.pb for r in results],
            [r.context for r in results],
            tuple(r.recognised for r in results),
            joint_limits,
        )
        for scenario, results in zip(scenarios, streams, strict=True)
    ]


def step_streams(
    model: TrainedModel,
    streams: Sequence[np.ndarray],
    online: OnlineConfig,
    meta: MetaParams | None = None,
    recognition: RecognitionConfig | None = None,
    steering: str = "always",
    inhibition: bool = False,
) -> list[list[StepResult]]:
    """Each stream of observed hands, (T, 4), from a fresh start of the mirror system; each
    one's step results. Together in sessions of one batched call
    (:func:`rnnpb.model.run_streams`) once they hold :data:`BATCHED_STEPS` steps in all (a
    batched step of a new width is compiled first, which costs seconds) and the meta-level
    neither guards by regime nor inhibits; else one after the other in one mirror system,
    reset before each."""
    together = len(streams) > 1 and sum(len(stream) for stream in streams) >= BATCHED_STEPS
    if together and steering == "always" and not inhibition:
        return run_streams(model, streams, online, meta, recognition)
    mirror = MirrorSystem(model, online, meta, recognition, steering, inhibition)
    out = []
    for stream in streams:
        mirror.reset()
        out.append([mirror.step(u) for u in stream])
    return out


def _predictions(results: Sequence[StepResult], size: int) -> np.ndarray:
    """Each step's prediction of its observation, made one step before (NaN at the first)."""
    before = np.array([r.predicted_hands for r in results[:-1]]).reshape(-1, size)
    return np.concatenate([np.full((1, size), math.nan), before])


def _run(
    scenario,
    predicted: np.ndarray,
    motor: Sequence[np.ndarray],
    pb: Sequence[np.ndarray],
    context: Sequence[np.ndarray | None],
    recognised: tuple[str | None, ...],
    joint_limits: np.ndarray,
) -> Run:
    observed = np.array(scenario.sensory, dtype=np.float64)
    motor_array = np.array(motor)
    return Run(
        name=scenario.name,
        labels=list(scenario.labels),
        switch_steps=list(scenario.switch_steps),
        observed=observed,
        predicted=predicted,
        motor=motor_array,
        truth_motor=scenario.motor,
        pb=np.array(pb),
        context=np.array(context),
        motor_error=metrics.motor_error(motor_array, scenario.motor, joint_limits),
        sensory_error=metrics.sensory_error(predicted, observed),
        recognised=recognised,
    )


def _normalized_motor(model: TrainedModel, motor: np.ndarray) -> np.ndarray:
    s = model.network.sensory_size
    return (motor - model.lower[s:]) / (model.upper[s:] - model.lower[s:])


# --- 3.1 synchronization and pause ---------------------------------------------------------


@dataclass(frozen=True)
class Synchronization:
    """The user performs one learned pattern, pauses and goes on (paper 3.1, Figure 5).

    Step counts are ``None`` when the event never happened.
    """

    pattern: str
    steps_to_lock: int | None
    pb_settle_steps: int | None
    phase_lag_steps: float  # nan: not locked long enough to measure
    recognized_pattern: str  # the learned pattern whose PB is nearest before the pause
    pb_distance_to_learned: float
    pause_relative_motion: float  # the robot's motion in the pause relative to before it
    pause_steps_to_relock: int | None
    pause_start: int
    pause_end: int
    run: Run | None  # None where only the measures are kept (the other draws)
    # The on-line recognition's answer before the pause (rnnpb.model.recognition): None when
    # it recognised nothing there.
    detected_pattern: str | None = None

    def without_run(self) -> Synchronization:
        """The measures alone, light to send back from a worker."""
        return replace(self, run=None)


def synchronization(
    model: TrainedModel,
    pattern: str,
    online: OnlineConfig,
    joint_limits: np.ndarray,
    seed: int = 0,
    before: int = 75,
    pause: int = PAUSE_STEPS,
    after: int = 45,
    meta: MetaParams | None = None,
    steering: str = "always",
    inhibition: bool = False,
) -> Synchronization:
    """The user performs ``pattern``, pauses, and goes on (paper Figure 5). ``meta``,
    ``steering``, ``inhibition``: see :func:`run_scenario`."""
    scenario = _pause_scenario(pattern, seed, before, pause, after)
    run = run_scenario(model, scenario, online, joint_limits, meta, steering, inhibition)
    return _synchronization_of(model, pattern, run, before, pause)


def synchronizations(
    model: TrainedModel,
    patterns: Sequence[str],
    online: OnlineConfig,
    joint_limits: np.ndarray,
    seeds: Sequence[int] = (0,),
    meta: MetaParams | None = None,
    steering: str = "always",
    inhibition: bool = False,
) -> dict[int, list[Synchronization]]:
    """:func:`synchronization` of each pattern with each draw ``seeds``, run together
    (:func:`run_scenarios`); by draw, in the order of ``patterns``."""
    cases = [(seed, pattern) for seed in seeds for pattern in patterns]
    scenarios = [_pause_scenario(pattern, seed) for seed, pattern in cases]
    runs = run_scenarios(model, scenarios, online, joint_limits, meta, steering, inhibition)
    return _synchronizations_of(model, cases, runs, seeds)


def _synchronizations_of(
    model: TrainedModel,
    cases: Sequence[tuple[int, str]],
    runs: Sequence[Run],
    seeds: Sequence[int],
) -> dict[int, list[Synchronization]]:
    out: dict[int, list[Synchronization]] = {seed: [] for seed in seeds}
    for (seed, pattern), run in zip(cases, runs, strict=True):
        out[seed].append(_synchronization_of(model, pattern, run, 75, PAUSE_STEPS))
    return out


def _pause_scenario(
    pattern: str, seed: int, before: int = 75, pause: int = PAUSE_STEPS, after: int = 45
):
    from rnnpb.demonstrator import pause_scenario

    return pause_scenario(pattern, before=before, pause=pause, after=after, seed=seed)


def _synchronization_of(
    model: TrainedModel, pattern: str, run: Run, before: int, pause: int
) -> Synchronization:
    lock = metrics.steps_to_lock(run.motor_error, run.sensory_error, 0, before)
    settle = metrics.pb_settle_step(run.pb[:before])
    lag = math.nan
    if lock is not None and before - lock >= 18:
        segment = slice(lock, before)
        lag = metrics.phase_lag(
            _normalized_motor(model, run.motor[segment]),
            _normalized_motor(model, run.truth_motor[segment]),
            max_lag=5,
        )
    pause_end = before + pause
    window = slice(before, pause_end)
    preceding = slice(before - pause, before)
    moving = np.ptp(run.motor[preceding], axis=0)
    during = np.ptp(run.motor[window], axis=0)
    relative_motion = float(np.sum(during) / max(np.sum(moving), 1e-9))
    relock = metrics.steps_to_lock(run.motor_error, run.sensory_error, pause_end)
    recognized, distance = model.nearest_pattern(run.pb[before - 1])
    return Synchronization(
        pattern=pattern,
        steps_to_lock=lock,
        pb_settle_steps=settle,
        phase_lag_steps=lag,
        recognized_pattern=recognized,
        pb_distance_to_learned=distance,
        pause_relative_motion=relative_motion,
        pause_steps_to_relock=relock,
        pause_start=before,
        pause_end=pause_end,
        run=run,
        detected_pattern=run.recognised[before - 1] if run.recognised else None,
    )


# --- 3.2 switching ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Switching:
    """Steps from the user's switch until the robot follows, per ordered pair ``"a->b"``."""

    pairs: dict[str, int | None]


def switching(
    model: TrainedModel,
    online: OnlineConfig,
    joint_limits: np.ndarray,
    seed: int = 0,
    steps_each: int = SWITCH_STEPS_EACH,
    meta: MetaParams | None = None,
    steering: str = "always",
    inhibition: bool = False,
) -> Switching:
    """Every ordered pair of learned patterns: steps from the switch until the robot follows
    the new pattern (locked on it), the pairs run together (:func:`run_scenarios`).
    ``meta``, ``steering``, ``inhibition``: see :func:`run_scenario`."""
    return switchings(model, online, joint_limits, (seed,), steps_each, meta, steering, inhibition)[
        seed
    ]


def switchings(
    model: TrainedModel,
    online: OnlineConfig,
    joint_limits: np.ndarray,
    seeds: Sequence[int],
    steps_each: int = SWITCH_STEPS_EACH,
    meta: MetaParams | None = None,
    steering: str = "always",
    inhibition: bool = False,
) -> dict[int, Switching]:
    """:func:`switching` with each draw ``seeds``, every run together; by draw."""
    cases = _switch_cases(model, seeds)
    scenarios = [_switch_scenario(pair, seed, steps_each) for seed, pair in cases]
    runs = run_scenarios(model, scenarios, online, joint_limits, meta, steering, inhibition)
    return _switchings_of(cases, runs, seeds, steps_each)


def _switch_cases(model: TrainedModel, seeds: Sequence[int]) -> list[tuple[int, tuple[str, str]]]:
    return [(seed, pair) for seed in seeds for pair in permutations(model.patterns, 2)]


def _switch_scenario(pair: tuple[str, str], seed: int, steps_each: int = SWITCH_STEPS_EACH):
    from rnnpb.demonstrator import switch_scenario

    return switch_scenario(pair, steps_each=steps_each, seed=seed)


def _switchings_of(
    cases: Sequence[tuple[int, tuple[str, str]]],
    runs: Sequence[Run],
    seeds: Sequence[int],
    steps_each: int = SWITCH_STEPS_EACH,
) -> dict[int, Switching]:
    out: dict[int, dict[str, int | None]] = {seed: {} for seed in seeds}
    for (seed, (a, b)), run in zip(cases, runs, strict=True):
        out[seed][f"{a}->{b}"] = metrics.steps_to_lock(
            run.motor_error, run.sensory_error, steps_each
        )
    return {seed: Switching(pairs) for seed, pairs in out.items()}


@dataclass(frozen=True)
class SwitchingSequence:
    """The user performs the learned patterns one after another (Figures 6 and 7)."""

    run: Run
    steps_to_follow: list[int | None]  # per switch


def switching_sequence(
    model: TrainedModel,
    online: OnlineConfig,
    joint_limits: np.ndarray,
    seed: int = 0,
    steps_each: int = 55,
) -> SwitchingSequence:
    """The paper's Figure 6: the user performs the learned patterns one after another."""
    from rnnpb.demonstrator import switch_scenario

    run = run_scenario(
        model,
        switch_scenario(tuple(model.patterns), steps_each=steps_each, seed=seed),
        online,
        joint_limits,
    )
    follow = [
        metrics.steps_to_lock(run.motor_error, run.sensory_error, s, s + steps_each)
        for s in run.switch_steps
    ]
    return SwitchingSequence(run, follow)


@dataclass(frozen=True)
class Draw:
    """The synchronization runs (one per learned pattern) and the switching of one draw of the
    user's imperfection, or of one on-line regression."""

    synchronization: list[Synchronization]
    switching: Switching

    def without_runs(self) -> Draw:
        """The measures alone, light to send back from a worker."""
        return Draw([s.without_run() for s in self.synchronization], self.switching)


def draws(
    model: TrainedModel, online: OnlineConfig, joint_limits: np.ndarray, seeds: Sequence[int]
) -> dict[int, Draw]:
    """The synchronization of every learned pattern and the switching of every pair, with
    each draw ``seeds`` of the user's imperfection, all run together (:func:`run_scenarios`);
    by draw."""
    sync_cases = [(seed, pattern) for seed in seeds for pattern in model.patterns]
    switch_cases = _switch_cases(model, seeds)
    runs = run_scenarios(
        model,
        [_pause_scenario(pattern, seed) for seed, pattern in sync_cases]
        + [_switch_scenario(pair, seed) for seed, pair in switch_cases],
        online,
        joint_limits,
    )
    sync = _synchronizations_of(model, sync_cases, runs[: len(sync_cases)], seeds)
    switch = _switchings_of(switch_cases, runs[len(sync_cases) :], seeds)
    return {seed: Draw(sync[seed], switch[seed]) for seed in seeds}


# --- 3.3 novel patterns and attractors -----------------------------------------------------


@dataclass(frozen=True)
class Attractor:
    """A learned pattern's closed-loop attractor after the transient."""

    motor: np.ndarray  # (T, 8) normalized joints
    context: np.ndarray  # (T, C)
    cycle: np.ndarray  # (60, 8): the last period (or the best one, when not periodic)
    period: float | None  # steps, possibly fractional; None: not periodic
    return_error: float


def learned_attractors(model: TrainedModel, n_steps: int, transient: int) -> dict[str, Attractor]:
    """Closed-loop run (no input) from each learned pattern's PB: motor and context after
    the transient, and one cycle of the motor trajectory."""
    out = {}
    for name, pb in model.pattern_pb.items():
        generated = generate(
            model, pb, n_steps, initial_context=model.pattern_initial_context(name)
        )
        motor = _normalized_motor(model, generated.motor[transient:])
        found = metrics.periodicity(motor)
        period = found.period or found.best_period
        out[name] = Attractor(
            motor=motor,
            context=generated.context[transient:],
            cycle=metrics.last_cycle(motor, period),
            period=found.period,
            return_error=found.return_error,
        )
    return out


@dataclass(frozen=True)
class NovelResponse:
    """The response to a learning set's novel pattern, classified (paper 3.3, Figure 8)."""

    learning_set: str
    novel_pattern: str
    amplitude: float  # the pattern's size relative to the learned ones
    case: int  # 1, 2 or 3 (metrics.classify_response)
    description: str
    period: float | None
    nearest_pattern: str | None
    distance: float
    return_error: float
    motor: np.ndarray  # (T, 8) rad
    pb: np.ndarray  # (T, P)
    context: np.ndarray  # (T, C)
    # None: one exact cycle repeated; else the draw of the user demonstrating it by hand
    user_draw: int | None = None

    def without_arrays(self) -> NovelResponse:
        """The measures alone, light to send back from a worker."""
        empty = np.zeros((0, 0))
        return replace(self, motor=empty, pb=empty, context=empty)

    def to_json(self) -> dict[str, Any]:
        """The measures as ``results.json`` keeps them (the arrays stay out)."""
        return {
            "learning_set": self.learning_set,
            "novel_pattern": self.novel_pattern,
            "amplitude": self.amplitude,
            "user_draw": self.user_draw,
            "case": self.case,
            "description": self.description,
            "period": self.period,
            "nearest_pattern": self.nearest_pattern,
            "distance": self.distance,
            "return_error": self.return_error,
        }


def novel_response(
    model: TrainedModel,
    learning_set: str,
    online: OnlineConfig,
    joint_limits: np.ndarray,
    attractors: dict[str, Attractor],
    n_steps: int,
    transient: int,
    amplitude: float = 1.0,
) -> NovelResponse:
    """One cycle of the novel pattern, repeated for ``n_steps`` with on-line PB regression
    (the paper's open-loop attractor analysis); the response is classified."""
    return novel_responses(
        model, learning_set, online, attractors, n_steps, transient, amplitudes=(amplitude,)
    )[0]


def novel_by_hand(
    model: TrainedModel,
    learning_set: str,
    online: OnlineConfig,
    attractors: dict[str, Attractor],
    n_steps: int,
    transient: int,
    seed: int,
) -> NovelResponse:
    """The user demonstrates the novel pattern by hand for ``n_steps``: imperfect cycles
    (period, size and shape vary from cycle to cycle, drawn with ``seed``), as in the paper's
    interaction experiment; the response is classified."""
    return novel_responses(
        model, learning_set, online, attractors, n_steps, transient, by_hand=(seed,)
    )[0]


def novel_responses(
    model: TrainedModel,
    learning_set: str,
    online: OnlineConfig,
    attractors: dict[str, Attractor],
    n_steps: int,
    transient: int,
    amplitudes: Sequence[float] = (),
    by_hand: Sequence[int] = (),
) -> list[NovelResponse]:
    """:func:`novel_response` at each of ``amplitudes``, then :func:`novel_by_hand` with each
    draw of ``by_hand``, run together (:func:`rnnpb.model.run_streams`); in that order."""
    from rnnpb.demonstrator import novel_pattern, novel_scenario

    pattern = novel_pattern(learning_set)
    streams = [_repeated_cycle(pattern, amplitude, n_steps) for amplitude in amplitudes]
    streams += [novel_scenario(learning_set, n_steps=n_steps, seed=d).sensory for d in by_hand]
    results = step_streams(model, streams, online)
    cases = [(a, None) for a in amplitudes] + [(1.0, d) for d in by_hand]
    return [
        _classified_response(
            model, learning_set, pattern, amplitude, steps, attractors, transient, user_draw
        )
        for (amplitude, user_draw), steps in zip(cases, results, strict=True)
    ]


def _repeated_cycle(pattern: str, amplitude: float, n_steps: int) -> np.ndarray:
    """One exact cycle of ``pattern`` at ``amplitude`` times the learned size, repeated for
    ``n_steps``."""
    from rnnpb.demonstrator import Imperfection, PatternConfig, make_scenario

    base = PatternConfig(imperfection=Imperfection.none())
    config = replace(
        base,
        horizontal_amplitude=base.horizontal_amplitude * amplitude,
        vertical_amplitude=base.vertical_amplitude * amplitude,
        rotation_radius=base.rotation_radius * amplitude,
    )
    period = int(round(config.period_steps))
    cycle = make_scenario([(pattern, period)], seed=0, config=config, novel=(pattern,))
    repeats = int(math.ceil(n_steps / period))
    return np.tile(cycle.sensory, (repeats, 1))[:n_steps]


def _classified_response(
    model: TrainedModel,
    learning_set: str,
    pattern: str,
    amplitude: float,
    steps: Sequence[StepResult],
    attractors: dict[str, Attractor],
    transient: int,
    user_draw: int | None,
) -> NovelResponse:
    motor = np.array([r.motor for r in steps])
    normalized = _normalized_motor(model, motor)
    learned_cycles = {name: a.cycle for name, a in attractors.items()}
    case = metrics.classify_response(normalized[transient:], learned_cycles)
    return NovelResponse(
        learning_set=learning_set,
        novel_pattern=pattern,
        amplitude=amplitude,
        case=case.case,
        description=case.describe(),
        period=case.period,
        nearest_pattern=case.nearest_pattern,
        distance=case.distance,
        return_error=case.return_error,
        motor=motor,
        pb=np.array([r.pb for r in steps]),
        context=np.array([r.context for r in steps]),
        user_draw=user_draw,
    )


# --- 3.4 the larger set ----------------------------------------------------------------------


@dataclass(frozen=True)
class FollowsEveryPattern:
    """Steps until the robot follows each learned pattern in turn (``None``: never)."""

    steps_to_follow: dict[str, int | None]
    follows_all: bool  # every pattern within metrics.SWITCH_LIMIT steps


def follows_every_pattern(
    model: TrainedModel,
    online: OnlineConfig,
    joint_limits: np.ndarray,
    seed: int = 0,
    steps_each: int = SWITCH_STEPS_EACH,
) -> FollowsEveryPattern:
    """The user switches through all learned patterns; does the robot follow each within
    ``metrics.SWITCH_LIMIT`` steps?"""
    return follows_every_pattern_draws(model, online, joint_limits, (seed,), steps_each)[seed]


def follows_every_pattern_draws(
    model: TrainedModel,
    online: OnlineConfig,
    joint_limits: np.ndarray,
    seeds: Sequence[int],
    steps_each: int = SWITCH_STEPS_EACH,
) -> dict[int, FollowsEveryPattern]:
    """:func:`follows_every_pattern` with each draw ``seeds``, run together; by draw."""
    from rnnpb.demonstrator import switch_scenario

    order = list(model.patterns)
    runs = run_scenarios(
        model,
        [switch_scenario(tuple(order), steps_each=steps_each, seed=seed) for seed in seeds],
        online,
        joint_limits,
    )
    out = {}
    for seed, run in zip(seeds, runs, strict=True):
        starts = [0, *run.switch_steps]
        follow = {
            p: metrics.steps_to_lock(run.motor_error, run.sensory_error, s, s + steps_each)
            for p, s in zip(order, starts, strict=True)
        }
        ok = all(v is not None and v <= metrics.SWITCH_LIMIT for v in follow.values())
        out[seed] = FollowsEveryPattern(follow, ok)
    return out
