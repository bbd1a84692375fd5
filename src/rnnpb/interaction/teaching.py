"""Teaching by showing, on-line: the :class:`Teacher` keeps a new movement out of the
interaction's stream, consolidates it into the model in the background and swaps the new model
version in between two steps (docs/teaching.md).

It composes parts of one job each:

- :mod:`rnnpb.interaction.episodes`: the episode cutter (:class:`EpisodeCutter`, pure
  bookkeeping on each step's novelty word) and its :class:`TeachingConfig`;
- :mod:`rnnpb.interaction.keeper`: the memory keeper (:class:`EpisodeKeeper`), which stores
  each cut movement as an episode of the short-term memory;
- :mod:`rnnpb.interaction.background`: the consolidation in a spawned process
  (:class:`BackgroundConsolidation`, with the policy
  :func:`rnnpb.model.consolidation_config` for ``"teach"``) and the new version's mirror
  system compiled in a thread (:class:`PreparedMirror`);
- the model file's renaming: :meth:`rnnpb.model.TrainedModel.renamed`;
- :mod:`rnnpb.interaction.settings`: a ``--config`` file's tables over the cutter's and the
  consolidation policy's values (:class:`ConfigTables`).
"""

from __future__ import annotations

import os
import re
import time
from pathlib import Path
from typing import TYPE_CHECKING

from rnnpb.demonstrator import MirrorMapping
from rnnpb.errors import ConfigError
from rnnpb.interaction.background import (
    BackgroundConsolidation,
    ConsolidationState,
    PreparedMirror,
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
    shown_as,
    tracked_hands,
)
from rnnpb.interaction.settings import ConfigTables

if TYPE_CHECKING:
    from rnnpb.model.consolidation import ConsolidationConfig

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
    "KeptMovement",
    "PreparedMirror",
    "Teacher",
    "TeachingConfig",
    "TeachingEvent",
    "episode_steps",
    "shown_as",
    "tracked_hands",
    "version_path",
]


def version_path(model_path: str | os.PathLike[str], version: int) -> Path:
    """The file of a model's version ``version``: ``model.npz`` → ``model.v2.npz`` (the
    original is version 1; a version's own file name gives the same family)."""
    path = Path(model_path)
    stem = re.sub(r"\.v\d+$", "", path.name.removesuffix(".npz"))
    return path.with_name(f"{stem}.v{int(version)}.npz")


class Teacher:
    """On-line teaching in the interaction loop (docs/teaching.md).

    Subscribe it to the loop (it keeps novel movements as episodes) and pass
    :meth:`between_steps` to ``loop.run``: there it starts a consolidation in the background
    once an episode is kept (``auto``, else on :meth:`confirm`), swaps the new model version in
    between two steps when it is done, and keeps every version for :meth:`undo`. With
    ``wait`` (a run as fast as possible) it blocks until each consolidation finishes, so a
    scripted run repeats; paced it never waits, and with ``prepare`` (paced: the default) the
    new version's mirror system is built and its step compiled in a thread before the swap,
    so the swap itself costs no deadline.

    ``config`` (default ``TeachingConfig()``) says when a movement is kept; ``iterations``
    (default: the policy's) how long each consolidation learns; ``tables``, a ``--config``
    file's, changes both: ``[teaching.cutter]`` the config's tuned values, ``[teaching]`` and
    ``[consolidation]`` the policy each consolidation takes (:meth:`consolidation`).
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
        tables: ConfigTables | None = None,
    ) -> None:
        self.iterations = iterations
        self.tables = tables or ConfigTables()
        config = self.tables.teaching(config or TeachingConfig())
        self.loop = loop
        self.memory = memory
        self.make_mirror = make_mirror
        self.versions: list[str] = [str(model_path)]
        # Taught joint angles are retargeted at the loop's step time (the servo's speed limit).
        mapping = MirrorMapping(dt=loop.config.dt)
        self.keeper = EpisodeKeeper(memory, str(model_path), source, config, hands_of, mapping)
        self.auto = auto
        self.wait = (not loop.config.paced) if wait is None else wait
        # Paced, a new version's mirror system is built and its step compiled in a thread
        # before the swap (seconds: a step's deadline would be missed if it happened between
        # two steps); as fast as possible, on the loop's thread, so that a run repeats.
        self.prepare = (not self.wait) if prepare is None else prepare
        self._prepared: PreparedMirror | None = None
        self.job: BackgroundConsolidation | None = None
        self.pending: list[int] = []
        self.events = self.keeper.events
        self.swapped_at: list[int] = []
        loop.subscribe(self._on_step)

    @property
    def model_path(self) -> str:
        return self.versions[-1]

    def _on_step(self, record) -> None:
        before = len(self.keeper.kept)
        self.keeper.model = self.model_path
        self.keeper(record)
        self.pending.extend(self.keeper.kept[before:])
        if self.auto and self.pending and self.job is None:
            self.confirm()

    def consolidation(self, model) -> ConsolidationConfig:
        """The consolidation a confirmed episode of ``model`` runs (in its own process)."""
        return teaching_consolidation(
            model, self.iterations, self.tables.consolidation, self.tables.origin
        )

    def confirm(self) -> None:
        """Start consolidating the pending episodes (the person said yes)."""
        if self.job is not None or not self.pending:
            return
        number = len(self.versions) + 1
        out = version_path(self.model_path, number)
        while out.exists():  # a version an earlier run wrote: never overwritten
            number += 1
            out = version_path(self.model_path, number)
        ids, self.pending = self.pending, []
        self.job = BackgroundConsolidation(
            self.model_path,
            self.memory.path,
            ids,
            out,
            self.iterations,
            self.tables.consolidation,
            self.tables.origin,
        )
        self.events.append(
            TeachingEvent(
                self.loop.steps,
                "consolidating",
                f"consolidating {len(ids)} episode(s) into {out.name}",
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
        self.swapped_at.append(self.loop.steps)
        learned = ", ".join(p for p in model.patterns if p.startswith("new-")) or "?"
        self.events.append(
            TeachingEvent(
                self.loop.steps,
                "learned",
                f"learned as pattern {learned} "
                f"({state.seconds:.0f} s, {Path(state.model_path).name})",
            )
        )

    def _use(self, mirror) -> None:
        """Swap ``mirror`` in between two steps, continuing the running interaction (its
        window, PB and what it has seen): the robot's command goes on smoothly."""
        running = self.loop.mirror
        carry_on = getattr(mirror, "continue_from", None)  # the NumPy twin starts afresh
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
            self._use(self.make_mirror(renamed))
        for episode in episodes:
            self.memory.rename(episode.id, name)
        self.events.append(
            TeachingEvent(self.loop.steps, "renamed", f"renamed pattern {pattern} to {name}")
        )
