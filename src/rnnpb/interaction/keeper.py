"""The memory keeper: a loop subscriber that stores each novel movement the
:class:`~rnnpb.interaction.episodes.EpisodeCutter` cuts as an episode of the short-term memory,
and the notes those episodes carry; and each performance of a pattern teaching learned that the
robot recognises but does not follow closely, as more data for that pattern."""

from __future__ import annotations

import re
from collections import deque
from dataclasses import dataclass, replace

import numpy as np

from rnnpb.demonstrator import MirrorMapping
from rnnpb.errors import RnnpbError
from rnnpb.interaction.episodes import RECORDING, EpisodeCutter, TeachingConfig
from rnnpb.interaction.repeats import find_repeat, same_cycles
from rnnpb.safety import SafetyChecker, SafetyLimits


@dataclass(frozen=True)
class TeachingEvent:
    """Something the teacher did, for the dashboard and the log.

    ``kind`` is ``recording`` (a novel movement is being recorded; ``text`` says which cycle),
    ``kept`` (an episode was stored; ``episode_id``, ``pattern``; ``repeat_of`` the episode
    it was merged with when it is another performance of a kept movement, and ``performances``
    how many the memory holds of it), ``extended`` (the performance went on after it was
    kept, and the episode ``episode_id`` now holds every whole cycle of it) or ``refused``
    (the memory would not take it, or its joint angles are unsafe for the robot; ``text``
    says why). The
    :class:`~rnnpb.interaction.teaching.Teacher` adds its own kinds.
    """

    step: int
    kind: str
    text: str
    episode_id: int | None = None
    pattern: str = ""
    repeat_of: int | None = None
    performances: int = 0


# A recognised pattern is followed closely ("locked", the paper measures' definition:
# rnnpb.analysis.metrics.SENSORY_LOCK_THRESHOLD and LOCK_HOLD, which a test holds these to)
# when the one-step prediction of the hands has been within LOCK_ERROR (RMS, view units) for
# LOCK_STEPS steps running.
LOCK_ERROR = 0.03
LOCK_STEPS = 6
GROWS = "grows "  # in an episode's note: a performance of a learned pattern, more data for it

SHOWN_STEPS = 2000  # steps of a source's own account kept (an episode is far shorter)
SHOWN_AS = "shown as "  # in an episode's note: what a scripted source said it performed


def times(n: int) -> str:
    """ "once", "twice", "3 times"."""
    return {1: "once", 2: "twice"}.get(n, f"{n} times")


def episode_steps(note: str) -> tuple[int, int] | None:
    """The loop steps an episode's note says it was cut from, (first, last), or None."""
    part = note.split("; ")[0]
    if not part.startswith("steps "):
        return None
    try:
        first, last = (int(v) for v in part.removeprefix("steps ").split("-"))
    except ValueError:
        return None
    return first, last


def shown_as(note: str) -> str:
    """The pattern an episode's note says a scripted source performed, or ""."""
    for part in note.split("; "):
        if part.startswith(SHOWN_AS):
            return part[len(SHOWN_AS) :]
    return ""


MERGED_WITH = "merged with episode "  # in an episode's note: the movement it repeats


def merged_with(note: str) -> int | None:
    """The episode an episode's note says it was merged with (the last merge), or None."""
    found = None
    for part in note.split("; "):
        if part.startswith(MERGED_WITH):
            number = part[len(MERGED_WITH) :].split(" ")[0]
            found = int(number) if number.isdigit() else found
        elif part.startswith("split from "):
            found = None
    return found


class EpisodeKeeper:
    """A loop subscriber: cuts novel movements with an :class:`EpisodeCutter` and stores each
    as an episode in the short-term memory: another performance of a movement the memory
    holds (:func:`rnnpb.interaction.repeats.find_repeat`) under that movement's name, merged
    with it; else under the next free name ``new-1``, ``new-2`` ….

    Parameters
    ----------
    memory : rnnpb.memory.MemoryStore
        Open store (the keeper does not close it).
    model : str
        The running model's file (which model saw the movement).
    source : str
        The source's description (where the movement came from).
    config : TeachingConfig, optional
    hands_of : callable, optional
        ``hands_of(record) -> array (2, 3) or None``: the 3-D hands of a step when the source
        gives them (a camera's depth from size); else they lie on the fixed plane.

    A performance recognised as one of ``taught`` (the patterns teaching learned: the
    teacher sets them) but not followed closely — not locked on (:data:`LOCK_ERROR` over
    :data:`LOCK_STEPS` steps) on most of its steps, cut as a novel movement is — is stored
    under that pattern's name, as more data for it ("grow a pattern with use").

    ``events`` lists what happened, newest last; ``kept`` the stored episodes' ids.
    ``recognition`` (a :class:`~rnnpb.model.recognition.RecognitionConfig`, default the
    paper preset's) is how shapes are compared: the running mirror system's, set by the
    teacher.

    A performance that goes on after it was kept is stored again, whole, when it ends
    (:class:`~rnnpb.interaction.episodes.EpisodeCutter`): the episode grows in the memory
    (``extended``) unless it is no longer ``kept`` or a running consolidation is learning it
    (``learning``, the episodes' ids, set by the teacher): what is learned is what was kept.
    """

    def __init__(
        self,
        memory,
        model: str,
        source: str,
        config: TeachingConfig | None = None,
        hands_of=None,
        mapping: MirrorMapping | None = None,
    ) -> None:
        self.memory = memory
        self.model = str(model)
        self.source = str(source)
        self.cutter = EpisodeCutter(config, mapping)
        # Cuts performances of a taught pattern it does not follow closely, as ``cutter`` cuts
        # novel movements: "novel" there is "recognised as ``_growing`` but not locked".
        self.grower = EpisodeCutter(config, mapping)
        self.taught: frozenset[str] = frozenset()
        self.learning: frozenset[int] = frozenset()  # episodes a consolidation is learning
        self._growing = ""
        self._errors: deque[float] = deque(maxlen=LOCK_STEPS)
        self._checker: SafetyChecker | None = None  # made at the first episode
        self.hands_of = hands_of
        self.events: list[TeachingEvent] = []
        self.kept: list[int] = []
        self._last_kept: dict[str, int | None] = {}  # per cutter, the episode it kept last
        self._last_text = ""
        self.recognition = None
        self._last_record = None  # the latest step seen, for finish()
        # What a scripted source says it performed, per recent step (a demonstrator's
        # pattern): only written into an episode's note, for the person; never used to learn.
        self._shown: deque[tuple[int, str]] = deque(maxlen=SHOWN_STEPS)  # (step, pattern)

    def next_pattern_name(self) -> str:
        """``new-N`` for the smallest N no episode of the memory is named yet."""
        taken = {e.pattern for e in self.memory.episodes()}
        n = 1
        while f"new-{n}" in taken:
            n += 1
        return f"new-{n}"

    def _shown_as(self, first: int, last: int) -> str:
        """The pattern the source said it performed over most of steps first..last, or ""."""
        said = dict(self._shown)  # only when an episode is cut: rare
        names = [said.get(step, "") for step in range(first, last + 1)]
        best = max(set(names), key=names.count) if names else ""
        return best if best and names.count(best) * 2 > len(names) else ""

    def finish(self) -> None:
        """The stream has ended: a performance still going is kept (or its kept episode
        grown) as if the person had stopped."""
        record = self._last_record
        if record is None:
            return
        if self._growing:
            grown = self.grower.end()
            if grown is not None:
                self._keep(record, grown, "grower", self._growing)
        episode = self.cutter.end()
        if episode is not None:
            self._keep(record, episode, "cutter")

    def __call__(self, record) -> None:
        self._last_record = record
        truth = getattr(record, "truth", None)
        shown = truth.get("pattern", "") if isinstance(truth, dict) else ""
        if shown:
            self._shown.append((record.step, str(shown)))  # the oldest fall off the end
        hands = self.hands_of(record) if self.hands_of is not None else None
        grown = self._grow(record, hands)
        if grown is not None:
            self._keep(record, grown, "grower", self._growing)
        episode = self.cutter.observe(
            record.step,
            record.observed,
            getattr(record, "novelty", ""),
            hands,
            getattr(record, "repeating", 0),
        )
        text = self.cutter.status.describe()
        if episode is None:
            if text != self._last_text and self.cutter.status.state == RECORDING:
                self.events.append(TeachingEvent(record.step, "recording", text))
            self._last_text = text
            return
        self._last_text = text
        self._keep(record, episode, "cutter")

    def _keep(self, record, episode, cutter: str, grows: str = "") -> None:
        """A movement ``cutter`` returned: stored, or the growth of the one it kept last."""
        if episode.extends:
            self._extend(record, episode, self._last_kept.get(cutter))
        else:
            self._last_kept[cutter] = self._store(record, episode, grows)

    def _extend(self, record, episode, episode_id: int | None) -> None:
        """The episode ``episode_id`` grown to ``episode``, while it is still only kept and no
        consolidation is learning it."""
        if episode_id is None or episode_id in self.learning:
            return
        try:
            kept = self.memory.episode(episode_id)
            # The same movement up to the first cycle unlike the kept one: the detector still
            # says novel for a few steps after the person switches to another movement.
            count = same_cycles(episode.sensory, episode.cycles, kept.sensory, self.recognition)
            if count <= kept.summary.n_cycles:
                return
            stop = episode.cycles[count - 1][1]
            episode = replace(
                episode,
                sensory=episode.sensory[:stop],
                motor=episode.motor[:stop],
                n_cycles=count,
                last_step=episode.first_step + stop - 1,
                cycles=episode.cycles[:count],
            )
            unsafe = self._unsafe(episode.motor)
            if unsafe:  # the kept episode stays as it is
                self.events.append(TeachingEvent(record.step, "refused", unsafe))
                return
            summary = kept.summary
            steps = f"steps {episode.first_step}-{episode.last_step}"
            note = re.sub(r"^steps \d+-\d+", steps, summary.note)
            if not self.memory.regrow(
                episode_id, episode.sensory, episode.motor, episode.n_cycles, note
            ):
                return
        except RnnpbError as error:
            self.events.append(TeachingEvent(record.step, "refused", str(error)))
            return
        size = f"{episode.n_cycles} cycles, {len(episode.sensory)} steps"
        self.events.append(
            TeachingEvent(
                record.step,
                "extended",
                f"kept more of {summary.pattern}'s performance ({size})",
                episode_id,
                summary.pattern,
            )
        )

    def _grow(self, record, hands):
        """One step of the grower: the performance of a taught pattern it cuts, or None."""
        error = getattr(record, "prediction_error", float("nan"))
        self._errors.append(float(error))
        recognised = getattr(record, "recognised", None)
        if recognised not in self.taught:
            if self._growing:
                self.grower.reset()
                self._growing = ""
            return None
        if recognised != self._growing:  # another pattern: another performance
            self.grower.reset()
            self._growing = str(recognised)
        errors = np.sqrt(np.asarray(self._errors))
        locked = len(errors) == LOCK_STEPS and bool(np.all(errors < LOCK_ERROR))
        word = "familiar" if locked else "novel"
        return self.grower.observe(record.step, record.observed, word, hands)

    def _store(self, record, episode, grows: str = "") -> int | None:
        """Store a cut episode: under ``grows`` (a taught pattern it is more data for), else
        merged with the movement it repeats, else as a new movement; its id, or None when
        refused."""
        unsafe = self._unsafe(episode.motor)
        if unsafe:
            # Never learned: the network would learn to command it. The retargeting makes safe
            # angles, so this guards a mapping that was changed or bypassed.
            self.events.append(TeachingEvent(record.step, "refused", unsafe))
            return None
        shown_as = self._shown_as(episode.first_step, episode.last_step)
        note = f"steps {episode.first_step}-{episode.last_step}" + (
            f"; {SHOWN_AS}{shown_as}" if shown_as else ""
        )
        try:
            repeat = None if grows else find_repeat(self.memory, episode.sensory, self.recognition)
            pattern = grows or (repeat.pattern if repeat is not None else self.next_pattern_name())
            if grows:
                note += f"; {GROWS}{grows} (recognised, not followed closely)"
            elif repeat is not None:
                note += f"; {MERGED_WITH}{repeat.episode_id} ({repeat.describe()})"
            episode_id = self.memory.add_episode(
                episode.sensory,
                episode.motor,
                source=self.source,
                model=self.model,
                pattern=pattern,
                n_cycles=episode.n_cycles,
                note=note,
            )
            performances = len(self.memory.group(pattern))
        except RnnpbError as error:
            self.events.append(TeachingEvent(record.step, "refused", str(error)))
            return None
        self.kept.append(episode_id)
        size = f"{episode.n_cycles} cycles, {len(episode.sensory)} steps"
        text = (
            f"kept a performance of {pattern} the robot did not follow closely ({size}): "
            f"more data for it"
            if grows
            else f"kept a new movement as {pattern} ({size})"
            if repeat is None
            else f"kept another performance of {pattern} ({size}; merged with episode "
            f"{repeat.episode_id}, {repeat.describe()}): seen {times(performances)}"
        )
        self.events.append(
            TeachingEvent(
                record.step,
                "kept",
                text,
                episode_id,
                pattern,
                None if repeat is None else repeat.episode_id,
                performances,
            )
        )
        return episode_id

    def _unsafe(self, motor: np.ndarray) -> str:
        """Why the episode's joint angles must not be learned (a collision or a step faster
        than the servos, by the robot's own checker), or ""."""
        if self._checker is None:
            self._checker = SafetyChecker(SafetyLimits(dt=self.cutter.mapping.dt))
        result = self._checker.check(motor)
        refused = result.kinds[:, 0] | result.kinds[:, 1]
        if not refused.any():
            return ""
        k = int(refused.argmax())
        return (
            f"not kept: step {k} of the movement is unsafe for the robot ({result.reasons[k]}); "
            f"{int(refused.sum())} of {len(refused)} steps"
        )


def tracked_hands(source):
    """For :class:`EpisodeKeeper`'s ``hands_of``: the 3-D hands the source knows for the step
    just read — a camera's tracker (depth from the balls' size or the pose model, unfiltered:
    on-line there is no later frame to filter with), or motion capture (``last_hands``) — or
    None when it knows none."""
    inner = getattr(source, "inner", source)  # a FrameStepSource keeps the camera inside

    def hands_of(record) -> np.ndarray | None:
        if hasattr(inner, "last_hands"):
            return inner.last_hands
        result = getattr(inner, "last_result", None)
        return None if result is None else result.hands_3d

    return hands_of
