"""The scripted subject of the paper's section 4.2: a person who explores a robot's repertoire,
as one side of a :class:`rnnpb.interaction.dyad.Dyad`.

It sees the robot as a person would (its hands in the person's space,
:mod:`rnnpb.interaction.person_space`), plays its own patterns, follows the robot's movement
when it is one of them, and initiates another when they cannot match (:class:`SubjectConfig`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rnnpb.demonstrator import PATTERNS, PatternConfig, pattern_offsets
from rnnpb.errors import ConfigError
from rnnpb.interaction.dyad import AgentConfig, AgentStep, Dyad, RobotAgent, random_start
from rnnpb.model.io import TrainedModel
from rnnpb.model.online_config import OnlineConfig
from rnnpb.robot.camera import RobotCamera


@dataclass(frozen=True)
class SubjectConfig:
    """The scripted subject of the paper's section 4.2.

    It does not know the robot's repertoire. It plays a pattern of its own; when the robot's
    movement comes close to one of its patterns it keeps following it (it takes that pattern,
    at the robot's phase); when they cannot match for ``patience`` steps it initiates another
    (one it has not found yet, if any); once matched for ``memorize_steps`` it counts the
    pattern found and, after holding it that long again, moves on to explore another.

    Attributes
    ----------
    repertoire : tuple of str
        Its patterns (the demonstrator's movements).
    patience : int
        Steps without a match before it initiates another pattern.
    memorize_steps : int
        Steps of match after which a pattern counts as found (for the subject); it holds the
        synchrony as long again before exploring.
    follow_steps : int
        Steps the robot must move one of its other patterns before it follows it.
    commit_steps : int
        Steps it keeps to a pattern it has just initiated before it would follow another of
        the robot's movements: a person who starts a movement gives the partner time to take
        it up (the robot's switching takes up to 15 steps), and does not drop it the moment
        the partner is still doing the old one (0: it follows at once).
    phase_coupling : float
        Fraction of the phase difference to the robot it closes each step while matched.
    period_steps : float
        Its own cycle (the demonstrator's: 12 steps).
    match_tolerance : float
        The movement-class tolerance (relative RMS misfit) under which it deems a movement
        one of its patterns.
    """

    repertoire: tuple[str, ...] = PATTERNS
    patience: int = 30
    memorize_steps: int = 24
    follow_steps: int = 4
    commit_steps: int = 20
    phase_coupling: float = 0.3
    period_steps: float = 12.0
    match_tolerance: float = 0.5

    def __post_init__(self) -> None:
        if not self.repertoire or any(p not in PATTERNS for p in self.repertoire):
            raise ConfigError(f"subject repertoire must be patterns of {', '.join(PATTERNS)}")
        for name in ("patience", "memorize_steps", "follow_steps"):
            if getattr(self, name) < 1:
                raise ConfigError(f"subject {name} must be >= 1, got {getattr(self, name)}")
        if self.commit_steps < 0:
            raise ConfigError(f"subject commit_steps must be >= 0, got {self.commit_steps}")
        if not 0.0 <= self.phase_coupling <= 1.0:
            raise ConfigError("subject phase_coupling must be in [0, 1]")
        if not 3.0 <= self.period_steps <= 200.0:
            raise ConfigError("subject period_steps must be in [3, 200]")
        if not self.match_tolerance > 0:
            raise ConfigError("subject match_tolerance must be > 0")


class ScriptedSubject:
    """A person who explores the robot's repertoire (:class:`SubjectConfig`)."""

    def __init__(
        self,
        config: SubjectConfig | None = None,
        *,
        seed: int = 0,
        agent: AgentConfig | None = None,
        name: str = "subject",
        pattern_config: PatternConfig | None = None,
        camera: RobotCamera | None = None,
    ) -> None:
        self.config = config or SubjectConfig()
        self.agent = agent or AgentConfig()
        self.name = name
        self.rng = np.random.default_rng(seed)
        self.pattern_config = pattern_config or PatternConfig()
        self.camera = camera or RobotCamera()
        period = int(round(self.config.period_steps))
        theta = 2 * np.pi * np.arange(period) / period
        self._templates = {}
        for name in self.config.repertoire:
            cycle = self.camera.sensory_from_hands(
                self.pattern_config.body.hand_centres
                + pattern_offsets(name, theta, self.pattern_config)
            )
            self._templates[name] = cycle - cycle.mean(axis=0)
        self._period = period
        self.pattern = str(self.rng.choice(self.config.repertoire))
        self.theta = float(self.rng.uniform(0, 2 * np.pi))
        self.believed_found: list[str] = []
        self._views: list[np.ndarray] = []
        self._matched = 0
        self._unmatched = 0
        self._dwell = 0
        self._other = ("", 0)
        self._committed = self.config.commit_steps  # its first movement is its own initiative
        self._hands = self._pose()

    @property
    def hands(self) -> np.ndarray:
        return self._hands

    def _pose(self) -> np.ndarray:
        return self.pattern_config.body.hand_centres + pattern_offsets(
            self.pattern, np.array(self.theta), self.pattern_config
        )

    def _initiate(self) -> None:
        unfound = [
            p for p in self.config.repertoire if p not in self.believed_found and p != self.pattern
        ]
        choices = (
            unfound
            or [p for p in self.config.repertoire if p != self.pattern]
            or list(self.config.repertoire)
        )
        self.pattern = str(self.rng.choice(choices))
        self._matched = self._unmatched = self._dwell = 0
        self._other = ("", 0)
        self._committed = self.config.commit_steps

    def _robot_movement(self) -> tuple[str, int]:
        """What it takes the robot to be doing: the one of its own patterns (and its phase)
        that the robot's last cycle looks like, as :func:`rnnpb.analysis.dyad.classify_movement`
        judges it (it knows its own movements, not the robot's)."""
        w = self._period
        if len(self._views) < w:
            return "", -1
        segment = np.asarray(self._views[-w:])
        if not np.isfinite(segment).all():
            return "", -1
        segment = segment - segment.mean(axis=0)
        index = (np.arange(w)[:, None] + np.arange(-w + 1, 1)[None, :]) % w
        best = (np.inf, "", -1)
        for name, cycle in self._templates.items():
            fits = np.sqrt(np.mean((cycle[index] - segment[None]) ** 2, axis=(1, 2))) / np.sqrt(
                np.mean(cycle**2)
            )
            j = int(np.argmin(fits))
            if fits[j] < best[0]:
                best = (float(fits[j]), name, j)
        return (best[1], best[2]) if best[0] < self.config.match_tolerance else ("", -1)

    def act(self, view: np.ndarray) -> AgentStep:
        seen = np.asarray(view, dtype=np.float64)
        if self.agent.noise > 0:
            seen = seen + self.agent.noise * self.rng.standard_normal(seen.shape)
        self._views.append(seen)
        del self._views[: -self._period]
        robot, phase = self._robot_movement()
        config = self.config
        initiative = False
        self._dwell += 1
        self._committed -= 1
        if robot and robot == self.pattern:
            self._matched += 1  # over the time on this pattern: a flicker does not reset it
            self._unmatched = 0
            # Keep following passively: close part of the phase gap to the robot.
            robot_theta = 2 * np.pi * phase / self._period
            gap = (robot_theta - self.theta + np.pi) % (2 * np.pi) - np.pi
            self.theta += config.phase_coupling * gap
            if self._matched == config.memorize_steps and self.pattern not in self.believed_found:
                self.believed_found.append(self.pattern)
            if self._matched >= 2 * config.memorize_steps and len(self.believed_found) < len(
                config.repertoire
            ):
                self._initiate()  # memorised: explore another
                initiative = True
        else:
            self._unmatched += 1
            if robot and robot != self.pattern and self._committed <= 0:
                name, count = self._other
                self._other = (robot, count + 1 if name == robot else 1)
                if self._other[1] >= config.follow_steps:
                    # The robot's movement is close to one of its own: follow it.
                    self.pattern = robot
                    self.theta = 2 * np.pi * phase / self._period
                    self._matched = self._unmatched = self._dwell = 0
                    self._other = ("", 0)
            else:
                self._other = ("", 0)
            if (
                self._unmatched >= config.patience
                or self._dwell >= config.patience + 2 * config.memorize_steps
            ):
                # They cannot match (or not for long enough to remember it): try another.
                self._initiate()
                initiative = True
        self.theta += 2 * np.pi / config.period_steps
        self._hands = self._pose()
        return AgentStep(hands=self._hands, view=seen, intent=self.pattern, initiative=initiative)


def robot_and_subject(
    model: TrainedModel,
    robot: AgentConfig | None = None,
    subject: SubjectConfig | None = None,
    *,
    seed: int = 0,
    online: OnlineConfig | None = None,
) -> Dyad:
    """A robot (agent A, from a random start) and a scripted subject (agent B)."""
    rng = np.random.default_rng([int(seed), 42])
    pb, joints = random_start(model, rng)
    robot_agent = RobotAgent(
        model,
        robot,
        online=online,
        seed=int(rng.integers(2**31)),
        name="robot",
        initial_pb=pb,
        initial_joints=joints,
    )
    return Dyad(robot_agent, ScriptedSubject(subject, seed=int(rng.integers(2**31))))
