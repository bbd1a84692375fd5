"""Teaching by showing in the dashboard: the session's :class:`~rnnpb.interaction.teaching.
Teacher`, its short-term memory and its model versions (docs/dashboard.md, "Teaching").

Everything here runs on the session thread, between two steps or in a step subscriber, and
nothing blocks: the consolidation runs in the Teacher's spawned process, and a new version's
on-line step (whose first call compiles for the new number of patterns: seconds, tens of
seconds on a loaded machine) is built and compiled in a thread of its own before the version
is swapped in, so the paced loop keeps its deadlines. The state sent to the pages is computed
here too, from the memory read on this thread only (an SQLite connection belongs to the
thread that opened it).
"""

from __future__ import annotations

import datetime
import logging
import shutil
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from rnnpb.errors import ConfigError, RnnpbError
from rnnpb.interaction.teaching import TeachingConfig, merged_with, shown_as
from rnnpb.web._models import ModelShelf, ReadyModel, make_ready
from rnnpb.web._protocol import TEACH_MODES

log = logging.getLogger("rnnpb.web")

SHOWN_EPISODES = 20
"""Newest episodes of the memory listed in the panel."""
SHOWN_EVENTS = 30


@dataclass(frozen=True)
class TeachingSettings:
    """How the dashboard teaches (``rnnpb serve --teach``, ``--consolidation-iterations``,
    ``--teach-dir``).

    Attributes
    ----------
    mode : str
        ``confirm`` (default): new movements are kept in the short-term memory and consolidated
        when the person presses Confirm; ``auto``: consolidated as soon as one is kept;
        ``off``: nothing is kept. The page can change it.
    iterations : int, optional
        Learning iterations of each consolidation (default: the consolidation policy's for
        teaching, :func:`rnnpb.model.consolidation.consolidation_config`).
    folder : path, optional
        Where a model shipped inside the package is copied to learn from (its memory and new
        versions beside the copy). Default: the session's folder, ``WORKDIR/taught`` (a
        temporary folder unless the server was given one).
    config : TeachingConfig
        When a novel movement is kept.
    """

    mode: str = "confirm"
    iterations: int | None = None
    folder: Path | None = None
    config: TeachingConfig = field(default_factory=TeachingConfig)

    def __post_init__(self) -> None:
        if self.mode not in TEACH_MODES:
            raise ConfigError(f"teaching mode must be one of {', '.join(TEACH_MODES)}")
        if self.iterations is not None and self.iterations < 1:
            raise ConfigError(f"consolidation iterations must be >= 1, got {self.iterations}")


class TeachingHost(Protocol):
    """What teaching needs of the session it teaches in."""

    @property
    def loop(self) -> Any:
        """The run's :class:`~rnnpb.interaction.InteractionLoop` (a Reset makes a new one), or
        None before the first run."""
        ...

    @property
    def mode(self) -> str:
        """Who drives: ``demonstrator``, ``pointer`` or ``webcam``."""
        ...

    @property
    def shelf(self) -> ModelShelf:
        """The models offered and the one running."""
        ...

    @property
    def workdir(self) -> Path: ...

    @property
    def temporary_workdir(self) -> bool:
        """Whether ``workdir`` is deleted when the server stops."""
        ...

    def hands_3d(self) -> np.ndarray | None:
        """The webcam's last hands in 3-D (None unless the webcam drives)."""
        ...

    def swap(self, ready: ReadyModel) -> None:
        """Run ``ready`` from the next step on, the loop going on with it."""
        ...

    def report(self, text: str) -> None:
        """Say ``text`` on every page as an error (and in the log)."""
        ...

    def publish_state(self) -> None: ...


class _LoopView:
    """The loop as the Teacher sees it: the session's current loop (a Reset makes a new one,
    the Teacher and its versions stay), its step subscription held by the session (so that
    teaching can be turned off), and its mirror swaps going through the session."""

    def __init__(self, teaching: SessionTeaching) -> None:
        self._teaching = teaching
        self.on_step = None

    @property
    def config(self):
        from rnnpb.interaction import LoopConfig

        loop = self._teaching.host.loop
        return loop.config if loop is not None else LoopConfig(paced=True)

    @property
    def steps(self) -> int:
        loop = self._teaching.host.loop
        return loop.steps if loop is not None else 0

    def subscribe(self, callback):
        self.on_step = callback
        return lambda: None

    @property
    def mirror(self):
        running = self._teaching.host.shelf.running
        return running.mirror if running is not None else None

    @mirror.setter
    def mirror(self, mirror) -> None:
        self._teaching.use(mirror)


class _Prepared:
    """A model version made ready off the session thread (:func:`make_ready`: loaded, its
    safety, its mirror system compiled); ``error`` says why not."""

    def __init__(self, shelf: ModelShelf, path: str) -> None:
        self.path = path
        self.result: ReadyModel | None = None
        self.error: str | None = None
        self._overrides, self._safety = shelf.overrides, shelf.safety_enabled
        self.thread = threading.Thread(target=self._run, name="rnnpb-prepare", daemon=True)
        self.thread.start()

    def _run(self) -> None:
        try:
            self.result = make_ready(self.path, self._overrides, self._safety)
        except Exception as error:  # noqa: BLE001 - reported, the swap builds it instead
            self.error = f"{type(error).__name__}: {error}"

    @property
    def done(self) -> bool:
        return not self.thread.is_alive()


class SessionTeaching:
    """The dashboard session's teaching: one :class:`Teacher` per model chosen.

    Parameters
    ----------
    host : TeachingHost
        The session.
    settings : TeachingSettings
    """

    def __init__(self, host: TeachingHost, settings: TeachingSettings) -> None:
        self.host = host
        self.settings = settings
        self.mode = settings.mode
        self.teacher = None
        self.memory = None
        self.unavailable: str | None = None
        self.failure: str | None = None
        self.result = ""
        self.events: list[dict[str, Any]] = []
        self.folder_note = ""
        self._view = _LoopView(self)
        self._said = 0
        self._first_name = ""  # the name the first version was chosen under
        self._mirrors: dict[str, ReadyModel] = {}  # model fingerprint -> the version ready
        self._prepared: _Prepared | None = None
        self._version_patterns: dict[str, list[str]] = {}
        self._lists: dict[str, Any] = {"episodes": [], "pending": 0}
        self._shapes: dict[str, str] = {}  # demonstrator shape -> the pattern it was learned as
        self._started_at = 0.0
        self._pending_use: ReadyModel | None = None
        self._kept: dict[str, list[int]] = {}  # kept movement -> its episodes, oldest first
        self._learning: set[str] = set()  # the movements a consolidation is learning
        # Every version this teaching has run (undone ones too: the model list offers them),
        # in the order learned, and the name the model list gives each.
        self._versions: list[str] = []
        self._names: dict[str, str] = {}

    # --- life cycle -----------------------------------------------------------------------
    def open(self, ready: ReadyModel, name: str = "") -> None:
        """Start teaching the model ``ready`` runs (offered as ``name``): learn from a copy
        when the file is the package's own, open its short-term memory. A memory that cannot
        be opened turns teaching off for this model with the reason; the robot runs on."""
        from rnnpb.interaction.teaching import Teacher
        from rnnpb.memory import MemoryStore, memory_path_for

        self.close()
        self._first_name = name
        self.unavailable = self.failure = None
        self.result = ""
        self.events = []
        self._said = 0
        self._mirrors = {ready.model.fingerprint: ready}
        try:
            path = self._learning_path(Path(ready.path))
            self.memory = MemoryStore(memory_path_for(path)).open()
        except (RnnpbError, OSError) as error:
            self.unavailable = f"teaching is off for this model: {error}"
            log.warning("%s", self.unavailable)
            return
        self._versions = [str(path)]
        self._names = {str(path): name or Path(ready.path).name}
        self._learning = set()
        self.teacher = Teacher(
            self._view,
            path,
            self.memory,
            make_mirror=self._mirror_for,
            source=self.host.mode,
            config=self.settings.config,
            auto=self.mode == "auto",
            wait=False,
            hands_of=self._hands_of,
            iterations=self.settings.iterations,
            prepare=False,  # made ready here (`_Prepared`), with the session's safety map
            overrides=self.host.shelf.overrides,
        )
        self._refresh()
        log.info("teaching: short-term memory %s (%s)", self.memory.path, self.mode)

    def close(self) -> None:
        teacher, self.teacher = self.teacher, None
        if teacher is not None and teacher.job is not None:
            teacher.job.cancel()
            log.info("teaching: the running consolidation was cancelled (model changed)")
        if self.memory is not None:
            self.memory.close()
            self.memory = None
        self._prepared = None

    def _learning_path(self, path: Path) -> Path:
        """The model file learning starts from: ``path``, or a copy of a shipped model (new
        versions and the memory are written beside it: never into the installed package)."""
        import rnnpb.models

        shipped = Path(rnnpb.models.__file__).resolve().parent
        if path.resolve().parent != shipped:
            self.folder_note = f"new versions are written beside {path.name}"
            return path
        folder = Path(self.settings.folder or self.host.workdir / "taught")
        folder.mkdir(parents=True, exist_ok=True)
        copy = folder / path.name
        if not copy.exists():
            shutil.copyfile(path, copy)
        temporary = self.settings.folder is None and self.host.temporary_workdir
        self.folder_note = f"learning from a copy of the shipped model in {folder}" + (
            " (a temporary folder, deleted when the server stops; rnnpb serve --teach-dir keeps it)"
            if temporary
            else ""
        )
        log.info("teaching: %s", self.folder_note)
        return copy

    def attach(self, loop) -> None:
        """Subscribe to a new loop (a Reset or a model change)."""
        loop.subscribe(self.on_step)

    # --- what the Teacher calls -----------------------------------------------------------
    def _mirror_for(self, model):
        """The Teacher's ``make_mirror``: a version made ready beforehand, a version seen
        before (undo), else one built now (a rename: the same shapes, compiled already)."""
        from rnnpb.model import MirrorSystem, OnlineConfig

        known = self._mirrors.get(model.fingerprint)
        if known is not None:
            known.mirror.reset()
            self._pending_use = known
            return known.mirror
        running = self.host.shelf.running
        safety = running.safety if running is not None else None
        online = safety.config if safety is not None else None
        options = safety.mirror_options if safety is not None else {}
        recognition = OnlineConfig.for_model(model, self.host.shelf.overrides).recognition
        mirror = MirrorSystem(model, online, recognition=recognition, **options)
        path = Path(self.teacher.model_path) if self.teacher is not None else Path()
        ready = ReadyModel(path, model, mirror, safety, running.risk if running else {})
        self._mirrors[model.fingerprint] = self._pending_use = ready
        return mirror

    def use(self, mirror) -> None:
        """Swap ``mirror`` in (between two steps): the session's model, mirror and safety
        map follow, the loop runs on with it."""
        ready = self._pending_use
        if ready is None or ready.mirror is not mirror:
            raise RuntimeError("teaching swapped in a mirror it did not make")
        self.host.swap(ready)

    def _hands_of(self, record):
        """3-D hands for the episode: the webcam's depth from the balls' size; the mouse and
        the demonstrator give none (their hands lie on the fixed plane)."""
        if self.host.mode != "webcam":
            return None
        return self.host.hands_3d()

    # --- each step, between steps ---------------------------------------------------------
    def on_step(self, record) -> None:
        teacher = self.teacher
        if teacher is None or self._view.on_step is None:
            return
        if self.mode == "off" or self._holding():
            teacher.keeper.cutter.reset()
        else:
            teacher.keeper.source = self.host.mode
            self._view.on_step(record)
        self._take_events()

    def _name_running(self) -> None:
        """The session names the version that runs (the status bar, the model list): the
        first version by the name it was chosen under, a learned one by its file's name
        (``set1.v2.npz``, as the model list names files), offered in the model list from
        then on (its file stays on disk)."""
        teacher, shelf = self.teacher, self.host.shelf
        if teacher is None:
            return
        if len(teacher.versions) == 1:
            shelf.name = self._first_name or shelf.name
            return
        path = teacher.model_path
        shelf.name = self._names[path] = shelf.offer(path)
        if path not in self._versions:
            self._versions.append(path)

    def _holding(self) -> bool:
        """Nothing more is kept while a movement seen often enough waits for Confirm or is
        being learned: the same movement, performed on, would otherwise be kept again and
        again (its run restarts whenever the detector hesitates). A movement seen fewer times
        waits for its next performance, which is kept and merged with it."""
        teacher = self.teacher
        if teacher is None:
            return False
        waiting = self.mode == "confirm" and teacher.waiting_for_confirm()
        return waiting or teacher.job is not None or self._prepared is not None

    def between_steps(self) -> None:
        """Follow the consolidation without waiting: when it is done, make the new version
        ready in a thread, then let the Teacher swap it in. A failure here is reported and
        never stops the robot."""
        try:
            self._follow()
        except Exception as error:  # noqa: BLE001 - the robot runs on
            log.exception("session: teaching failed")
            self.failure = f"teaching failed: {type(error).__name__}: {error}"
            self.host.report(f"{self.failure}; the running model stays")

    def _follow(self) -> None:
        teacher = self.teacher
        if teacher is None:
            return
        job = teacher.job
        if job is not None:
            state = job.poll()
            if state.state == "running":
                return
            if state.state == "done":
                prepared = self._prepared
                if prepared is None or prepared.path != state.model_path:
                    self._prepared = _Prepared(self.host.shelf, state.model_path)
                    return
                if not prepared.done:
                    return
                if prepared.result is not None:
                    self._mirrors[prepared.result.model.fingerprint] = prepared.result
                else:
                    log.warning("teaching: %s made ready: %s", state.model_path, prepared.error)
                self._prepared = None
        teacher.between_steps(0.0)
        self._take_events()

    def _take_events(self) -> None:
        teacher = self.teacher
        if teacher is None or len(teacher.events) == self._said:
            return
        news = teacher.events[self._said :]
        self._said = len(teacher.events)
        for event in news:
            if event.kind == "recording":
                continue
            entry = {
                "step": event.step,
                "kind": event.kind,
                "text": event.text,
                "time": datetime.datetime.now().strftime("%H:%M:%S"),
            }
            self.events = [*self.events, entry][-SHOWN_EVENTS:]
            if event.kind in ("failed", "refused"):
                self.failure = event.text
                log.warning("teaching: step %d: %s", event.step, event.text)
                self.host.report(f"teaching: {event.text}; the running model stays")
            else:
                log.info("teaching: step %d: %s", event.step, event.text)
            if event.kind in ("learned", "failed", "refused"):
                self._learning = set()
            if event.kind in ("learned", "undone"):
                self.failure = None
            if event.kind in ("learned", "undone", "renamed"):
                self._name_running()
                self.result = event.text
            elif event.kind == "renamed":
                # "learned as pattern new-1 (…)" goes on naming what the robot learned.
                old, new = event.text.removeprefix("renamed pattern ").split(" to ", 1)
                learned = f"learned as pattern {old} "
                self.result = (
                    self.result.replace(learned, f"learned as pattern {new} (renamed from {old}) ")
                    if self.result.startswith(learned)
                    else event.text
                )
            if event.kind == "consolidating":
                self._started_at = time.monotonic()
                self._learning = {p for p in (event.pattern or "").split(", ") if p}
        self._refresh()
        self.host.publish_state()

    # --- commands -------------------------------------------------------------------------
    def _need(self):
        if self.teacher is None:
            raise ConfigError(self.unavailable or "no model is loaded")
        return self.teacher

    def set_mode(self, mode: str) -> None:
        self.mode = mode
        if self.teacher is not None:
            self.teacher.auto = mode == "auto"
            if mode == "auto" and self.teacher.job is None:
                self.confirm(quiet=True)  # what waits for a Confirm is learned now

    def asks(self) -> str:
        """The movement Confirm learns now (the panel asks about it and its button names it):
        of the kept movements not being learned, the newest seen often enough to learn, else
        the newest kept; ``""`` when nothing is kept."""
        teacher = self.teacher
        if teacher is None or teacher.job is not None:
            return ""
        waiting = {p: ids for p, ids in self._kept.items() if p not in self._learning}
        newest = sorted(waiting, key=lambda p: max(waiting[p]), reverse=True)
        seen = self._lists.get("seen", {})
        ready = [p for p in newest if seen.get(p, 0) >= teacher.performances]
        return (ready or newest or [""])[0]

    def confirm(self, pattern: str | None = None, quiet: bool = False) -> None:
        """Consolidate one kept movement: ``pattern``, or the one the panel asks about
        (:meth:`asks`). Only its episodes are learned — a movement kept by accident before
        stays kept — also those a failed consolidation or an earlier session left; a
        movement seen fewer times than the Teacher waits for is learned from what was seen."""
        teacher = self._need()
        if teacher.job is not None:
            raise ConfigError("a consolidation is running already")
        self._refresh()
        chosen = pattern or self.asks()
        if not chosen:
            if quiet:
                return
            raise ConfigError("no kept movement to learn: perform a new movement first")
        ids = self._kept.get(chosen)
        if not ids:
            kept = ", ".join(self._kept) or "none"
            raise ConfigError(f"no kept movement {chosen!r} to learn (kept: {kept})")
        others = [i for i in teacher.pending if i not in ids]
        teacher.pending = list(ids)
        teacher.confirm()
        teacher.pending = [*others, *teacher.pending]
        self._learning = {chosen}
        self._take_events()

    def undo(self) -> None:
        teacher = self._need()
        if teacher.job is not None:
            raise ConfigError("a consolidation is running: undo once it has finished")
        if len(teacher.versions) < 2:
            raise ConfigError("nothing to undo: the robot runs its first version")
        teacher.undo()
        self._take_events()

    def rename(self, pattern: str, name: str) -> None:
        teacher = self._need()
        teacher.rename(pattern, name)
        self._version_patterns.pop(teacher.model_path, None)
        self._take_events()

    # --- what the pages see ---------------------------------------------------------------
    def _refresh(self) -> None:
        """Re-read the memory's episodes (on the session thread)."""
        if self.memory is None:
            self._lists = {"episodes": [], "pending": 0}
            self._shapes = {}
            self._kept = {}
            return
        try:
            episodes = self.memory.episodes()
        except RnnpbError as error:
            self.failure = f"the short-term memory cannot be read: {error}"
            return
        shown = [
            {
                "id": e.id,
                "pattern": e.pattern,
                "status": e.status,
                "n_cycles": e.n_cycles,
                "n_steps": e.n_steps,
                "source": e.source,
                "when": datetime.datetime.fromtimestamp(e.created_at).strftime("%H:%M:%S"),
                "note": e.note,
                "merged": merged_with(e.note),
            }
            for e in reversed(episodes)
        ][:SHOWN_EPISODES]
        pending = sum(e.status == "kept" for e in episodes)
        # How many performances the memory holds of each movement waiting to be learned.
        seen: dict[str, int] = {}
        for e in episodes:
            if e.status in ("kept", "learned"):
                seen[e.pattern] = seen.get(e.pattern, 0) + 1
        waiting = {e.pattern: seen[e.pattern] for e in episodes if e.status == "kept"}
        self._kept = {}
        for e in episodes:
            if e.status == "kept":
                self._kept.setdefault(e.pattern, []).append(e.id)
        self._lists = {
            "episodes": shown,
            "pending": pending,
            "total": len(episodes),
            "seen": waiting,
            "performances": self.teacher.performances if self.teacher is not None else 2,
        }
        # Which demonstrator shape each learned pattern was shown as (the buttons say so).
        self._shapes = {
            shown_as(e.note): e.pattern
            for e in episodes
            if e.status == "learned" and shown_as(e.note)
        }

    def _patterns_of(self, path: str) -> list[str]:
        if path not in self._version_patterns:
            from rnnpb.model import TrainedModel

            try:
                self._version_patterns[path] = list(TrainedModel.load(path).patterns)
            except RnnpbError:
                self._version_patterns[path] = []
        return self._version_patterns[path]

    def status(self) -> dict[str, Any]:
        """What the teaching panel shows now (each step message carries it)."""
        teacher = self.teacher
        if teacher is None:
            return {"phase": "off", "text": self.unavailable or ""}
        cutter = teacher.keeper.cutter.status
        job = teacher.job
        out: dict[str, Any] = {
            "phase": cutter.state if self.mode != "off" else "off",
            "text": cutter.describe() if self.mode != "off" else "",
            "cycles": cutter.cycles,
            "episode_cycles": cutter.episode_cycles,
        }
        if job is not None:
            state = job.state
            out["consolidation"] = {
                "state": state.state,
                "iteration": state.iteration,
                "total": state.total,
                "seconds": round(time.monotonic() - self._started_at, 1),
            }
        return out

    def state(self) -> dict[str, Any]:
        """The ``teaching`` part of the state message."""
        teacher = self.teacher
        out: dict[str, Any] = {
            "mode": self.mode,
            "available": teacher is not None,
            "unavailable": self.unavailable,
            "failure": self.failure,
            "result": self.result,
            "events": self.events,
            "status": self.status(),
            **self._lists,
        }
        if teacher is None:
            return {
                **out,
                "versions": [],
                "taught": [],
                "taught_shapes": {},
                "can_undo": False,
                "folder": "",
            }
        first = set(self._patterns_of(teacher.versions[0]))
        shelf = self.host.shelf
        running = list(shelf.running.model.patterns) if shelf.running is not None else []
        learning = self._learning if teacher.job is not None else set()
        out.update(
            memory=str(self.memory.path) if self.memory is not None else "",
            folder=self.folder_note,
            # The model list offers every version learned (an undone one too): so does this.
            versions=[
                {
                    "name": self._names.get(v, Path(v).name),
                    "patterns": self._patterns_of(v),
                    "running": v == teacher.model_path,
                    "undone": v not in teacher.versions,
                }
                for v in self._versions
            ],
            taught=[p for p in running if p not in first],
            taught_shapes={k: v for k, v in self._shapes.items() if v in running},
            can_undo=len(teacher.versions) > 1 and teacher.job is None,
            consolidating=teacher.job is not None,
            # What is being learned is not asked about again (nor counted as waiting).
            learning=sorted(learning),
            seen={p: n for p, n in self._lists.get("seen", {}).items() if p not in learning},
            asks=self.asks(),
            waiting=self.mode == "confirm" and teacher.waiting_for_confirm(),
        )
        return out
