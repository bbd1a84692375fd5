"""The dashboard's one shared interaction session, run by its own thread.

All browser tabs observe the same session. Control messages (start, stop, reset, mode,
pattern, dt, model) are put on a queue and applied by the session thread between two steps,
one at a time, so two tabs can never interleave half-applied changes; pointer positions go
straight to the :class:`PointerSource` (the newest position wins).

The loop drives itself: while the session runs, its thread is inside
:meth:`InteractionLoop.run <rnnpb.interaction.InteractionLoop.run>`, which paces the steps at
``dt`` and hands the waits between them to the session to apply its commands. The session
subscribes to the loop's step records and publishes one JSON message per step to its own
subscribers (the WebSocket connections), which only observe. While stopped, the thread waits
for commands and applies them itself.

Nothing a step or a command raises ends the session thread: a failed step stops the robot
and says why on every page (``error`` message, ``state.error``), a failed recording turns
recording off and the robot goes on, and later commands are applied as before. Recordings are
bounded (:class:`RecordingLimits`) and the session removes what it made (docs/robustness.md,
"The dashboard's session: errors, recordings, command limits").
"""

from __future__ import annotations

import base64
import contextlib
import json
import logging
import math
import queue
import secrets
import shutil
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rnnpb.errors import ConfigError, RnnpbError
from rnnpb.interaction.settings import ConfigTables
from rnnpb.sources import UserSource
from rnnpb.web._sources import PAUSE, DemonstratorSource, PointerSource, SwitchableSource
from rnnpb.web._teaching import SessionTeaching, TeachingSettings

if TYPE_CHECKING:
    from rnnpb.robot import Robot

log = logging.getLogger("rnnpb.web")

FRAME_WIDTH = 320
"""Width (pixels) of the camera image sent to the page."""
RECENT_STEPS = 120
"""Step messages kept for a tab that connects (the page plots this many steps)."""
MAX_QUEUED_COMMANDS = 64
"""Commands waiting for the session thread; more are refused with an error reply."""


def offered_models(model_or_dir: str | Path) -> tuple[dict[str, Path], dict[str, str]]:
    """The models ``--model`` offers, each loaded once to check it, and those it refuses.

    A ``.npz`` file is offered if it loads; otherwise its one-line error is raised. A folder
    offers every ``*.npz`` under it that loads, except training checkpoints
    (``*.checkpoint.npz``) and hidden files (``.name``: unfinished writes); the others are
    refused with their reason. A folder with nothing to offer is an error.

    Returns
    -------
    models : dict of name → path
        Names are paths relative to the folder (the file's name for a file).
    refused : dict of name → reason
    """
    from rnnpb.model import TrainedModel

    path = Path(model_or_dir)
    if path.is_file():
        TrainedModel.load(path)  # a bad model is its one-line error, before serving
        return {path.name: path}, {}
    if not path.is_dir():
        raise ConfigError(f"{path}: no such model file or folder")
    models: dict[str, Path] = {}
    refused: dict[str, str] = {}
    for found in sorted(path.rglob("*.npz")):
        name = str(found.relative_to(path))
        # A checkpoint, or a model's safety map (M.safety.npz, docs/safety.md): not models.
        if found.name.endswith((".checkpoint.npz", ".safety.npz")) or any(
            part.startswith(".") for part in found.relative_to(path).parts
        ):
            continue
        try:
            TrainedModel.load(found)
        except RnnpbError as error:
            refused[name] = str(error)
            continue
        models[name] = found
    if not models:
        reasons = "; ".join(f"{reason}" for reason in refused.values())
        raise ConfigError(
            f"{path}: no usable model files (*.npz) in this folder"
            + (f" ({reasons})" if reasons else "; train one with `rnnpb train`")
        )
    return models, refused


def find_models(model_or_dir: str | Path) -> dict[str, Path]:
    """The models ``--model`` offers (:func:`offered_models`); each refused model is logged
    as a warning with its reason."""
    models, refused = offered_models(model_or_dir)
    for name, reason in refused.items():
        log.warning("not offering %s: %s", name, reason)
    return models


@dataclass(frozen=True)
class RecordingLimits:
    """How much the dashboard keeps on disk.

    Attributes
    ----------
    rows_per_file : int
        A recording that reaches this many rows (steps) goes on in a new file (the next part
        of the same run). 50,000 rows are about 12 MB: 17 minutes at ``dt`` 0.02, 5.5 hours
        at the paper's 0.4.
    keep_files : int
        Recording files kept; the oldest beyond this number are deleted (the newest, being
        written, is always kept). So the session's files are bounded by
        ``keep_files × rows_per_file`` rows, about 60 MB with the defaults.
    """

    rows_per_file: int = 50_000
    keep_files: int = 5

    def __post_init__(self) -> None:
        if self.rows_per_file < 1 or self.keep_files < 1:
            raise ConfigError("recording limits must be >= 1 row per file and >= 1 file kept")


class _Recording:
    """The recorder the loop writes to: the session's CSV in parts of at most
    ``limits.rows_per_file`` rows, the oldest files deleted beyond ``limits.keep_files``. A
    write that fails (a full disk) turns the recording off and reports it through
    ``on_failure``; the robot is not stopped for it."""

    def __init__(self, session: Session, run: int) -> None:
        self.session = session
        self.run = run
        self.part = 0
        self.failed: str | None = None
        self.rows = 0
        self._recorder = None
        self._next_part()

    def _next_part(self) -> None:
        from rnnpb.interaction import SessionRecorder

        self._close_part()
        self.part += 1
        suffix = "" if self.part == 1 else f"-part{self.part}"
        path = self.session.workdir / f"session-{self.run:03d}{suffix}.csv"
        recorder = SessionRecorder(path, self.session.model.network.pb_size)
        recorder.open()
        self._recorder = recorder
        self.path = path
        self.session._keep_recording(path)

    def write(self, record) -> None:
        if self.failed is not None:
            return
        try:
            if self._recorder.rows >= self.session.recording_limits.rows_per_file:
                self._next_part()
            self._recorder.write(record)
            self.rows += 1
        except OSError as error:
            self.failed = f"recording stopped: {self.path.name}: {error.strerror or error}"
            with contextlib.suppress(OSError):  # already reported
                self._close_part()
            self.session._error(
                f"{self.failed}; the robot goes on without recording (Reset starts a new recording)"
            )

    def _close_part(self) -> None:
        recorder, self._recorder = self._recorder, None
        if recorder is not None:
            recorder.close()

    def close(self) -> None:
        with contextlib.suppress(OSError):  # already reported
            self._close_part()


class _UserView:
    """Where the person's hands are in 3-D, from the view-plane values the robot perceives:
    back-projected through the robot's camera at the depth of the demonstrator's hands (the
    sensory vector has no depth), so the 3-D view can show the person in front of the robot."""

    def __init__(self) -> None:
        from rnnpb.demonstrator import UserBody
        from rnnpb.robot.camera import RobotCamera

        self.camera = RobotCamera()
        centres = UserBody().hand_centres
        self.depth = float(self.camera.camera_coordinates(centres)[:, 2].mean())
        self.rest = self.camera.sensory_from_hands(centres)

    def hands(self, sensory: np.ndarray) -> list[list[float] | None]:
        yz = np.asarray(sensory, dtype=np.float64).reshape(2, 2)
        out: list[list[float] | None] = []
        for hand in yz:
            if not np.all(np.isfinite(hand)):
                out.append(None)
                continue
            pixel = self.camera.pixels_from_normalized(hand)
            point = self.camera.back_project(pixel, np.array(self.depth))
            out.append(np.round(point, 4).tolist())
        return out


def _listed(values: np.ndarray) -> list[float | None]:
    return [float(v) if math.isfinite(v) else None for v in np.asarray(values, float).ravel()]


class Session:
    """Model, mirror system, sources, loop and recording of the dashboard.

    Parameters
    ----------
    models : dict of name → path
    dt : float
        Seconds per step (the loop paces itself at it).
    workdir : path, optional
        Where session recordings are written; by default a temporary folder the session
        makes and deletes when it closes.
    recording_limits : RecordingLimits, optional
    max_queued_commands : int
        Commands waiting for the session thread; :meth:`submit` refuses more.
    teaching : TeachingSettings, optional
        Teaching by showing (docs/dashboard.md, "Teaching"); by default new movements are
        kept and consolidated when the person confirms.
    config_tables : ConfigTables, optional
        A ``--config`` file's tables (``rnnpb serve --config``), put over the on-line
        regression and recognition chosen for each model and over teaching's settings
        (:mod:`rnnpb.interaction.settings`); read when a model loads.
    routines : paths, optional
        Routine files (``rnnpb train-routines``, docs/routines.md): the one learned over the
        running model version, if any, follows the interaction and the step message says the
        routine it recognises and the movement it anticipates.
    """

    def __init__(
        self,
        models: dict[str, Path],
        dt: float = 0.4,
        workdir: str | Path | None = None,
        recording_limits: RecordingLimits | None = None,
        max_queued_commands: int = MAX_QUEUED_COMMANDS,
        teaching: TeachingSettings | None = None,
        config_tables: ConfigTables | None = None,
        routines: Sequence[str | Path] = (),
    ) -> None:
        if not models:
            raise ConfigError("the dashboard needs at least one model")
        import tempfile

        self.models = dict(models)
        self.dt = float(dt)
        self.recording_limits = recording_limits or RecordingLimits()
        self._own_workdir = workdir is None
        self.workdir = Path(workdir or tempfile.mkdtemp(prefix="rnnpb-serve-"))
        self.pointer = PointerSource()
        self.demonstrator = DemonstratorSource()
        self.camera_index = 0
        self.perception = "balls"  # how the webcam's frames become hands: balls or pose
        self.mode = "demonstrator"
        self.running = False
        self.loading = False
        self.loading_model: str | None = None
        self.model_name: str | None = None
        self.model = None
        self.mirror = None
        self.loop = None
        self.recorder: _Recording | None = None
        self.last_error: str | None = None
        self.model_error: str | None = None
        self._webcam: UserSource | None = None
        self._source = SwitchableSource(self.demonstrator)
        self._user_view = _UserView()
        self._commands: queue.Queue[dict[str, Any]] = queue.Queue(maxsize=max_queued_commands)
        self._subscribers: list[Callable[[str], None]] = []
        self._subscribers_lock = threading.Lock()
        self._recent: deque[str] = deque(maxlen=RECENT_STEPS)
        self._closed = threading.Event()
        self._thread: threading.Thread | None = None
        self._recordings = 0
        self._recording_files: deque[Path] = deque()
        # Names this server's runs, so a page that reconnects to a restarted server knows
        # its plots belong to another run even when the run numbers coincide.
        self._token = secrets.token_hex(4)
        # Safety (docs/safety.md): the command filter always and the model's map when one
        # lies beside it; ``rnnpb serve --no-safety`` sets this False before start().
        self.safety_enabled = True
        self.safety = None  # rnnpb.safety.OnlineSafety of the loaded model
        # A connected robot the loop also drives (`rnnpb serve --robot`; docs/bridge.md);
        # None: the page's simulated humanoid only.
        self.robot: Robot | None = None
        self._risk_views: dict[str, Any] = {}
        self.config_tables = config_tables or ConfigTables()
        self.teaching = SessionTeaching(self, teaching or TeachingSettings())
        self.routine_files = [Path(p) for p in routines]
        self._followers: dict[str, tuple[Any, str]] = {}  # fingerprint -> (follower, note)

    # --- life cycle -----------------------------------------------------------------------
    def start(self, model_name: str | None = None) -> None:
        """Start the session thread and load the first model in it."""
        name = model_name or next(iter(self.models))
        self._commands.put({"type": "model", "name": name})
        self._thread = threading.Thread(target=self._run, name="rnnpb-session", daemon=True)
        self._thread.start()

    def close(self) -> None:
        """Stop the session thread, close the recording and the camera, and delete the
        session's own temporary folder (a ``workdir`` given by the caller is left, with at
        most ``recording_limits.keep_files`` recordings in it)."""
        self._closed.set()
        with contextlib.suppress(queue.Full):
            self._commands.put_nowait({"type": "_wake"})
        if self._thread is not None:
            self._thread.join(timeout=10)
        self.teaching.close()
        self._close_run()
        self._close_webcam()
        if self._own_workdir:
            shutil.rmtree(self.workdir, ignore_errors=True)

    # --- what clients use -----------------------------------------------------------------
    def submit(self, command: dict[str, Any]) -> bool:
        """Queue a validated control message for the session thread; ``False`` (and nothing
        queued) when :data:`MAX_QUEUED_COMMANDS` are already waiting."""
        try:
            self._commands.put_nowait(command)
        except queue.Full:
            return False
        return True

    def subscribe(
        self, callback: Callable[[str], None], replay: bool = False
    ) -> Callable[[], None]:
        """``callback(json_text)`` for every message the session publishes.

        With ``replay``, ``callback`` first gets the state and a ``history`` message with the
        current run's last :data:`RECENT_STEPS` steps, so a new tab starts with full plots;
        no step is both replayed and published to it, nor missed.
        """
        with self._subscribers_lock:
            if replay:
                callback(json.dumps(self.state(), separators=(",", ":")))
                run, steps = json.dumps(self.run_id), ",".join(self._recent)
                callback(f'{{"type":"history","run":{run},"steps":[{steps}]}}')
            self._subscribers.append(callback)

        def unsubscribe() -> None:
            with self._subscribers_lock:
                if callback in self._subscribers:
                    self._subscribers.remove(callback)

        return unsubscribe

    @property
    def subscriber_count(self) -> int:
        with self._subscribers_lock:
            return len(self._subscribers)

    @property
    def run_id(self) -> str:
        """Names the current run (changes at every Reset, model change and server start)."""
        return f"{self._token}-{self._recordings}"

    @property
    def recording_path(self) -> Path | None:
        """The recording file being written (``None`` before the first run, or after the
        recording failed)."""
        recorder = self.recorder
        if recorder is None or recorder.failed is not None:
            return None
        return recorder.path

    @property
    def recording_files(self) -> list[Path]:
        """The recordings the session keeps, oldest first."""
        return list(self._recording_files)

    def state(self) -> dict[str, Any]:
        """The session's state as the ``state`` message carries it."""
        from rnnpb.demonstrator import MOVEMENT_DESCRIPTIONS, UserBody
        from rnnpb.robot import FOREARM_LENGTH, JOINT_LIMITS, SHOULDERS, UPPER_ARM_LENGTH
        from rnnpb.vectors import MOTOR_NAMES

        model = self.model
        learned = list(model.patterns) if model is not None else []
        recording = self.recording_path
        return {
            "type": "state",
            "models": list(self.models),
            "model": self.model_name,
            "loading": self.loading,
            "loading_model": self.loading_model,
            "running": self.running,
            "run": self.run_id,
            "mode": self.mode,
            "dt": self.dt,
            "camera_index": self.camera_index,
            "perception": self.perception,
            "demonstrator_pattern": PAUSE
            if self.demonstrator.paused
            else self.demonstrator.pattern,
            "patterns": learned,
            "demonstrator_patterns": list(self.demonstrator.patterns),
            "novel_patterns": [p for p in self.demonstrator.patterns if p not in learned],
            "pattern_pb": {k: _listed(v) for k, v in model.pattern_pb.items()}
            if model is not None
            else {},
            "steps": self.loop.steps if self.loop is not None else 0,
            "recording": recording is not None and recording.exists(),
            "recording_error": self.recorder.failed if self.recorder is not None else None,
            "error": self.last_error,
            "model_error": self.model_error,
            "rest_hands": _listed(self._user_view.rest),
            "user_shoulders": UserBody().shoulders.tolist(),
            "robot": {
                "shoulders": SHOULDERS.tolist(),
                "upper_arm": UPPER_ARM_LENGTH,
                "forearm": FOREARM_LENGTH,
                "joint_limits": JOINT_LIMITS.tolist(),
                "joint_names": list(MOTOR_NAMES),
            },
            "safety": self._safety_state(),
            "movement_descriptions": {
                p: MOVEMENT_DESCRIPTIONS.get(p, "") for p in self.demonstrator.patterns
            },
            "teaching": self.teaching.state(),
            "routines": self._routines_state(),
        }

    # --- the session thread ---------------------------------------------------------------
    def _publish(self, message: dict[str, Any]) -> None:
        text = json.dumps(message, separators=(",", ":"))
        with self._subscribers_lock:
            if message["type"] == "step":
                self._recent.append(text)
            callbacks = list(self._subscribers)
        for callback in callbacks:
            try:
                callback(text)
            except Exception:  # a broken subscriber must not stop the robot
                log.exception("dashboard subscriber failed")

    def _publish_state(self) -> None:
        self._publish(self.state())

    def _error(self, text: str) -> None:
        log.warning("session: %s", text)
        self.last_error = text
        self._publish({"type": "error", "message": text})

    def _run(self) -> None:
        while not self._closed.is_set():
            try:
                loop = self.loop
                if self.running and loop is not None:
                    self._drive(loop)
                else:
                    self._teach_between_steps()
                    self._apply_commands(timeout_s=0.1 if self.teaching.teacher else 0.5)
            except Exception as error:  # the thread must outlive anything a step raises
                log.exception("session: unexpected failure")
                self.running = False
                self._error(f"the session stopped the robot: {type(error).__name__}: {error}")
                with contextlib.suppress(Exception):
                    self._publish_state()
                time.sleep(0.05)  # a failure that repeats must not spin

    def _drive(self, loop) -> None:
        """Let ``loop`` run (it paces itself) until a command stops or replaces it, the session
        closes, or its source ends or fails; the queued commands are applied between steps.
        Whatever a step raises stops the robot with the reason on every page; the session
        goes on taking commands (Start tries again)."""

        def between_steps(wait_s: float) -> None:
            started = time.perf_counter()
            self._teach_between_steps()
            self._apply_commands(timeout_s=max(0.0, wait_s - (time.perf_counter() - started)))
            if self._closed.is_set() or not self.running or self.loop is not loop:
                loop.stop()

        try:
            loop.run(between_steps=between_steps)
        except RnnpbError as error:
            self.running = False
            self._error(f"the {self.mode} source failed: {error}")
            self._publish_state()
            return
        except Exception as error:  # an OSError, a bug, a failing camera driver...
            log.exception("session: step %d failed", loop.steps)
            self.running = False
            self._error(
                f"step {loop.steps} failed, the robot is stopped: {type(error).__name__}: {error}"
            )
            self._publish_state()
            return
        if self.running and self.loop is loop and not self._closed.is_set():
            self.running = False
            self._error(f"the {self.mode} source has ended")
            self._publish_state()

    def _teach_between_steps(self) -> None:
        """Follow a consolidation and swap a new version in; a failure here is reported and
        never stops the robot."""
        try:
            self.teaching.between_steps()
        except Exception as error:  # noqa: BLE001 - the robot runs on
            log.exception("session: teaching failed")
            self.teaching.failure = f"teaching failed: {type(error).__name__}: {error}"
            self._error(f"{self.teaching.failure}; the running model stays")

    def _apply_commands(self, timeout_s: float) -> None:
        """Apply every queued command, waiting up to ``timeout_s`` for the first."""
        try:
            command = self._commands.get(timeout=timeout_s)
        except queue.Empty:
            return
        while True:
            self._apply_safely(command)
            try:
                command = self._commands.get_nowait()
            except queue.Empty:
                return

    def _apply_safely(self, command: dict[str, Any]) -> None:
        try:
            self._apply(command)
            self.last_error = None if command["type"] != "_wake" else self.last_error
        except RnnpbError as error:
            self._error(str(error))
        except Exception as error:  # keep serving whatever one command did
            log.exception("session: command %r failed", command)
            self._error(f"{command.get('type')} failed: {error}")
        self._publish_state()

    def _apply(self, command: dict[str, Any]) -> None:
        kind = command["type"]
        if kind == "_wake":
            return
        if kind == "model":
            self._load_model(command["name"])
        elif kind == "control":
            action = command["action"]
            if action == "start":
                if self.mirror is None:
                    raise ConfigError(
                        "no model is loaded" + (f": {self.model_error}" if self.model_error else "")
                    )
                if self.loop is None:
                    self._new_run()
                self.running = True
            elif action == "stop":
                self.running = False
            else:
                self._new_run()
        elif kind == "mode":
            self._set_mode(command["mode"])
        elif kind == "camera":
            self.camera_index = command["index"]
        elif kind == "perception":
            self._set_perception(command["perception"])
        elif kind == "pattern":
            self.demonstrator.perform(command["pattern"])
        elif kind == "teach_mode":
            self.teaching.set_mode(command["mode"])
        elif kind == "teach":
            if command["action"] == "confirm":
                self.teaching.confirm()
            else:
                self.teaching.undo()
        elif kind == "rename":
            self.teaching.rename(command["pattern"], command["name"])
        elif kind == "dt":
            self.dt = command["dt"]
            if self.loop is not None:
                self.loop.set_dt(self.dt)

    def _load_model(self, name: str) -> None:
        """Load and compile model ``name``; a running robot goes on running with it. A model
        that fails leaves the previous one (if any) in place, with the reason."""
        from rnnpb.model import MirrorSystem, TrainedModel

        if name not in self.models:
            raise ConfigError(f"no model {name!r} (this server offers: {', '.join(self.models)})")
        was_running = self.running
        self.running = False
        self.loading = True
        self.loading_model = name
        self._publish_state()
        try:
            from rnnpb.robot import JOINT_LIMITS

            model = TrainedModel.load(self.models[name], joint_limits=JOINT_LIMITS)
            # The regression that suits the model's learning (docs/model.md, "On-line
            # interaction"), with a --config file's values, as `rnnpb interact` picks it.
            choice = self.config_tables.choice_for(model)
            safety, risk = self._load_safety(self.models[name], model, choice.config)
            mirror = MirrorSystem(
                model, safety.config, recognition=choice.recognition, **safety.mirror_options
            )
            started = time.perf_counter()
            mirror.step(np.full(model.network.sensory_size, 0.5))  # compiles the step
            mirror.reset()
            log.info(
                "model %s ready with the %s on-line regression (%s; step compiled in %.1f s)",
                name,
                choice.name,
                choice.reason,
                time.perf_counter() - started,
            )
        except Exception as error:
            kept = f"; still using {self.model_name}" if self.model_name else ""
            self.model_error = f"model {name} cannot be used: {error}{kept}"
            self.running = was_running and self.mirror is not None
            raise ConfigError(self.model_error) from None
        finally:
            self.loading = False
            self.loading_model = None
        # Teaching first: whoever sees the new mirror sees its teaching too.
        self.teaching.open(self.models[name], model, mirror, safety, risk, name=name)
        self.model, self.mirror, self.model_name = model, mirror, name
        self.safety, self._risk_views = safety, risk
        self.model_error = None
        self._follower()  # the model's routine level, if a routine file was learned over it
        self._new_run()
        self.running = was_running

    def _keep_recording(self, path: Path) -> None:
        """Note a new recording file; delete the oldest beyond ``keep_files``."""
        self._recording_files.append(path)
        while len(self._recording_files) > self.recording_limits.keep_files:
            old = self._recording_files.popleft()
            with contextlib.suppress(FileNotFoundError):
                old.unlink()

    def _new_run(self) -> None:
        """Forget the interaction so far: fresh window, new loop and a new recording."""
        from rnnpb.interaction import InteractionLoop, LoopConfig

        self._close_run()
        if self.mirror is None:
            return
        self.mirror.reset()
        for follower, _ in self._followers.values():
            if follower is not None:
                follower.reset()
        with self._subscribers_lock:
            self._recent.clear()
            self._recordings += 1
        try:
            self.recorder = _Recording(self, self._recordings)
        except OSError as error:
            self.recorder = None
            self._error(f"cannot record this run: {error}; the robot runs without recording")
        command_filter = self.safety.command_filter if self.safety is not None else None
        if command_filter is not None:
            command_filter.reset()
        self.loop = InteractionLoop(
            self.mirror,
            self._source,
            robot=self.robot,
            recorder=self.recorder,
            config=LoopConfig(dt=self.dt, paced=True),
            command_filter=command_filter,
        )
        # The loop calls subscribers once a step's timings are complete, so the step message
        # carries this step's sections; teaching first, so that it carries its status too.
        self.teaching.attach(self.loop)
        self.loop.subscribe(self._publish_step)

    def _load_safety(self, path: Path, model, online) -> tuple[Any, dict[str, Any]]:
        """The model's safety (filter; map if beside it) and the risk on the PB plot's
        views, computed once per model (sent with the state message)."""
        from rnnpb.safety import online_safety, risk_views

        safety = online_safety(path, model, online, enabled=self.safety_enabled)
        log.info("%s", safety.note)
        views = {} if safety.safety_map is None else risk_views(safety.safety_map, model.pattern_pb)
        return safety, views

    def _safety_state(self) -> dict[str, Any]:
        """The ``safety`` part of the state message: what guards the robot, and the risk
        grids of the PB plot (empty without a map)."""
        if self.safety is None:
            return {"map": False, "guard": "off", "filter": False, "note": "", "risk": {}}
        return {**self.safety.to_dict(), "risk": self._risk_views}

    def _close_run(self) -> None:
        if self.recorder is not None:
            self.recorder.close()
        self.loop = None

    def _set_mode(self, mode: str) -> None:
        if mode == self.mode:
            return
        if mode == "webcam":
            self._open_webcam()
        else:
            self._source.inner = self.pointer if mode == "pointer" else self.demonstrator
            self._close_webcam()
        self.mode = mode

    def _open_webcam(self) -> None:
        from rnnpb.perception import open_camera_source

        webcam = open_camera_source("webcam", self.camera_index, perception=self.perception)
        try:
            webcam.connect()
        except RnnpbError as error:
            webcam.close()
            raise RnnpbError(f"no camera: {error}") from None
        self._close_webcam()
        self._webcam = webcam
        self._source.inner = webcam

    def _set_perception(self, perception: str) -> None:
        """Balls or bare hands; an open webcam is opened again with the new tracker (and kept
        as it was when that fails)."""
        if perception == self.perception:
            return
        from rnnpb.perception import HANDS_INSTALL, pose_available

        if perception == "pose" and not pose_available():
            raise RnnpbError(f"bare hands need the pose model: {HANDS_INSTALL}")
        previous, self.perception = self.perception, perception
        if self.mode == "webcam":
            try:
                self._open_webcam()
            except RnnpbError:
                self.perception = previous
                raise

    def _close_webcam(self) -> None:
        if self._webcam is not None:
            self._webcam.close()
            self._webcam = None

    def _publish_step(self, record) -> None:
        from rnnpb.robot import forward_kinematics

        hands, elbows = forward_kinematics(record.motor)
        nearest, distance = self.model.nearest_pattern(record.pb)
        message = {
            "type": "step",
            "step": record.step,
            "time_s": round(record.time_s, 4),
            "mode": self.mode,
            "observed": _listed(record.observed),
            "predicted": _listed(record.predicted),
            "predicted_next": _listed(record.predicted_next),
            "motor": _listed(record.motor),
            "pb": _listed(record.pb),
            "nearest": nearest,
            "nearest_distance": distance,
            # What the step recognised (rnnpb.model.recognition): the readout says "not sure"
            # or "new movement" rather than a confident wrong name.
            "recognised": record.recognised,
            "confidence": round(float(record.confidence), 4),
            "novelty": record.novelty,
            "pattern_confidence": {
                k: round(float(v), 4) for k, v in record.pattern_confidence.items()
            },
            "prediction_error": _listed([record.prediction_error])[0],
            "window_error": _listed([record.window_error])[0],
            "held": record.held,
            "truth": str(record.truth.get("pattern", "")),
            "dt": self.dt,
            "user_hands": self._user_view.hands(record.observed),
            "arms": {"elbows": np.round(elbows, 5).tolist(), "hands": np.round(hands, 5).tolist()},
            "timings_ms": {k: round(v * 1e3, 3) for k, v in record.timings.items()},
            "missed_deadlines": self.loop.missed_deadlines if self.loop is not None else 0,
            "teaching": self.teaching.status(),
            **self._step_safety(record),
            **self._step_routine(record),
        }
        self._publish(message)
        if record.frame is not None and self._webcam is not None:
            self._publish_frame(record.frame)

    def _step_safety(self, record) -> dict[str, Any]:
        """The step message's safety fields: why the generated command was unsafe (empty
        when safe), what the filter did, and how many commands it has changed this run; what
        drove the motion (``regime``) and why the meta-level held the command (``inhibited``,
        empty when sent), and how many it has held this run."""
        return {
            "unsafe": record.unsafe,
            "filtered": record.filtered,
            "prevented": self.loop.prevented_commands if self.loop is not None else 0,
            "regime": record.regime,
            "inhibited": record.inhibited,
            "inhibited_count": self.loop.inhibited_commands if self.loop is not None else 0,
        }

    def _follower(self) -> tuple[Any, str]:
        """The routine level of the running model version (a
        :class:`~rnnpb.model.routines.RoutineFollower`, or None) and a line on it: a routine
        file applies to the model it was learned over only, so a version made by teaching
        runs without one (and an Undo back to that model finds it again). Made on the
        session thread only."""
        from rnnpb.model.routines import RoutineFollower, RoutineModel

        model = self.model
        if model is None or not self.routine_files:
            return None, ""
        known = self._followers.get(model.fingerprint)
        if known is not None:
            return known
        found: tuple[Any, str] = (
            None,
            f"no routine file was learned over {self.model_name} (given: "
            f"{', '.join(p.name for p in self.routine_files)}, over other models)",
        )
        for path in self.routine_files:
            try:
                routines = RoutineModel.load(path)
            except RnnpbError as error:  # checked when the server started; gone since
                log.warning("routine file %s: %s", path, error)
                continue
            if routines.lower_fingerprint == model.fingerprint:
                names = ", ".join(routines.routines)
                found = (RoutineFollower(routines), f"routines of {path.name}: {names}")
                break
        self._followers[model.fingerprint] = found
        return found

    def _routines_state(self) -> dict[str, Any]:
        """The ``routines`` part of the state message: whether a routine level runs, and
        a line on it (empty when the server was given no routine file)."""
        model = self.model
        known = self._followers.get(model.fingerprint) if model is not None else None
        if known is None:  # made on the session thread when the model first steps or loads
            return {"on": False, "note": ""}
        return {"on": known[0] is not None, "note": known[1]}

    def _step_routine(self, record) -> dict[str, Any]:
        """The step message's routine fields (docs/routines.md): the routine recognised
        (empty: none) and the movement it says comes next, with the steps left until then;
        no fields without a routine level for the running model."""
        follower, _ = self._follower()
        model = self.model
        if follower is None or model is None:
            return {}
        said = follower.observe(np.asarray(record.pb, dtype=np.float64))
        anticipated = ""
        if said.routine is not None:
            anticipated = model.nearest_pattern(said.predicted_pb)[0]
        steps_left = said.steps_left if said.routine is not None else None
        return {
            "routine": said.routine or "",
            "anticipated": anticipated,
            "switch_due": bool(said.switch_due),
            "steps_left": None if steps_left is None else round(float(steps_left), 1),
        }

    def _publish_frame(self, frame: np.ndarray) -> None:
        import cv2

        from rnnpb.perception import draw_tracking

        result = getattr(self._webcam, "last_result", None)
        image = draw_tracking(frame, result) if result is not None else frame
        height = int(round(image.shape[0] * FRAME_WIDTH / image.shape[1]))
        image = cv2.resize(image, (FRAME_WIDTH, height), interpolation=cv2.INTER_AREA)
        ok, jpeg = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 70])
        if ok:
            self._publish(
                {"type": "frame", "jpeg": base64.b64encode(jpeg.tobytes()).decode("ascii")}
            )
