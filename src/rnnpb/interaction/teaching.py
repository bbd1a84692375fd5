"""Teaching by showing, on-line: cut a new movement out of the interaction's stream.

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
2. The whole cycles of the run are counted with :func:`rnnpb.interaction.learning_phase.
   cycle_bounds`. From ``confirm_cycles`` whole cycles on the cutter is *recording* ("cycle
   k of ``episode_cycles``"); when the run holds ``episode_cycles`` whole cycles, the last
   ``episode_cycles`` of them are the episode: their sensory values as seen and the robot's
   joint angles for them (3-D hands from the source when it gives them, else on the fixed
   plane; mirror mapping and inverse kinematics, as in the learning phase).
3. The cutter then stays *kept* until the run ends, so one performance gives one episode.

It is pure bookkeeping (NumPy only, no clock or I/O): a principal component and an
autocorrelation of at most ``max_run_steps`` steps, 0.2 ms a step (median) with a full run.
"""

from __future__ import annotations

import os
import re
import time
from collections import deque
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rnnpb.demonstrator import MirrorMapping
from rnnpb.errors import ConfigError
from rnnpb.interaction.learning_phase import cycle_bounds
from rnnpb.perception import MOUSE_PLANE_X, hands_on_plane
from rnnpb.robot.camera import RobotCamera

WATCHING, RECORDING, KEPT = "watching", "recording", "kept"
CUTTER_STATES = (WATCHING, RECORDING, KEPT)


@dataclass(frozen=True)
class TeachingConfig:
    """When a novel movement is kept.

    Attributes
    ----------
    confirm_cycles : int
        Whole cycles called ``novel`` before the cutter says it is recording.
    episode_cycles : int
        Whole cycles an episode holds.
    tolerance_steps : int
        Consecutive steps without evidence (``""``) a run survives.
    interruption_steps : int
        Consecutive steps called ``familiar``, ``unstructured`` or ``still`` a run survives.
    min_novel_share : float
        The share of an episode's steps with evidence that must have been called ``novel``.
    max_run_steps : int
        The run's oldest steps are dropped beyond this many (bounds the cost per step).
    plane_x : float
        ``x`` (m) of the hands' plane for sources that give no 3-D hands.
    """

    confirm_cycles: int = 1
    # Chosen by replaying the cutter over the novelty words of the teach study's script (every
    # learning set × new shape, user draw 500; checked on the study's own draws 100+,
    # docs/teaching.md): 4 unbroken cycles kept 5 of 20 new shapes (single `still` steps at
    # a diagonal's turning points broke the runs); these keep 17 of 20, none from
    # unstructured movement or with another pattern in them.
    episode_cycles: int = 3
    tolerance_steps: int = 2
    interruption_steps: int = 2
    min_novel_share: float = 0.9
    max_run_steps: int = 200
    plane_x: float = MOUSE_PLANE_X

    def __post_init__(self) -> None:
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
    """

    sensory: np.ndarray
    motor: np.ndarray
    n_cycles: int
    first_step: int
    last_step: int


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
        self.reset()

    def reset(self) -> None:
        """Forget the current run."""
        self._steps: list[int] = []
        self._sensory: list[np.ndarray] = []
        self._hands: list[np.ndarray] = []
        self._novel: list[float] = []  # 1 novel, 0 familiar or unstructured, nan no evidence
        self._quiet = 0
        self._interrupted = 0
        self._cycles = 0
        self._kept = False

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
        self, step: int, observed: np.ndarray, novelty: str, hands: np.ndarray | None = None
    ) -> KeptMovement | None:
        """One step: the hands seen (4,), the step's novelty word, optionally the 3-D hands
        (2, 3); returns the episode on the step it is complete, else None."""
        observed = np.asarray(observed, dtype=np.float64).reshape(4)
        seen = bool(np.isfinite(observed).all())
        config = self.config
        going = bool(self._steps) and seen
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
            self.reset()
            return None
        if self._kept:
            return None
        self._steps.append(int(step))
        self._novel.append(np.nan if novelty == "" else float(novelty == "novel"))
        self._sensory.append(observed)
        self._hands.append(
            np.full((2, 3), np.nan)
            if hands is None
            else np.asarray(hands, dtype=np.float64).reshape(2, 3)
        )
        if len(self._steps) > config.max_run_steps:
            del self._steps[0], self._sensory[0], self._hands[0], self._novel[0]
        cycles = cycle_bounds(np.array(self._sensory))
        self._cycles = len(cycles)
        if self._cycles < config.episode_cycles:
            return None
        start, stop = cycles[-config.episode_cycles][0], cycles[-1][1]
        said = np.array(self._novel[start:stop])
        said = said[np.isfinite(said)]
        if not said.size or said.mean() < config.min_novel_share:
            return None  # not novel enough yet: the run goes on, its window slides
        sensory = np.array(self._sensory[start:stop])
        hands = np.array(self._hands[start:stop])
        missing = ~np.isfinite(hands).all(axis=(1, 2))
        if missing.any():
            hands[missing] = hands_on_plane(sensory[missing], self.camera, config.plane_x)
        motor = self.mapping.motor_from_hands(hands)
        self._kept = True
        return KeptMovement(
            sensory, motor, config.episode_cycles, self._steps[start], self._steps[stop - 1]
        )


@dataclass(frozen=True)
class TeachingEvent:
    """Something the teacher did, for the dashboard and the log.

    ``kind`` is ``recording`` (a novel movement is being recorded; ``text`` says which cycle),
    ``kept`` (an episode was stored; ``episode_id``, ``pattern``) or ``refused`` (the memory
    would not take it; ``text`` says why).
    """

    step: int
    kind: str
    text: str
    episode_id: int | None = None
    pattern: str = ""


SHOWN_STEPS = 2000  # steps of a source's own account kept (an episode is far shorter)
SHOWN_AS = "shown as "  # in an episode's note: what a scripted source said it performed


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


class EpisodeKeeper:
    """A loop subscriber: cuts novel movements with an :class:`EpisodeCutter` and stores each
    as an episode in the short-term memory, under the next free name ``new-1``, ``new-2`` ….

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

    ``events`` lists what happened, newest last; ``kept`` the stored episodes' ids.
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
        self.hands_of = hands_of
        self.events: list[TeachingEvent] = []
        self.kept: list[int] = []
        self._last_text = ""
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

    def __call__(self, record) -> None:
        truth = getattr(record, "truth", None)
        shown = truth.get("pattern", "") if isinstance(truth, dict) else ""
        if shown:
            self._shown.append((record.step, str(shown)))  # the oldest fall off the end
        hands = self.hands_of(record) if self.hands_of is not None else None
        episode = self.cutter.observe(
            record.step, record.observed, getattr(record, "novelty", ""), hands
        )
        text = self.cutter.status.describe()
        if episode is None:
            if text != self._last_text and self.cutter.status.state == RECORDING:
                self.events.append(TeachingEvent(record.step, "recording", text))
            self._last_text = text
            return
        self._last_text = text
        pattern = self.next_pattern_name()
        shown_as = self._shown_as(episode.first_step, episode.last_step)
        from rnnpb.errors import RnnpbError

        try:
            episode_id = self.memory.add_episode(
                episode.sensory,
                episode.motor,
                source=self.source,
                model=self.model,
                pattern=pattern,
                n_cycles=episode.n_cycles,
                note=f"steps {episode.first_step}-{episode.last_step}"
                + (f"; {SHOWN_AS}{shown_as}" if shown_as else ""),
            )
        except RnnpbError as error:
            self.events.append(TeachingEvent(record.step, "refused", str(error)))
            return
        self.kept.append(episode_id)
        self.events.append(
            TeachingEvent(
                record.step,
                "kept",
                f"kept a new movement as {pattern} ({episode.n_cycles} cycles, "
                f"{len(episode.sensory)} steps)",
                episode_id,
                pattern,
            )
        )


def tracked_hands(source):
    """For :class:`EpisodeKeeper`'s ``hands_of``: the 3-D hands a camera source's tracker found
    for the step just read (depth from the balls' size, unfiltered: on-line there is no later
    frame to filter with), or None when ``source`` has no tracker."""
    inner = getattr(source, "inner", source)  # a FrameStepSource keeps the camera inside

    def hands_of(record) -> np.ndarray | None:
        result = getattr(inner, "last_result", None)
        return None if result is None else result.hands_3d

    return hands_of


def version_path(model_path: str | os.PathLike[str], version: int) -> Path:
    """The file of a model's version ``version``: ``model.npz`` → ``model.v2.npz`` (the
    original is version 1; a version's own file name gives the same family)."""
    path = Path(model_path)
    stem = re.sub(r"\.v\d+$", "", path.name.removesuffix(".npz"))
    return path.with_name(f"{stem}.v{int(version)}.npz")


def rename_pattern(model, pattern: str, name: str):
    """``model`` with its pattern ``pattern`` called ``name``: the sequences' names and the
    history's last entry (its ``added`` and ``patterns``; ``details["renamed"]`` records
    ``{"from", "to", "created"}``), so the model file says what the pattern was learned as.

    Raises :class:`ConfigError` for a pattern the model does not hold, a name that is not a
    pattern name, or one the model already holds.
    """
    import datetime
    from dataclasses import replace

    from rnnpb.sequences import pattern_name_problem

    if pattern not in model.patterns:
        raise ConfigError(f"the model has no pattern {pattern!r}")
    problem = pattern_name_problem(name)
    if problem:
        raise ConfigError(f"pattern name {name!r} {problem}")
    if name in model.patterns:
        raise ConfigError(f"the model already has a pattern {name!r}")

    def renamed(names):
        return tuple(name if n == pattern else n for n in names)

    *older, last = model.history
    record = {
        "from": pattern,
        "to": name,
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
    }
    last = replace(
        last,
        added=renamed(last.added),
        patterns=renamed(last.patterns),
        details={**last.details, "renamed": [*last.details.get("renamed", []), record]},
    )
    meta = {**model.meta, "history": [e.to_json() for e in (*older, last)]}
    return replace(model, sequence_patterns=renamed(model.sequence_patterns), meta=meta)


TEACHING_ITERATIONS = {"momentum": 20_000, "adam": 1_000}
"""On-line teaching's consolidation iterations by optimizer. A taught episode is three cycles
of an imperfect demonstration: with 5,000 iterations of the paper's learning the network
predicted the person's next performance of it just above the lock-on threshold, with 10,000
it followed (user draws 101: 15 → 19 of 20 locked onto within 90 s, counted by any
lock-on, checked on 102). Rehearsing the old network's function
(:data:`rnnpb.model.consolidation.REHEARSAL_TARGET`) learns with 20,000, the consolidation's
own (docs/teaching.md, "The full study"). Adam (the fast preset): twice the consolidation's
500."""


TEACHING_INPUT_NOISE = 0.03
"""The least input noise of a teaching consolidation (normalized units), above the
consolidation's own 0.02 for a rehearsal of the old network's function
(:data:`rnnpb.model.consolidation.FUNCTION_REHEARSAL_INPUT_NOISE`). The noise is where the old
function is learned, and a person's version of an old pattern can lie further from its cycle
than the noise of 0.02 reaches (set 1's pattern 2: 0.041-0.05). Chosen on the teach study's
user draws 102 and 103 (old lock-ons within 10: 124 of 128 against 122, switches within 15:
285 of 288 against 278; new shapes locked onto within 90 s, counted by any lock-on: 38 of
40 against 39), checked on draws 104 (62 of 64 against 60, 140 of 144 against 138, 20 of 20
both; docs/teaching.md, "Study")."""

TEACHING_HOLD_OLD_PB = "off"
TEACHING_NEW_PB_START = "centre"
"""Teaching's own start of a consolidation: the new PB at the centre and every PB learning,
not the consolidation's defaults (farthest, old PBs held for the first half). Those kept the
old patterns' cycles closer in the incremental study, but in teaching they measured level on
user draws 102 and 103 (38 of 40 shapes locked onto within 90 s against 39, old lock-ons 115 of
128 against 117, switches 276 of 288 against 273), and the shipped fast model taught
figure-eight locked on its next performance after 11 steps instead of within 10. With the old
network's function rehearsed they were worse on the same draws (old lock-ons 116 of 128
against 122, switches 273 of 288 against 278; docs/teaching.md, "Study")."""


def _consolidation_worker(
    model_path: str,
    memory_path: str,
    episode_ids: list[int],
    out_path: str,
    queue,
    iterations: int | None = None,
) -> None:
    """In a spawned process: consolidate the episodes into the model, write the new version,
    record the consolidation in the memory; report progress and the outcome on ``queue``."""
    start = time.perf_counter()
    try:
        from dataclasses import replace

        from rnnpb.memory import MemoryStore
        from rnnpb.model import ConsolidationConfig, TrainedModel, consolidate, rehearse

        model = TrainedModel.load(model_path)
        with MemoryStore(memory_path, create=False) as memory:
            sequences = [memory.episode(i).sequence() for i in episode_ids]

        def progress(p) -> None:
            queue.put(("progress", int(p.iteration), int(p.total), float(p.mse)))

        config = ConsolidationConfig(
            hold_old_pb=TEACHING_HOLD_OLD_PB, new_pb_start=TEACHING_NEW_PB_START
        )
        learning = config.learning_for(model)
        if iterations is None:
            iterations = TEACHING_ITERATIONS.get(learning.optimizer, learning.iterations)
        noise = max(learning.input_noise, TEACHING_INPUT_NOISE)
        config = replace(
            config, train=replace(learning, iterations=int(iterations), input_noise=noise)
        )
        learned = consolidate(model, sequences, config, parent=model_path, progress=progress)
        learned.save(out_path)
        rehearsed = rehearse(model)
        seconds = time.perf_counter() - start
        with MemoryStore(memory_path, create=False) as memory:
            memory.add_consolidation(
                model_before=model_path,
                model_after=out_path,
                episode_ids=episode_ids,
                rehearsed=[*rehearsed, *sequences],
                seconds=seconds,
            )
        queue.put(("done", out_path, seconds))
    except BaseException as error:  # the parent keeps its model and says why
        message = (
            f"{type(error).__name__}: {error}" if not str(error).startswith("rnnpb") else str(error)
        )
        try:
            from rnnpb.memory import MemoryStore

            with MemoryStore(memory_path, create=False) as memory:
                memory.add_consolidation(
                    model_before=model_path,
                    model_after="",
                    episode_ids=episode_ids,
                    rehearsed=[],
                    status="failed",
                    message=message[:500],
                    seconds=time.perf_counter() - start,
                )
        except BaseException:  # noqa: BLE001 - the message to the parent matters more
            pass
        queue.put(("failed", message))


@dataclass(frozen=True)
class ConsolidationState:
    """Where a background consolidation is: ``running`` (``iteration`` of ``total``),
    ``done`` (``model_path`` of the new version, ``seconds``) or ``failed`` (``message``)."""

    state: str
    iteration: int = 0
    total: int = 0
    model_path: str = ""
    seconds: float = 0.0
    message: str = ""

    def describe(self) -> str:
        if self.state == "running":
            share = f" {100 * self.iteration / self.total:.0f} %" if self.total else ""
            return f"consolidating{share}"
        if self.state == "done":
            return f"consolidated in {self.seconds:.0f} s"
        return f"consolidation failed: {self.message}"


class BackgroundConsolidation:
    """A consolidation in a spawned process, so that the loop keeps its pace.

    The process loads the model, reads the episodes from the memory, runs
    :func:`rnnpb.model.consolidate` (rehearsal), writes the new version beside the model and
    records the consolidation in the memory; :meth:`poll` never blocks, :meth:`wait` does.
    """

    def __init__(
        self,
        model_path: str | os.PathLike[str],
        memory_path: str | os.PathLike[str],
        episode_ids: list[int],
        out_path: str | os.PathLike[str],
        iterations: int | None = None,
    ) -> None:
        import multiprocessing

        context = multiprocessing.get_context("spawn")
        self._queue = context.Queue()
        self.out_path = str(out_path)
        self._process = context.Process(
            target=_consolidation_worker,
            daemon=True,
            args=(
                str(model_path),
                str(memory_path),
                list(episode_ids),
                self.out_path,
                self._queue,
                iterations,
            ),
        )
        self.state = ConsolidationState("running")
        self._process.start()

    def poll(self) -> ConsolidationState:
        """The latest state, reading what the process reported so far (never blocks)."""
        import queue as queues

        while self.state.state == "running":
            try:
                message = self._queue.get_nowait()
            except queues.Empty:
                if not self._process.is_alive() and self._queue.empty():
                    code = self._process.exitcode
                    self.state = ConsolidationState(
                        "failed", message=f"the consolidation process ended (exit code {code})"
                    )
                break
            self._take(message)
        return self.state

    def wait(self, timeout_s: float | None = None) -> ConsolidationState:
        """Block until the consolidation has finished (or ``timeout_s``), and its process
        has ended (up to 5 s more)."""
        deadline = None if timeout_s is None else time.perf_counter() + timeout_s
        while self.poll().state == "running":
            if deadline is not None and time.perf_counter() > deadline:
                break
            self._process.join(0.05)
        if self.state.state != "running":
            self._process.join(5.0)
        return self.state

    def _take(self, message: tuple) -> None:
        kind = message[0]
        if kind == "progress":
            self.state = ConsolidationState("running", message[1], message[2])
        elif kind == "done":
            # Not joined here: the process takes a moment to end after it reported (its
            # interpreter and JAX shut down), and poll() must never hold up a paced loop.
            # ``ended`` tells when it has; ``wait`` and ``cancel`` join it.
            self.state = ConsolidationState("done", model_path=message[1], seconds=message[2])
        else:
            self.state = ConsolidationState("failed", message=message[1])

    @property
    def ended(self) -> bool:
        """Whether the process has exited (and been reaped); never blocks."""
        return not self._process.is_alive()

    def cancel(self) -> None:
        if self._process.is_alive():
            self._process.terminate()
            self._process.join(5.0)


class _PreparedMirror:
    """A new model version's mirror system, built and its first step compiled in a thread of
    its own (``mirror`` None when that failed: the swap then builds it, and says why)."""

    def __init__(self, path: str, make_mirror) -> None:
        import threading

        self.path = path
        self.model = None
        self.mirror = None
        self.error = ""
        self._make_mirror = make_mirror
        self._thread = threading.Thread(target=self._run, name="rnnpb-prepare", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        from rnnpb.model import TrainedModel

        try:
            model = TrainedModel.load(self.path)
            mirror = self._make_mirror(model)
            mirror.step(np.full(model.network.sensory_size, 0.5))  # compiles the step
            mirror.reset()
            self.model, self.mirror = model, mirror
        except Exception as error:  # noqa: BLE001 - the swap builds it on the loop's thread
            self.error = f"{type(error).__name__}: {error}"

    @property
    def done(self) -> bool:
        return not self._thread.is_alive()


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
    ) -> None:
        self.iterations = iterations
        self.loop = loop
        self.memory = memory
        self.make_mirror = make_mirror
        self.versions: list[str] = [str(model_path)]
        self.keeper = EpisodeKeeper(memory, str(model_path), source, config, hands_of)
        self.auto = auto
        self.wait = (not loop.config.paced) if wait is None else wait
        # Paced, a new version's mirror system is built and its step compiled in a thread
        # before the swap (seconds: a step's deadline would be missed if it happened between
        # two steps); as fast as possible, on the loop's thread, so that a run repeats.
        self.prepare = (not self.wait) if prepare is None else prepare
        self._prepared: _PreparedMirror | None = None
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
            self.model_path, self.memory.path, ids, out, self.iterations
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
                    self._prepared = _PreparedMirror(state.model_path, self.make_mirror)
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

    def _swap(self, state: ConsolidationState, prepared: _PreparedMirror | None = None) -> None:
        from rnnpb.model import TrainedModel

        assert self.job is not None
        self.job = None
        if prepared is not None and prepared.model is not None and prepared.mirror is not None:
            model, self.loop.mirror = prepared.model, prepared.mirror
        else:  # not prepared (or its preparation failed): built here, as fast runs do
            model = TrainedModel.load(state.model_path)
            self.loop.mirror = self.make_mirror(model)
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

    def undo(self) -> None:
        """Go back to the previous model version (the newer file stays on disk)."""
        from rnnpb.model import TrainedModel

        if len(self.versions) < 2:
            return
        undone = self.versions.pop()
        self.loop.mirror = self.make_mirror(TrainedModel.load(self.model_path))
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
        not in the first one) is renamed in that version's file (:func:`rename_pattern`) and
        the new model swapped in; the memory's episodes of that name are renamed too (a kept
        episode not learned yet is then consolidated under its new name)."""
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
            renamed = rename_pattern(model, pattern, name)
            renamed.save(self.model_path)
            self.loop.mirror = self.make_mirror(renamed)
        for episode in episodes:
            self.memory.rename(episode.id, name)
        self.events.append(
            TeachingEvent(self.loop.steps, "renamed", f"renamed pattern {pattern} to {name}")
        )
