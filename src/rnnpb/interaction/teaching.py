"""Teaching by showing, on-line: the :class:`Teacher` keeps a new movement out of the
interaction's stream, consolidates it into the model in the background and swaps the new model
version in between two steps (docs/teaching.md).

It composes parts of one job each:

- :mod:`rnnpb.interaction.episodes`: the episode cutter (:class:`EpisodeCutter`, pure
  bookkeeping on each step's novelty word) and its :class:`TeachingConfig`;
- :mod:`rnnpb.interaction.repeats`: whether a kept movement repeats one the memory holds
  (:func:`find_repeat`, by shape), so that it is merged with it rather than kept anew;
- :mod:`rnnpb.interaction.keeper`: the memory keeper (:class:`EpisodeKeeper`), which stores
  each cut movement as an episode of the short-term memory;
- :mod:`rnnpb.interaction.background`: the consolidation in a spawned process
  (:class:`BackgroundConsolidation`, with the policy
  :func:`rnnpb.model.consolidation_config` for ``"teach"``) and the new version's mirror
  system compiled in a thread (:class:`PreparedMirror`);
- the model file's renaming: :meth:`rnnpb.model.TrainedModel.renamed`;
- a ``--config`` file (:class:`rnnpb.presets.Overrides`), handed as it is to the cutter's
  config (:meth:`TeachingConfig.overridden`) and to each consolidation's policy.
"""

from __future__ import annotations

import os
import re
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from rnnpb.demonstrator import MirrorMapping, UserBody
from rnnpb.errors import ConfigError
from rnnpb.interaction.background import (
    BackgroundConsolidation,
    ConsolidationState,
    PreparedMirror,
    start_process_server,
    teaching_consolidation,
)
from rnnpb.interaction.episodes import (
    CUTTER_STATES,
    KEPT,
    RECORDING,
    WATCHING,
    CutterStatus,
    EpisodeCutter,
    KeptMovement,
    TeachingConfig,
)
from rnnpb.interaction.keeper import (
    SHOWN_AS,
    EpisodeKeeper,
    TeachingEvent,
    episode_steps,
    merged_with,
    shown_as,
    times,
    tracked_hands,
)
from rnnpb.interaction.repeats import Repeat, find_repeat, shape_distance
from rnnpb.learning_phase import placed_body

if TYPE_CHECKING:
    from rnnpb.model.consolidation import ConsolidationConfig
    from rnnpb.presets import Overrides

__all__ = [
    "CUTTER_STATES",
    "KEPT",
    "RECORDING",
    "SHOWN_AS",
    "WATCHING",
    "BackgroundConsolidation",
    "ConsolidationState",
    "CutterStatus",
    "EpisodeCutter",
    "EpisodeKeeper",
    "PERFORMANCES",
    "KeptMovement",
    "PreparedMirror",
    "Repeat",
    "Teacher",
    "TeachingConfig",
    "TeachingEvent",
    "episode_steps",
    "find_repeat",
    "merged_with",
    "shape_distance",
    "shown_as",
    "tracked_hands",
    "version_path",
]


PERFORMANCES = 2
"""Performances of a new movement the teacher waits for before learning it: a pattern
learned from one short take predicts that movement's next performance poorly; from two that
differ it learns what varies."""


def version_path(model_path: str | os.PathLike[str], version: int) -> Path:
    """The file of a model's version ``version``: ``model.npz`` → ``model.v2.npz`` (the
    original is version 1; a version's own file name gives the same family)."""
    path = Path(model_path)
    stem = re.sub(r"\.v\d+$", "", path.name.removesuffix(".npz"))
    return path.with_name(f"{stem}.v{int(version)}.npz")


class Teacher:
    """On-line teaching in the interaction loop (docs/teaching.md).

    Subscribe it to the loop (it keeps novel movements as episodes, a repeat of a kept one
    merged with it) and pass :meth:`between_steps` to ``loop.run``: there it starts a
    consolidation in the background once a movement is ready (``auto``, else on
    :meth:`confirm`), swaps the new model version in between two steps when it is done, and
    keeps every version for :meth:`undo`.

    A new movement is ready when it has been seen ``performances`` times (default
    :data:`PERFORMANCES`: a pattern learned from one short take predicts the next performance
    poorly); until then the teacher says how many it has and waits for the next one.
    :meth:`confirm` (the person insists) learns what is kept, even from one performance, and
    so does ``performances=1``. A performance of a pattern teaching learned already is more
    data for it: ready at once, consolidated into that pattern. With
    ``wait`` (a run as fast as possible) it blocks until each consolidation finishes, so a
    scripted run repeats; paced it never waits, and with ``prepare`` (paced: the default) the
    new version's mirror system is built and its step compiled in a thread before the swap,
    so the swap itself costs no deadline.

    ``config`` (default ``TeachingConfig()``) says when a movement is kept; ``iterations``
    (default: the policy's) how long each consolidation learns; ``overrides``, a ``--config``
    file, changes both: ``[teaching.cutter]`` the config's tuned values, ``[teaching]`` and
    ``[consolidation]`` the policy each consolidation takes (:meth:`consolidation`).
    ``framing`` (metres; None: the standard user's place) is where the 3-D hands a source gives
    of a person's body stand: the model's framing (:mod:`rnnpb.learning_phase`).
    """

    def __init__(
        self,
        loop,
        model_path: str | os.PathLike[str],
        memory,
        *,
        make_mirror,
        source: str = "",
        config: TeachingConfig | None = None,
        auto: bool = True,
        wait: bool | None = None,
        hands_of=None,
        iterations: int | None = None,
        prepare: bool | None = None,
        overrides: Overrides | None = None,
        performances: int = PERFORMANCES,
        framing: float | None = None,
    ) -> None:
        if performances < 1:
            raise ConfigError(f"performances must be >= 1, got {performances}")
        self.performances = performances
        self.iterations = iterations
        self.overrides = overrides
        config = (config or TeachingConfig()).overridden(overrides)
        self.loop = loop
        self.memory = memory
        self.make_mirror = make_mirror
        self.versions: list[str] = [str(model_path)]
        # Taught joint angles are retargeted at the loop's step time (the servo's speed limit),
        # from 3-D hands of a person framed as the model frames one.
        body = UserBody() if framing is None else placed_body(framing)
        mapping = MirrorMapping(body, dt=loop.config.dt)
        self.keeper = EpisodeKeeper(memory, str(model_path), source, config, hands_of, mapping)
        self.auto = auto
        self.wait = (not loop.config.paced) if wait is None else wait
        # Paced, a new version's mirror system is built and its step compiled in a thread
        # before the swap (seconds: a step's deadline would be missed if it happened between
        # two steps); as fast as possible, on the loop's thread, so that a run repeats.
        self.prepare = (not self.wait) if prepare is None else prepare
        self._prepared: PreparedMirror | None = None
        self.job: BackgroundConsolidation | None = None
        self._job_patterns: tuple[str, ...] = ()
        self._job_episodes: frozenset[int] = frozenset()
        self._patterns: dict[str, tuple[str, ...]] = {}  # a version's file -> its patterns
        self.pending: list[int] = []
        self._look = False  # whether a pending movement may have become ready
        self.events = self.keeper.events
        self.swapped_at: list[int] = []
        loop.subscribe(self._on_step)
        # The consolidations' process server imports JAX now, beside the loop, so that the
        # first consolidation does not wait for it.
        start_process_server()

    @property
    def model_path(self) -> str:
        return self.versions[-1]

    def _on_step(self, record) -> None:
        self._watch(lambda: self.keeper(record))

    def finish(self) -> None:
        """The stream has ended (a file or scenario source): a performance still going is
        kept, or its kept episode grown, as if the person had stopped; and learned when that
        makes it ready, as on a step."""
        self._watch(self.keeper.finish)

    def _watch(self, observe: Callable[[], None]) -> None:
        """``observe`` (the keeper watching a step, or the stream's end), then what it kept."""
        before = len(self.keeper.kept)
        self.keeper.model = self.model_path
        self.keeper.recognition = getattr(self.loop.mirror, "recognition", None)
        self.keeper.cutter.learned = getattr(self.loop.mirror, "learned_shape", None)
        self.keeper.taught = self.taught_patterns()
        # A running consolidation learns its episodes as they were: they do not grow.
        self.keeper.learning = self._job_episodes if self.job is not None else frozenset()
        observe()
        new = self.keeper.kept[before:]
        self.pending.extend(new)
        if new:
            self._say_waiting()
            self._look = True
        # What is ready changes only with a new episode or a new version (reads the memory).
        if self.auto and self.job is None and self._look:
            self._look = False
            self._start(self.ready())

    def learned_patterns(self, path: str | None = None) -> tuple[str, ...]:
        """The patterns of the running version (or of the version file ``path``)."""
        path = self.model_path if path is None else path
        if path not in self._patterns:
            from rnnpb.model import TrainedModel

            self._patterns[path] = TrainedModel.load(path).patterns
        return self._patterns[path]

    def taught_patterns(self) -> frozenset[str]:
        """The patterns teaching learned: in the running version, not in the first."""
        if len(self.versions) == 1:
            return frozenset()
        return frozenset(self.learned_patterns()) - set(self.learned_patterns(self.versions[0]))

    def _groups(self) -> dict[str, list[int]]:
        """The pending episodes by movement (pattern name), in the order they were kept."""
        names = {e.id: e.pattern for e in self.memory.episodes("kept")}
        groups: dict[str, list[int]] = {}
        for episode_id in self.pending:
            if episode_id in names:
                groups.setdefault(names[episode_id], []).append(episode_id)
        return groups

    def ready(self) -> list[int]:
        """The pending episodes a consolidation would learn now: those of a movement seen
        ``performances`` times, or of a pattern the running version holds."""
        learned = set(self.learned_patterns())
        return [
            episode_id
            for pattern, ids in self._groups().items()
            if pattern in learned or len(self.memory.group(pattern)) >= self.performances
            for episode_id in ids
        ]

    def waiting_for_confirm(self) -> bool:
        """Some movement is ready and waits for :meth:`confirm` (not ``auto``)."""
        return not self.auto and self.job is None and bool(self.pending) and bool(self.ready())

    def _say_waiting(self) -> None:
        """Say how many performances each pending new movement has: "seen once: show it
        again", or "seen twice: learn it now?" when it waits for the person's Confirm."""
        learned = set(self.learned_patterns())
        for pattern, ids in self._groups().items():
            if pattern in learned:
                continue
            count = len(self.memory.group(pattern))
            if count < self.performances:
                more = self.performances - count
                text = (
                    f"{pattern} seen {times(count)}: show it "
                    f"{'again' if more == 1 else f'{more} more times'} to learn it "
                    "(or confirm to learn it from what was seen)"
                )
            elif self.auto:
                continue  # learned now: the consolidating event says so
            else:
                text = f"{pattern} seen {times(count)}: learn it now?"
            self.events.append(
                TeachingEvent(self.loop.steps, "waiting", text, ids[-1], pattern, None, count)
            )

    def consolidation(self, model) -> ConsolidationConfig:
        """The consolidation a confirmed episode of ``model`` runs (in its own process)."""
        return teaching_consolidation(model, self.iterations, self.overrides)

    def confirm(self) -> None:
        """Start consolidating every pending episode (the person said yes): a movement seen
        fewer than ``performances`` times is learned from what was seen."""
        if self.job is not None or not self.pending:
            return
        self._start(list(self.pending))

    def _start(self, ids: list[int]) -> None:
        """Consolidate the pending episodes ``ids`` in the background."""
        if self.job is not None or not ids:
            return
        number = len(self.versions) + 1
        out = version_path(self.model_path, number)
        while out.exists():  # a version an earlier run wrote: never overwritten
            number += 1
            out = version_path(self.model_path, number)
        self.pending = [i for i in self.pending if i not in ids]
        self._job_episodes = frozenset(ids)
        names = {e.id: e.pattern for e in self.memory.episodes()}
        self._job_patterns = tuple(dict.fromkeys(names.get(i, "?") for i in ids))
        self.job = BackgroundConsolidation(
            self.model_path,
            self.memory.path,
            ids,
            out,
            self.iterations,
            self.overrides,
        )
        self.events.append(
            TeachingEvent(
                self.loop.steps,
                "consolidating",
                f"consolidating {len(ids)} episode(s) into {out.name}",
                pattern=", ".join(self._job_patterns),
            )
        )

    def between_steps(self, wait_s: float) -> None:
        start = time.perf_counter()
        if self.job is not None:
            state = self.job.wait() if self.wait else self.job.poll()
            if state.state == "done" and self.prepare:
                prepared = self._prepared
                if prepared is None or prepared.path != state.model_path:
                    self._prepared = PreparedMirror(state.model_path, self.make_mirror)
                elif prepared.done:
                    self._prepared = None
                    self._swap(state, prepared)
            elif state.state == "done":
                self._swap(state)
            elif state.state == "failed":
                self.events.append(TeachingEvent(self.loop.steps, "failed", state.describe()))
                self.job = None
                self._job_patterns = ()
                self._look = bool(self.pending)
        rest = wait_s - (time.perf_counter() - start)
        if rest > 0:
            time.sleep(min(rest, 0.02))

    def _swap(self, state: ConsolidationState, prepared: PreparedMirror | None = None) -> None:
        from rnnpb.model import TrainedModel

        assert self.job is not None
        self.job = None
        if prepared is not None and prepared.model is not None and prepared.mirror is not None:
            model = prepared.model
            self._use(prepared.mirror)
        else:  # not prepared (or its preparation failed): built here, as fast runs do
            model = TrainedModel.load(state.model_path)
            self._use(self.make_mirror(model))
        self.versions.append(state.model_path)
        self._patterns[state.model_path] = model.patterns
        self._look = bool(self.pending)
        self.swapped_at.append(self.loop.steps)
        names = [p for p in self._job_patterns if p in model.patterns]
        learned = ", ".join(names) or "?"
        counts = ", ".join(times(len(self.memory.group(p))) for p in names)
        self.events.append(
            TeachingEvent(
                self.loop.steps,
                "learned",
                f"learned as pattern {learned} "
                f"(seen {counts or 'as kept'}; "
                f"{state.seconds:.0f} s, {Path(state.model_path).name})",
                pattern=learned,
            )
        )
        self._job_patterns = ()

    def _use(self, mirror) -> None:
        """Swap ``mirror`` in between two steps, continuing the running interaction (its
        window, PB and what it has seen): the robot's command goes on smoothly."""
        running = self.loop.mirror
        carry_on = getattr(mirror, "continue_from", None)  # a mirror without it starts afresh
        if running is not None and running is not mirror and carry_on is not None:
            carry_on(running)
        self.loop.mirror = mirror

    def undo(self) -> None:
        """Go back to the previous model version (the newer file stays on disk)."""
        from rnnpb.model import TrainedModel

        if len(self.versions) < 2:
            return
        undone = self.versions.pop()
        self._use(self.make_mirror(TrainedModel.load(self.model_path)))
        # What that version learned is kept again, not learned: a Confirm learns it again
        # (never at once, even with ``auto``: the person has just said no to it).
        again = self.memory.unlearn(undone)
        kept = f"; episode{'s' if len(again) > 1 else ''} {', '.join(map(str, again))} kept again"
        self.events.append(
            TeachingEvent(
                self.loop.steps,
                "undone",
                f"back to {Path(self.model_path).name}{kept if again else ''}",
            )
        )

    def rename(self, pattern: str, name: str) -> None:
        """Call ``pattern`` ``name``: a pattern the teacher learned (in the running version,
        not in the first one) is renamed in that version's file
        (:meth:`~rnnpb.model.TrainedModel.renamed`) and the new model swapped in; the
        memory's episodes of that name are renamed too (a kept episode not learned yet is then
        consolidated under its new name)."""
        from rnnpb.model import TrainedModel
        from rnnpb.sequences import pattern_name_problem

        if self.job is not None:
            raise ConfigError("a consolidation is running: rename once it has finished")
        problem = pattern_name_problem(name)
        if problem:
            raise ConfigError(f"pattern name {name!r} {problem}")
        model = TrainedModel.load(self.model_path)
        episodes = [e for e in self.memory.episodes() if e.pattern == pattern]
        taught = (
            pattern in model.patterns
            and pattern not in TrainedModel.load(self.versions[0]).patterns
        )
        if not taught and not episodes:
            raise ConfigError(f"no pattern {pattern!r} was learned or kept by teaching")
        if name in model.patterns or any(e.pattern == name for e in self.memory.episodes()):
            raise ConfigError(f"the name {name!r} is taken")
        if taught:
            renamed = model.renamed(pattern, name)
            renamed.save(self.model_path)
            self._patterns.pop(self.model_path, None)  # the same file, new names
            self._use(self.make_mirror(renamed))
        for episode in episodes:
            self.memory.rename(episode.id, name)
        self.events.append(
            TeachingEvent(self.loop.steps, "renamed", f"renamed pattern {pattern} to {name}")
        )
