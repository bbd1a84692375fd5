"""Two agents coupled through their senses (the paper's section 4.2): robot–robot and
robot–subject, in one process, as fast as possible or paced.

Each agent moves a body and sees its partner's. What an agent shows its partner is its hands
*in the person's space*: where a person's hands would be, in the seeing robot's frame, for the
robot's camera to see them as it saw its teachers (:mod:`rnnpb.interaction.person_space`: the
scale mapping between a robot's body and a person's). The robot agent is here; the scripted
subject, the person it may face, is :mod:`rnnpb.interaction.subject`.

Timing: the agents see each other one step late (the other's body as it was after the last
step), so both can act at once; a subject and a robot alike. Paced, the dyad keeps the
deadlines as the interaction loop does (:class:`rnnpb.interaction.pacing.Pacer`).

What an agent may vary (:class:`AgentConfig`): its *adaptation* — how fast its PB follows what
it sees (a scale on the regression's learning rates; 0: the PB never follows, the robot plays
its own pattern), its *persistence* — after how many steps of stable interaction it takes the
initiative and starts another of its patterns (``None``: never), and *noise* on what it sees.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor, wait
from dataclasses import dataclass, field, replace
from typing import Protocol

import numpy as np

from rnnpb.demonstrator import UserBody
from rnnpb.errors import ConfigError
from rnnpb.interaction.pacing import Pacer
from rnnpb.interaction.person_space import WARMUP, person_hands
from rnnpb.model.generation import generate
from rnnpb.model.io import TrainedModel
from rnnpb.model.mirror import MirrorSystem, StepResult
from rnnpb.model.online_config import OnlineConfig
from rnnpb.robot.camera import RobotCamera

LEAD_HORIZON = 600  # steps an initiative can last past lead_steps while the partner follows
LEADER_HORIZON = 4000  # steps a robot that never follows plans ahead (then plans again)
UNMATCHED = ("novel", "unstructured", "still")  # what the detector calls no learned pattern
RELEASE = 3  # unstable steps after which a leader whose partner no longer follows lets go


@dataclass(frozen=True)
class AgentConfig:
    """What an agent may vary.

    Attributes
    ----------
    adaptation : float
        Scale on the PB's (and the window onset's) learning rates of the on-line regression;
        1 is the configured rate; 0: the robot does not follow at all, it plays its own
        pattern (closed-loop generation from its PB) whatever it sees.
    persistence : int or None
        Steps of stable interaction (the agent's own prediction error below ``stable_error``)
        after which the agent takes the initiative: it starts another of its patterns and
        plays it without looking for ``lead_steps`` steps — its own closed-loop generation of
        that pattern, from the pattern's learned initial context. None: never.
    noise : float
        Standard deviation of the noise on what the agent sees (normalized view units).
    patience : int or None
        Steps of not predicting its partner (prediction error above ``stable_error``) after
        which the agent initiates another pattern, hoping the partner will follow (the
        paper's subjects did); each time a little longer, up to twice as long, drawn from its
        own random stream so that two agents do not keep initiating together. None: never.
    alone_steps : int or None
        Steps of seeing no movement (every view coordinate's standard deviation over them
        below ``still_level``) after which the agent, left alone, takes the initiative. None:
        never.
    still_level : float
        The movement (view units) under which the partner counts as still.
    lead_steps : int
        How long an initiative is held before the agent looks again.
    yield_steps : int or None
        While it leads, steps of predicting its partner well on a pattern that is neither the
        one it leads nor the one they were on before (the partner took an initiative of its
        own at about the same time) after which it gives way and follows the partner: each
        time drawn from ``yield_steps`` to three times as many, so that two agents do not give
        way together. None: it holds its initiative for ``lead_steps`` whatever the partner
        does.
    stable_error : float
        RMS prediction error (view units) under which a step counts as stable.
    familiar_only : bool
        A step counts as stable only if, besides predicting the partner, its mirror system
        recognises a learned pattern in what it sees (or has not decided yet): two robots can
        settle on a movement that each predicts well and that is none of their patterns, which
        their own novelty detector calls ``novel``, ``unstructured`` or ``still``; that is a
        movement they cannot match, after which the patience runs out as for any other.
    """

    adaptation: float = 1.0
    persistence: int | None = None
    noise: float = 0.0
    patience: int | None = None
    alone_steps: int | None = 12
    still_level: float = 0.01
    lead_steps: int = 24
    yield_steps: int | None = 3
    stable_error: float = 0.03
    familiar_only: bool = True

    def __post_init__(self) -> None:
        if not (math.isfinite(self.adaptation) and 0.0 <= self.adaptation <= 10.0):
            raise ConfigError(f"adaptation must be in [0, 10], got {self.adaptation}")
        if self.persistence is not None and self.persistence < 1:
            raise ConfigError(f"persistence must be >= 1 step or None, got {self.persistence}")
        if not (math.isfinite(self.noise) and self.noise >= 0.0):
            raise ConfigError(f"noise must be >= 0, got {self.noise}")
        if self.patience is not None and self.patience < 1:
            raise ConfigError(f"patience must be >= 1 step or None, got {self.patience}")
        if self.alone_steps is not None and self.alone_steps < 2:
            raise ConfigError(f"alone_steps must be >= 2 steps or None, got {self.alone_steps}")
        if not self.still_level >= 0:
            raise ConfigError(f"still_level must be >= 0, got {self.still_level}")
        if self.lead_steps < 0:
            raise ConfigError(f"lead_steps must be >= 0, got {self.lead_steps}")
        if self.yield_steps is not None and self.yield_steps < 1:
            raise ConfigError(f"yield_steps must be >= 1 step or None, got {self.yield_steps}")
        if not self.stable_error > 0:
            raise ConfigError(f"stable_error must be > 0, got {self.stable_error}")

    def online_config(self, base: OnlineConfig | None = None) -> OnlineConfig:
        """The on-line regression of an agent with this adaptation."""
        base = base or OnlineConfig()
        if self.adaptation == 1.0:
            return base
        if self.adaptation == 0.0:
            # No regression, and no restarts (they jump the PB to what fits): the PB stays.
            return replace(base, iterations=0).with_tuning(restart_span=0, phase_restarts=0)
        return base.with_tuning(
            pb=replace(base.pb, learning_rate=base.pb.learning_rate * self.adaptation),
            onset_learning_rate=base.onset_learning_rate * self.adaptation,
        )


@dataclass(frozen=True)
class AgentStep:
    """What an agent did in a step.

    Attributes
    ----------
    hands : array, shape (2, 3)
        Its hands in the person's space (what its partner sees next step).
    view : array, shape (4,)
        What it saw this step (its partner's hands through its camera, with its noise).
    pb : array, shape (P,) or None
        Its PB (a robot), or None (a subject).
    motor : array, shape (8,) or None
        Its joint angles (a robot).
    intent : str
        The pattern it means to play (a subject's current pattern; a robot's initiative while
        it lasts), else ``""``.
    initiative : bool
        It took the initiative at this step.
    result : StepResult or None
        The mirror system's step (a robot).
    """

    hands: np.ndarray
    view: np.ndarray
    pb: np.ndarray | None = None
    motor: np.ndarray | None = None
    intent: str = ""
    initiative: bool = False
    result: StepResult | None = None


class Agent(Protocol):
    """One side of a dyad: it sees (4,) and moves; ``hands`` is what it shows now."""

    name: str

    @property
    def hands(self) -> np.ndarray: ...

    def act(self, view: np.ndarray) -> AgentStep: ...


class RobotAgent:
    """A mirror system moving a simulated body (kinematic: the joints go where commanded)."""

    def __init__(
        self,
        model: TrainedModel,
        config: AgentConfig | None = None,
        *,
        online: OnlineConfig | None = None,
        seed: int = 0,
        name: str = "robot",
        body: UserBody | None = None,
        view: str = "mirrored",
        initial_pb: np.ndarray | None = None,
        initial_joints: np.ndarray | None = None,
    ) -> None:
        self.model = model
        self.config = config or AgentConfig()
        self.name = name
        self.body = body or UserBody()
        self.view_kind = view
        self.rng = np.random.default_rng(seed)
        self.mirror = MirrorSystem(model, self.config.online_config(online))
        self.patterns = tuple(model.patterns)
        if initial_pb is not None:
            self.mirror.reset(np.asarray(initial_pb, dtype=np.float64))
        lower = np.asarray(model.lower)[model.network.sensory_size :]
        upper = np.asarray(model.upper)[model.network.sensory_size :]
        self.joints = (
            np.asarray(initial_joints, dtype=np.float64)
            if initial_joints is not None
            else 0.5 * (lower + upper)
        )
        self._hands = person_hands(self.joints, self.body, view)
        self._stable = 0
        self._unstable = 0
        self._led = 0
        self._patience = self._draw_patience()
        self._intent = ""
        self._before = ""  # the pattern they were on when it took the initiative
        self._contested = 0
        self._yield_after: int | None = None
        self._recent: list[np.ndarray] = []
        self._plan: list[np.ndarray] = []  # joint angles to play while leading
        if self.config.adaptation == 0.0:
            self._play(self.mirror.pb, LEADER_HORIZON)

    @property
    def hands(self) -> np.ndarray:
        return self._hands

    def _draw_patience(self) -> int | None:
        p = self.config.patience
        return None if p is None else p + int(self.rng.integers(0, p + 1))

    def _left_alone(self) -> bool:
        """The partner has not moved (or not been seen) for ``alone_steps`` steps: the steps
        it was seen on, if at least two, spread less than ``still_level``. A partner moving
        whenever seen is not alone: one unseen step (a person's page not yet heard from, a
        tracker's lost frame) is no reason to take the initiative."""
        n = self.config.alone_steps
        if n is None or len(self._recent) < n:
            return False
        recent = np.asarray(self._recent[-n:])
        seen = recent[np.isfinite(recent).all(axis=1)]
        if len(seen) < 2:
            return True
        return bool(np.all(seen.std(axis=0) < self.config.still_level))

    def set_config(self, config: AgentConfig) -> None:
        """Change persistence, noise and lead from the next step on (the adaptation is fixed
        at construction: it is part of the compiled step)."""
        self.config = replace(config, adaptation=self.config.adaptation)

    def take_initiative(self, pattern: str | None = None) -> str:
        """Start another learned pattern now (``pattern``, or one drawn from the others) and
        play it without looking for ``lead_steps`` steps; returns its name."""
        current = self.model.nearest_pattern(self.mirror.pb)[0]
        if pattern is None:
            others = [p for p in self.patterns if p != current] or list(self.patterns)
            pattern = str(self.rng.choice(others))
        if pattern not in self.patterns:
            raise ConfigError(
                f"pattern {pattern!r} is not one this robot learned ({', '.join(self.patterns)})"
            )
        self.mirror.reset(self.model.pattern_pb[pattern])
        self._play(
            self.model.pattern_pb[pattern],
            self.config.lead_steps + LEAD_HORIZON,
            self.model.pattern_initial_context(pattern),
        )
        # The pattern they were on, if they were on one (an initiative after a stable while):
        # a partner still doing it has not followed yet, and is no reason to give way.
        self._before, self._contested = (current if self._stable > 0 else ""), 0
        self._stable, self._unstable, self._led, self._intent = 0, 0, 0, pattern
        y = self.config.yield_steps
        self._yield_after = None if y is None else y + int(self.rng.integers(0, 2 * y + 1))
        self._patience = self._draw_patience()
        self._recent.clear()
        return pattern

    def _play(self, pb: np.ndarray, n_steps: int, context: np.ndarray | None = None) -> None:
        if n_steps > 0:
            # The closed loop of a model learned from short demonstrations takes a few cycles
            # to settle on its pattern (docs/dyad.md): the robot plays it from then on.
            generated = generate(
                self.model, np.clip(pb, 0.0, 1.0), WARMUP + n_steps, initial_context=context
            )
            self._plan = list(generated.motor[WARMUP:])

    def act(self, view: np.ndarray) -> AgentStep:
        seen = np.asarray(view, dtype=np.float64)
        if self.config.noise > 0:
            seen = seen + self.config.noise * self.rng.standard_normal(seen.shape)
        initiative = False
        if self.config.adaptation == 0.0:
            # It never follows: it plays its own pattern, planned ahead.
            if not self._plan:
                self._play(self.mirror.pb, LEADER_HORIZON)
            self.joints = self._plan.pop(0)
            self._hands = person_hands(self.joints, self.body, self.view_kind)
            return AgentStep(hands=self._hands, view=seen, pb=self.mirror.pb, motor=self.joints)
        if self._plan and self._led >= self.config.lead_steps and self._unstable >= RELEASE:
            # The partner no longer follows: look and follow again (and wait a while of its own
            # before initiating again, so that two agents do not keep initiating together).
            self._plan = []
            self._unstable, self._patience = 0, self._draw_patience()
        leading = bool(self._plan)
        persistence = self.config.persistence
        if (persistence is not None and self._stable >= persistence) or (
            not leading
            and (
                (self._patience is not None and self._unstable >= self._patience)
                or self._left_alone()
            )
        ):
            self.take_initiative()
            initiative = leading = True
        result = self.mirror.step(seen)
        stable = (
            math.isfinite(result.prediction_error)
            and math.sqrt(result.prediction_error) < self.config.stable_error
        )
        if self.config.familiar_only and not leading and result.novelty in UNMATCHED:
            stable = False  # predicted, but none of its patterns: they cannot match on it
        if leading:
            # Led: stable while the partner follows the led pattern (the mirror system, which
            # watches it, recognises that pattern in it).
            seen_pattern = self.model.nearest_pattern(result.pb)[0]
            contested = stable and seen_pattern not in (self._intent, self._before)
            self._contested = self._contested + 1 if contested else 0
            stable = stable and seen_pattern == self._intent
            if (
                not initiative
                and self._yield_after is not None
                and self._contested >= self._yield_after
            ):
                # The partner leads a pattern of its own: give way, follow it from this step.
                self._plan, self._intent, leading = [], "", False
                self._stable, self._unstable, self._contested = 0, 0, 0
                self._patience = self._draw_patience()
        self._stable = self._stable + 1 if stable else 0
        self._unstable = 0 if stable else self._unstable + 1
        if leading:
            # While it leads, the robot plays its generated pattern and does not act on what
            # it sees; its mirror system, started at that pattern's PB, watches the partner:
            # the lead lasts ``lead_steps`` and then as long as the partner follows (the
            # mirror predicts it), and the robot carries on from where the partner is.
            self.joints = self._plan.pop(0)
            self._led += 1
            if not self._plan:
                self._intent = ""
        else:
            self._intent = ""
            self._recent.append(seen)
            del self._recent[: -max(self.config.alone_steps or 1, 1)]
            self.joints = result.motor
        self._hands = person_hands(self.joints, self.body, self.view_kind)
        return AgentStep(
            hands=self._hands,
            view=seen,
            pb=result.pb,
            motor=self.joints,
            intent=self._intent,
            initiative=initiative,
            result=result,
        )


@dataclass(frozen=True)
class DyadStep:
    """One step of both agents: ``step`` index, each agent's :class:`AgentStep`, the seconds
    the step took, and each agent's hands as the other's camera sees them after the step
    (``shown_a``, ``shown_b``, (4,) each: what the partner sees next)."""

    step: int
    a: AgentStep
    b: AgentStep
    seconds: float
    shown_a: np.ndarray
    shown_b: np.ndarray


class Dyad:
    """Two agents facing each other; each sees the other's hands through its own camera.

    ``side_by_side``: two robots act at once, agent B in a thread of the dyad's own while A
    acts in the caller's (JAX computes without holding Python's lock, so on a machine with a
    core for each the two on-line steps overlap). The agents share nothing they change, so
    the steps are the same either way. None (the default): side by side when both agents are
    robots and this process may use two cores or more.
    """

    def __init__(
        self,
        a: Agent,
        b: Agent,
        camera: RobotCamera | None = None,
        *,
        side_by_side: bool | None = None,
    ) -> None:
        self.a, self.b = a, b
        self.camera = camera or RobotCamera()
        self.steps = 0
        if side_by_side is None:
            side_by_side = (
                isinstance(a, RobotAgent) and isinstance(b, RobotAgent) and usable_cores() >= 2
            )
        self.side_by_side = side_by_side
        self._thread: ThreadPoolExecutor | None = None
        self._shown: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self._pacer = Pacer()

    @property
    def missed_deadlines(self) -> int:
        """Steps of :meth:`run` that took longer than its ``dt``."""
        return self._pacer.missed_deadlines

    def view(self, of: Agent) -> np.ndarray:
        """What a robot's camera sees of an agent now, (4,)."""
        hands = of.hands
        kept = self._shown.get(id(of))
        if kept is not None and np.array_equal(kept[0], hands):
            return kept[1].copy()
        seen = self.camera.sensory_from_hands(hands)
        self._shown[id(of)] = (np.array(hands, copy=True), seen)
        return seen.copy()

    def _act_both(
        self, view_of_b: np.ndarray, view_of_a: np.ndarray
    ) -> tuple[AgentStep, AgentStep]:
        if not self.side_by_side:
            return self.a.act(view_of_b), self.b.act(view_of_a)
        if self._thread is None:
            self._thread = ThreadPoolExecutor(max_workers=1, thread_name_prefix="dyad-b")
        later = self._thread.submit(self.b.act, view_of_a)
        try:
            a = self.a.act(view_of_b)
        except BaseException:
            wait([later])  # B's step ends before A's error goes up: nothing runs on unseen
            raise
        return a, later.result()  # B's error, if any, is raised here

    def step(self) -> DyadStep:
        """Both agents see each other as they are and act (each sees the other one step
        late)."""
        start = time.perf_counter()
        view_of_b, view_of_a = self.view(self.b), self.view(self.a)
        a, b = self._act_both(view_of_b, view_of_a)
        seconds = time.perf_counter() - start
        record = DyadStep(self.steps, a, b, seconds, self.view(self.a), self.view(self.b))
        self.steps += 1
        return record

    def run(
        self,
        n_steps: int,
        *,
        dt: float = 0.4,
        paced: bool = False,
        on_step: Callable[[DyadStep], None] | None = None,
        between_steps: Callable[[float], None] | None = None,
        should_stop: Callable[[], bool] | None = None,
    ) -> DyadRun:
        """``n_steps`` steps, as fast as possible or one every ``dt`` seconds, paced as
        :class:`rnnpb.interaction.InteractionLoop` is (:class:`~rnnpb.interaction.pacing.Pacer`:
        a late step counts a missed deadline and starts the next at once). Paced,
        ``between_steps(wait_s)`` is called while waiting; ``should_stop()`` ends the run
        before its next step."""
        records = []
        self._pacer.start()
        for _ in range(n_steps):
            if paced:
                self._pacer.wait(True, between_steps, should_stop)
            if should_stop is not None and should_stop():
                break
            record = self.step()
            self._pacer.took(record.seconds, dt)
            records.append(record)
            if on_step is not None:
                on_step(record)
            self._pacer.stepped(dt)
        return DyadRun.from_steps(records)


@dataclass(frozen=True)
class DyadRun:
    """A two-agent run as arrays, (n, …) each: for each agent ``x`` in ``a``, ``b``: ``x_view``
    (what it saw, (n, 4)), ``x_shown`` (its hands as the other's camera saw them next, (n,
    4)), ``x_pb`` ((n, P), NaN for a subject), ``x_motor`` ((n, 8), NaN for a subject),
    ``x_intent`` and ``x_initiative``; ``seconds`` per step."""

    arrays: dict[str, np.ndarray] = field(default_factory=dict)

    @classmethod
    def from_steps(cls, steps: list[DyadStep]) -> DyadRun:
        out: dict[str, np.ndarray] = {"step": np.array([s.step for s in steps])}
        for side in ("a", "b"):
            parts = [getattr(s, side) for s in steps]
            out[f"{side}_view"] = np.array([p.view for p in parts]).reshape(-1, 4)
            out[f"{side}_shown"] = np.array([getattr(s, f"shown_{side}") for s in steps]).reshape(
                -1, 4
            )
            pb_size = next((len(p.pb) for p in parts if p.pb is not None), 4)
            out[f"{side}_pb"] = np.array(
                [p.pb if p.pb is not None else np.full(pb_size, np.nan) for p in parts]
            ).reshape(-1, pb_size)
            out[f"{side}_motor"] = np.array(
                [p.motor if p.motor is not None else np.full(8, np.nan) for p in parts]
            ).reshape(-1, 8)
            out[f"{side}_intent"] = np.array([p.intent for p in parts], dtype=object)
            out[f"{side}_initiative"] = np.array([p.initiative for p in parts], dtype=bool)
        out["seconds"] = np.array([s.seconds for s in steps])
        return cls(out)

    def __getitem__(self, key: str) -> np.ndarray:
        return self.arrays[key]

    def __len__(self) -> int:
        return len(self.arrays.get("step", ()))


def usable_cores() -> int:
    """The cores this process may run on (its affinity, where the platform has one)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - a platform without affinity (macOS)
        return os.cpu_count() or 1


def random_start(model: TrainedModel, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A random start for a robot: a PB drawn uniformly in [0.1, 0.9] per unit and joint
    angles drawn uniformly within the model's motor range; ((P,), (8,))."""
    s = model.network.sensory_size
    lower = np.asarray(model.lower)[s:]
    upper = np.asarray(model.upper)[s:]
    pb = rng.uniform(0.1, 0.9, model.network.pb_size)
    return pb, rng.uniform(lower, upper)


def robot_pair(
    model_a: TrainedModel,
    model_b: TrainedModel,
    a: AgentConfig | None = None,
    b: AgentConfig | None = None,
    *,
    seed: int = 0,
    online: OnlineConfig | None = None,
    view: str = "mirrored",
) -> Dyad:
    """Two robots from random starts (drawn from ``seed``)."""
    rng = np.random.default_rng([int(seed), 18])
    pb_a, joints_a = random_start(model_a, rng)
    pb_b, joints_b = random_start(model_b, rng)
    robot_a = RobotAgent(
        model_a,
        a,
        online=online,
        seed=int(rng.integers(2**31)),
        name="a",
        view=view,
        initial_pb=pb_a,
        initial_joints=joints_a,
    )
    robot_b = RobotAgent(
        model_b,
        b,
        online=online,
        seed=int(rng.integers(2**31)),
        name="b",
        view=view,
        initial_pb=pb_b,
        initial_joints=joints_b,
    )
    return Dyad(robot_a, robot_b)
