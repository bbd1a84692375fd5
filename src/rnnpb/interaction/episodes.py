"""The episode cutter: a new movement cut out of the interaction's stream.

The novelty detector (each on-line step's ``novelty``: ``familiar``, ``novel``,
``unstructured``, ``still`` or ``""``) says when the person performs a structured movement no
learned pattern fits. :class:`EpisodeCutter` watches those words step by step and keeps the
movement once it has been ``novel`` long enough to be sure and to hold whole cycles:

1. A *run* starts on a step called ``novel`` and goes on while the detector keeps calling
   the movement ``novel``: up to ``tolerance_steps`` consecutive steps without evidence
   (``""`` — the detector says nothing while a hand is lost for a moment, but the hand
   positions must be seen) and up to ``interruption_steps`` consecutive steps called
   ``familiar``, ``unstructured`` or ``still`` (the detector hesitates now and then on a new
   movement, and says ``still`` for a step where the hands turn) are forgiven. Anything
   longer (a pause, another movement) or a hand lost ends the run and throws it away.
   An episode is kept only when at least ``min_novel_share`` of its own steps were called
   ``novel``, so ``unstructured`` movement — which the detector calls ``novel`` on almost no
   step — is never kept, nor a learned pattern the detector calls ``familiar``.
2. The whole cycles of the run are counted with :func:`rnnpb.learning_phase.cycle_bounds`.
   From ``confirm_cycles`` whole cycles on the cutter is *recording* ("cycle k of
   ``episode_cycles``"); when the run holds ``episode_cycles`` whole cycles, the last
   ``episode_cycles`` of them are the episode: their sensory values as seen and the robot's
   joint angles for them (3-D hands from the source when it gives them, else on the fixed
   plane; mirror mapping and inverse kinematics, as in the learning phase).
3. The cutter then stays *kept* until the run ends, so one performance gives one episode,
   and goes on recording the performance: when the run ends (the person stops or changes
   movement) or holds ``max_run_steps`` steps from the episode's start, it returns the same
   performance again with every whole cycle seen since the episode began (``extends``), for
   the memory to hold in its place while it has not been learned. A person who shows a
   movement for longer teaches it with more of the variation they bring; the episode is
   kept, and the person told, as soon as it holds ``episode_cycles`` cycles.
4. **A short performance is kept when it ends.** The detector says ``novel`` once the
   movement's last cycle repeats the one before it, so about two cycles go by before a run
   starts, and a performance of three or four cycles ends before its run holds
   ``episode_cycles``. The steps that first call rests on (the step's ``repeating``) are the
   new movement already: when a run ends before it was kept, they are put in front of it
   (counted as called ``novel``) — as far back as the hands were seen without a break and no
   step was called ``still`` (a pause before the movement is not part of it). Steps called
   ``familiar`` are looked back through (recognition of the movement before holds a few
   steps into a new one), but leading cycles that are a learned pattern's shape
   (``EpisodeCutter.learned``, the running mirror system's judgement) are left out — and
   every whole cycle up to its last ``novel`` step is the
   episode, when they are ``episode_cycles`` or more, at least ``confirm_cycles`` of them the
   detector's own calls reach into, and novel enough. A performance long
   enough to keep on its own is cut as above, from the detector's own calls alone.

It is pure bookkeeping (NumPy only, no clock or I/O), bounded per step: a principal component
and an autocorrelation of at most ``max_run_steps`` steps.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import InitVar, dataclass, field
from typing import Any

import numpy as np

from rnnpb.demonstrator import MirrorMapping
from rnnpb.errors import ConfigError
from rnnpb.learning_phase import cycle_bounds, whole_cycles
from rnnpb.model._tuned import Tuning, section_values, settle, with_values
from rnnpb.model._tuned import with_tuning as _with_tuning
from rnnpb.perception import MOUSE_PLANE_X, hands_on_plane
from rnnpb.presets import Overrides
from rnnpb.robot.camera import RobotCamera

WATCHING, RECORDING, KEPT = "watching", "recording", "kept"
CUTTER_STATES = (WATCHING, RECORDING, KEPT)


@dataclass(frozen=True)
class TeachingConfig:
    """When a novel movement is kept.

    The settings a user changes are the constructor's; the three found by replaying the cutter
    over the novelty words of the teach study's script are read from the learning preset's
    ``[teaching.cutter]`` section (with their evidence) and changed only by
    :meth:`with_tuning`.

    Attributes
    ----------
    confirm_cycles : int
        Whole cycles called ``novel`` before the cutter says it is recording (and that a short
        performance must hold of the detector's own calls to be kept).
    tolerance_steps : int
        Consecutive steps without evidence (``""``: a hand lost for a moment) a run survives.
    max_run_steps : int
        The run's oldest steps are dropped beyond this many (bounds the cost per step); a
        kept performance grows to at most this many steps.
    plane_x : float
        ``x`` (m) of the hands' plane for sources that give no 3-D hands.
    episode_cycles : int
        Whole cycles an episode holds (tuned).
    interruption_steps : int
        Consecutive steps called ``familiar``, ``unstructured`` or ``still`` a run survives:
        the detector hesitates at a shape's turning points (tuned).
    min_novel_share : float
        The share of an episode's steps with evidence that must have been called ``novel``,
        so that unstructured movement and learned patterns are never kept (tuned).
    """

    confirm_cycles: int = 1
    tolerance_steps: int = 2
    max_run_steps: int = 200
    plane_x: float = MOUSE_PLANE_X
    episode_cycles: int = field(init=False)
    interruption_steps: int = field(init=False)
    min_novel_share: float = field(init=False)
    _tuning: InitVar[Mapping[str, Any] | None] = None

    def __post_init__(self, _tuning: Mapping[str, Any] | None) -> None:
        settle(self, _tuning, Tuning("paper", section_values("paper", "teaching.cutter")), None)
        if self.episode_cycles < 1:
            raise ConfigError(f"episode_cycles must be >= 1, got {self.episode_cycles}")
        if not 1 <= self.confirm_cycles <= self.episode_cycles:
            raise ConfigError(
                f"confirm_cycles must be in [1, episode_cycles], got {self.confirm_cycles}"
            )
        if self.tolerance_steps < 0:
            raise ConfigError(f"tolerance_steps must be >= 0, got {self.tolerance_steps}")
        if self.interruption_steps < 0:
            raise ConfigError(f"interruption_steps must be >= 0, got {self.interruption_steps}")
        if not 0.5 <= self.min_novel_share <= 1.0:
            raise ConfigError(f"min_novel_share must be in [0.5, 1], got {self.min_novel_share}")
        if self.max_run_steps < 16:
            raise ConfigError(f"max_run_steps must be >= 16, got {self.max_run_steps}")

    def with_tuning(self, **changes: Any) -> TeachingConfig:
        """These settings with some tuned values changed, for research: e.g.
        ``TeachingConfig().with_tuning(episode_cycles=4)``."""
        return _with_tuning(self, changes)

    def overridden(self, overrides: Overrides | None) -> TeachingConfig:
        """These settings with a ``--config`` file's ``[teaching.cutter]`` values over them."""
        return self if overrides is None else with_values(self, overrides.values("teaching.cutter"))


@dataclass(frozen=True)
class KeptMovement:
    """Whole cycles of a new movement, cut out of the stream.

    Attributes
    ----------
    sensory : array, shape (n_steps, 4)
    motor : array, shape (n_steps, 8)
        The robot's joint angles for the person's hands, radians.
    n_cycles : int
    first_step, last_step : int
        The loop steps it spans (inclusive).
    extends : bool
        The performance the cutter kept last, grown by the whole cycles seen since: it takes
        that movement's place.
    cycles : tuple of (start, stop)
        Its whole cycles, in steps from its first (stop exclusive).
    """

    sensory: np.ndarray
    motor: np.ndarray
    n_cycles: int
    first_step: int
    last_step: int
    extends: bool = False
    cycles: tuple[tuple[int, int], ...] = ()


@dataclass(frozen=True)
class CutterStatus:
    """What the cutter is doing, for the dashboard and the log."""

    state: str
    cycles: int
    episode_cycles: int

    def describe(self) -> str:
        if self.state == RECORDING:
            return (
                f"recording a new movement (cycle {min(self.cycles + 1, self.episode_cycles)}"
                f" of {self.episode_cycles})"
            )
        if self.state == KEPT:
            return "new movement kept"
        return ""


class EpisodeCutter:
    """Watches each step's novelty and keeps whole cycles of a novel movement (module doc).

    Parameters
    ----------
    config : TeachingConfig, optional
    mapping : MirrorMapping, optional
    camera : RobotCamera, optional
    """

    def __init__(
        self,
        config: TeachingConfig | None = None,
        mapping: MirrorMapping | None = None,
        camera: RobotCamera | None = None,
    ) -> None:
        self.config = config or TeachingConfig()
        self.mapping = mapping or MirrorMapping()
        self.camera = camera or RobotCamera()
        # What says a cycle is a learned pattern's shape (the running mirror system's
        # MirrorSystem.learned_shape, set by the teacher), or None.
        self.learned: Callable[[np.ndarray], str | None] | None = None
        self.reset()

    def reset(self) -> None:
        """Forget the current run and the steps seen before it."""
        self._steps: list[int] = []
        self._sensory: list[np.ndarray] = []
        self._hands: list[np.ndarray] = []
        self._novel: list[float] = []  # 1 novel, 0 familiar or unstructured, nan no evidence
        self._quiet = 0
        self._interrupted = 0
        self._cycles = 0
        self._kept = False
        self._kept_from = 0  # where the kept episode begins in the run
        # The steps the run's first novel call rested on (step, hands seen, 3-D hands, novelty
        # word): taken in only if the run ends before it was kept (_rescue).
        self._looked_back: list[tuple[int, np.ndarray, np.ndarray, str]] = []
        self._grown = False  # the kept performance's growth was returned
        # The latest steps seen without a break (step, hands seen, 3-D hands, novelty word),
        # for the start of the next run: the cycles the detector's first "novel" call rests on.
        self._recent: deque[tuple[int, np.ndarray, np.ndarray, str]] = deque(
            maxlen=self.config.max_run_steps
        )

    @property
    def extending(self) -> bool:
        """Whether a kept performance goes on, to be returned grown when it ends."""
        return self._kept and not self._grown

    @property
    def status(self) -> CutterStatus:
        config = self.config
        if self._kept:
            state = KEPT
        elif self._cycles >= config.confirm_cycles:
            state = RECORDING
        else:
            state = WATCHING
        return CutterStatus(state, self._cycles, config.episode_cycles)

    def observe(
        self,
        step: int,
        observed: np.ndarray,
        novelty: str,
        hands: np.ndarray | None = None,
        repeating: int = 0,
    ) -> KeptMovement | None:
        """One step: the hands seen (4,), the step's novelty word, optionally the 3-D hands
        (2, 3) and, on a step called ``novel``, how many of the latest steps (this one
        included) the detector found repeating; returns the episode on the step it is
        complete, the same performance grown (``extends``) on the step its run ends or fills
        ``max_run_steps``, else None."""
        observed = np.asarray(observed, dtype=np.float64).reshape(4)
        seen = bool(np.isfinite(observed).all())
        hands = (
            np.full((2, 3), np.nan)
            if hands is None
            else np.asarray(hands, dtype=np.float64).reshape(2, 3)
        )
        config = self.config
        going = bool(self._steps) and seen
        before = self._before(step, repeating) if novelty == "novel" and not going else []
        self._remember(step, observed, hands, seen, novelty)
        if novelty == "novel" and seen:
            self._quiet = self._interrupted = 0
        elif novelty == "" and going and self._quiet < config.tolerance_steps:
            self._quiet += 1  # no evidence for a moment: the run goes on
        elif (
            novelty in ("familiar", "unstructured", "still")
            and going
            and self._interrupted < config.interruption_steps
        ):
            self._interrupted += 1  # the detector hesitates: the run goes on
        else:
            grown = self._growth() if self.extending else self._rescue()
            self._forget()
            return grown
        if self._kept and self._grown:
            return None
        if not self._steps:
            self._looked_back = before
        self._add(step, observed, np.nan if novelty == "" else float(novelty == "novel"), hands)
        if self._kept:
            if len(self._steps) - self._kept_from < config.max_run_steps:
                return None
            grown, self._grown = self._growth(), True
            return grown
        if len(self._steps) > config.max_run_steps:
            del self._steps[0], self._sensory[0], self._hands[0], self._novel[0]
        cycles = cycle_bounds(np.array(self._sensory), growing=True)
        self._cycles = len(cycles)
        if self._cycles < config.episode_cycles:
            return None
        start, stop = cycles[-config.episode_cycles][0], cycles[-1][1]
        if not self._novel_enough(start, stop):
            return None  # not novel enough yet: the run goes on, its window slides
        self._kept, self._kept_from = True, start
        return self._movement(cycles[-config.episode_cycles :])

    def end(self) -> KeptMovement | None:
        """The stream has ended: the run ends as if the person had stopped. Returns what its
        end gives (a kept performance grown, or a short one kept), else None."""
        ended = self._growth() if self.extending else self._rescue()
        self.reset()
        return ended

    def _add(self, step: int, observed: np.ndarray, novel: float, hands: np.ndarray) -> None:
        self._steps.append(int(step))
        self._novel.append(novel)
        self._sensory.append(observed)
        self._hands.append(hands)

    def _forget(self) -> None:
        """End the run; the steps seen lately stay for the next one."""
        recent = self._recent
        self.reset()
        self._recent = recent

    def _remember(
        self, step: int, observed: np.ndarray, hands: np.ndarray, seen: bool, novelty: str
    ) -> None:
        """Keep the step among the latest seen without a break (a lost hand is a break)."""
        if not seen or (self._recent and self._recent[-1][0] != step - 1):
            self._recent.clear()
        if seen:
            self._recent.append((int(step), observed, hands, novelty))

    def _before(self, step: int, repeating: int) -> list[tuple[int, np.ndarray, np.ndarray, str]]:
        """The steps just before ``step`` among the ``repeating`` latest (``step`` is the
        last of them), as far back as they were seen without a break and none was called
        ``still``. Steps called ``familiar`` are taken: the last recognised pattern is held a
        few steps into the next movement (hysteresis), while the structure test already
        found the new one repeating over them; a learned pattern before the new movement is
        left out when its cycles are cut (:meth:`_cycles_to_last_novel`)."""
        wanted = max(0, int(repeating) - 1)
        if not wanted or not self._recent or self._recent[-1][0] != step - 1:
            return []
        taken: list[tuple[int, np.ndarray, np.ndarray, str]] = []
        for entry in reversed(self._recent):
            if len(taken) == wanted or entry[3] == "still":
                break
            taken.append(entry)
        return taken[::-1]

    def _novel_enough(self, start: int, stop: int) -> bool:
        said = np.array(self._novel[start:stop])
        said = said[np.isfinite(said)]
        return bool(said.size) and said.mean() >= self.config.min_novel_share

    def _movement(self, cycles: list[tuple[int, int]], extends: bool = False) -> KeptMovement:
        """The run's whole ``cycles`` (consecutive, in run steps) as a kept movement."""
        start, stop = cycles[0][0], cycles[-1][1]
        sensory = np.array(self._sensory[start:stop])
        hands = np.array(self._hands[start:stop])
        missing = ~np.isfinite(hands).all(axis=(1, 2))
        if missing.any():
            hands[missing] = hands_on_plane(sensory[missing], self.camera, self.config.plane_x)
        motor = self.mapping.motor_from_hands(hands)  # safe by construction (MirrorMapping)
        return KeptMovement(
            sensory,
            motor,
            len(cycles),
            self._steps[start],
            self._steps[stop - 1],
            extends,
            tuple((a - start, b - start) for a, b in cycles),
        )

    def _rescue(self) -> KeptMovement | None:
        """A run that ends before it was kept, with the steps its first novel call rested on
        in front: every whole cycle up to its last step called ``novel`` (at most
        ``max_run_steps`` steps), when they are ``episode_cycles`` or more, at least
        ``confirm_cycles`` of them the detector's own calls, and novel enough; else None. The
        run is over: its steps are changed."""
        config = self.config
        if not self._looked_back or self._steps[0] != self._looked_back[-1][0] + 1:
            return None  # nothing to add, or the run's first steps were dropped (a long run)
        ahead = len(self._looked_back)
        for entry in reversed(self._looked_back):
            self._steps.insert(0, entry[0])
            self._sensory.insert(0, entry[1])
            self._hands.insert(0, entry[2])
            self._novel.insert(0, 1.0)  # the call rested on them
        self._looked_back = []
        cycles = self._cycles_to_last_novel(0)
        # A cycle of the look back that is a learned pattern's shape is the movement before
        # this one (its recognition held a few steps into this one): left out.
        while cycles and cycles[0][0] < ahead and self._learned(cycles[0]):
            cycles.pop(0)
        # The cycles the detector's own calls reach into (not only those the look back holds).
        own = sum(stop > ahead for _, stop in cycles)
        if len(cycles) < config.episode_cycles or own < config.confirm_cycles:
            return None
        if not self._novel_enough(cycles[0][0], cycles[-1][1]):
            return None
        return self._movement(cycles)

    def _learned(self, cycle: tuple[int, int]) -> bool:
        if self.learned is None:
            return False
        return self.learned(np.array(self._sensory[cycle[0] : cycle[1]])) is not None

    def _cycles_to_last_novel(self, first: int) -> list[tuple[int, int]]:
        """The run's whole cycles (counted from its start) up to its last step called
        ``novel``, those that end after step ``first`` of the run, the oldest dropped beyond
        ``max_run_steps`` steps; none when no step from ``first`` on was called novel."""
        end = len(self._novel)
        while end > first and self._novel[end - 1] != 1.0:
            end -= 1  # after the last step called novel
        if end <= first:
            return []
        # The run was cut where the detector stopped saying novel, not where a cycle ends;
        # its movement is the last run of cycles that repeat one another (a learned pattern
        # before it, a look back too far, are other stretches).
        sensory = np.array(self._sensory[:end])
        runs = [r for r in whole_cycles(sensory, growing=True).runs if r[-1][1] > first]
        cycles = [c for c in (runs[-1] if runs else ()) if c[1] > first]
        while cycles and cycles[-1][1] - cycles[0][0] > self.config.max_run_steps:
            cycles.pop(0)
        return cycles

    def _growth(self) -> KeptMovement | None:
        """The kept performance with every whole cycle seen since it began, up to its last
        step called ``novel`` and at most ``max_run_steps`` steps; None when that adds no
        cycle or is not novel enough."""
        # The cycles of the run as the keep found them (from its start), from the one the
        # kept episode begins with.
        cycles = self._cycles_to_last_novel(self._kept_from)
        if len(cycles) <= self.config.episode_cycles:
            return None
        if not self._novel_enough(cycles[0][0], cycles[-1][1]):
            return None
        return self._movement(cycles, extends=True)
