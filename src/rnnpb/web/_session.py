"""The dashboard's one shared interaction session.

All browser tabs observe the same session. The session composes parts of one job each, none
reaching into another:

- the thread and its command queue (:mod:`rnnpb.web._thread`): control messages are applied
  one at a time, between two steps while the loop runs;
- the models and versions offered, and the one made ready and running
  (:mod:`rnnpb.web._models`, safety included);
- teaching (:mod:`rnnpb.web._teaching`), which swaps a version it learned in through
  :meth:`Session.swap`;
- the webcam (:mod:`rnnpb.web._webcam`), the routine level (:mod:`rnnpb.web._routines`),
  the recordings (:mod:`rnnpb.web._recording`);
- what the pages are told (:mod:`rnnpb.web._broadcast`, the step message
  :mod:`rnnpb.web._steps`).

Pointer positions go straight to the :class:`PointerSource` (the newest position wins). The
loop drives itself (:class:`rnnpb.interaction.InteractionLoop`); the session subscribes to
its step records and publishes one JSON message per step to its subscribers (the WebSocket
connections), which only observe.

Nothing a step or a command raises ends the session thread: a failed step stops the robot
and says why on every page (``error`` message, ``state.error``), a failed recording turns
recording off and the robot goes on, and later commands are applied as before. Recordings are
bounded (:class:`RecordingLimits`) and the session removes what it made (docs/robustness.md,
"The dashboard's session: errors, recordings, command limits").
"""

from __future__ import annotations

import logging
import secrets
import shutil
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rnnpb.errors import ConfigError, RnnpbError
from rnnpb.presets import Overrides
from rnnpb.web._broadcast import RECENT_STEPS, Broadcast
from rnnpb.web._handover import Handover
from rnnpb.web._models import ModelShelf, ReadyModel, find_models, offered_models
from rnnpb.web._recording import Recording, RecordingLimits, Recordings
from rnnpb.web._routines import RoutineLevel
from rnnpb.web._sources import PAUSE, DemonstratorSource, PointerSource, SwitchableSource
from rnnpb.web._steps import UserView, listed, step_message
from rnnpb.web._teaching import SessionTeaching, TeachingSettings
from rnnpb.web._thread import MAX_QUEUED_COMMANDS, SessionThread
from rnnpb.web._webcam import FRAME_WIDTH, Webcam

if TYPE_CHECKING:
    from rnnpb.robot import Robot

__all__ = [
    "FRAME_WIDTH",
    "MAX_QUEUED_COMMANDS",
    "RECENT_STEPS",
    "RecordingLimits",
    "Session",
    "find_models",
    "offered_models",
]

log = logging.getLogger("rnnpb.web")


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
    overrides : Overrides, optional
        A ``--config`` file (``rnnpb serve --config``), put over the on-line regression and
        recognition chosen for each model and over teaching's settings; read when a model
        loads.
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
        overrides: Overrides | None = None,
        routines: Sequence[str | Path] = (),
    ) -> None:
        import tempfile

        self.shelf = ModelShelf(models)
        self.shelf.overrides = overrides
        self.dt = float(dt)
        self.temporary_workdir = workdir is None
        self.workdir = Path(workdir or tempfile.mkdtemp(prefix="rnnpb-serve-"))
        self.recordings = Recordings(self.workdir, recording_limits or RecordingLimits())
        self.pointer = PointerSource()
        self.demonstrator = DemonstratorSource()
        self.webcam = Webcam()
        self.mode = "demonstrator"
        self.running = False
        self.loop = None
        self.recorder: Recording | None = None
        self.last_error: str | None = None
        self.broadcast = Broadcast()
        self.routines = RoutineLevel([Path(p) for p in routines])
        # A connected robot the loop also drives (`rnnpb serve --robot`; docs/bridge.md);
        # None: the page's simulated humanoid only.
        self.robot: Robot | None = None
        self.teaching = SessionTeaching(self, teaching or TeachingSettings())
        self._source = SwitchableSource(self.demonstrator)
        self._user_view = UserView()
        self._last_command: np.ndarray | None = None  # the run's last motor command sent
        # Names this server's runs, so a page that reconnects to a restarted server knows
        # its plots belong to another run even when the run numbers coincide.
        self._token = secrets.token_hex(4)
        self._thread = SessionThread(
            self._apply_safely, self._idle, self._stopped, max_queued=max_queued_commands
        )
        self._thread.source_name = self.mode

    # --- what the parts hold, by the names the command line and the tests use -------------
    @property
    def models(self) -> dict[str, Path]:
        return self.shelf.offered

    @property
    def model_name(self) -> str | None:
        return self.shelf.name

    @property
    def model(self):
        return self.shelf.running.model if self.shelf.running is not None else None

    @property
    def mirror(self):
        return self.shelf.running.mirror if self.shelf.running is not None else None

    @property
    def safety(self):
        """The running model's :class:`rnnpb.safety.OnlineSafety` (None before one loads)."""
        return self.shelf.running.safety if self.shelf.running is not None else None

    @property
    def loading(self) -> bool:
        return self.shelf.loading is not None

    @property
    def loading_model(self) -> str | None:
        return self.shelf.loading

    @property
    def model_error(self) -> str | None:
        return self.shelf.error

    @property
    def safety_enabled(self) -> bool:
        """The command filter always and the model's map when one lies beside it (docs/
        safety.md); ``rnnpb serve --no-safety`` sets it False before :meth:`start`."""
        return self.shelf.safety_enabled

    @safety_enabled.setter
    def safety_enabled(self, enabled: bool) -> None:
        self.shelf.safety_enabled = enabled

    @property
    def overrides(self) -> Overrides | None:
        return self.shelf.overrides

    @overrides.setter
    def overrides(self, overrides: Overrides | None) -> None:
        self.shelf.overrides = overrides

    @property
    def routine_files(self) -> list[Path]:
        return self.routines.files

    @routine_files.setter
    def routine_files(self, files: list[Path]) -> None:
        self.routines = RoutineLevel(files)

    @property
    def perception(self) -> str:
        """How the webcam's frames become hands: ``balls`` or ``pose``."""
        return self.webcam.perception

    @perception.setter
    def perception(self, perception: str) -> None:
        self.webcam.perception = perception

    @property
    def camera_index(self) -> int:
        return self.webcam.index

    @property
    def recording_limits(self) -> RecordingLimits:
        return self.recordings.limits

    # --- life cycle -----------------------------------------------------------------------
    def start(self, model_name: str | None = None) -> None:
        """Start the session thread and load the first model in it."""
        self._thread.submit({"type": "model", "name": model_name or self.shelf.first})
        self._thread.start()

    def close(self) -> None:
        """Stop the session thread, close the recording and the camera, and delete the
        session's own temporary folder (a ``workdir`` given by the caller is left, with at
        most ``recording_limits.keep_files`` recordings in it)."""
        self._thread.close()
        self.teaching.close()
        self._close_run()
        self.webcam.close()
        if self.temporary_workdir:
            shutil.rmtree(self.workdir, ignore_errors=True)

    # --- what clients use -----------------------------------------------------------------
    def submit(self, command: dict[str, Any]) -> bool:
        """Queue a validated control message for the session thread; ``False`` (and nothing
        queued) when :data:`MAX_QUEUED_COMMANDS` are already waiting."""
        return self._thread.submit(command)

    def subscribe(
        self, callback: Callable[[str], None], replay: bool = False
    ) -> Callable[[], None]:
        """``callback(json_text)`` for every message the session publishes.

        With ``replay``, ``callback`` first gets the state and a ``history`` message with the
        current run's last :data:`RECENT_STEPS` steps, so a new tab starts with full plots;
        no step is both replayed and published to it, nor missed.
        """
        return self.broadcast.subscribe(
            callback, (lambda: (self.state(), self.run_id)) if replay else None
        )

    @property
    def subscriber_count(self) -> int:
        return self.broadcast.count

    @property
    def run_id(self) -> str:
        """Names the current run (changes at every Reset, model change and server start)."""
        return f"{self._token}-{self.broadcast.run}"

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
        return self.recordings.files

    def state(self) -> dict[str, Any]:
        """The session's state as the ``state`` message carries it."""
        from rnnpb.demonstrator import MOVEMENT_DESCRIPTIONS, UserBody
        from rnnpb.robot import FOREARM_LENGTH, JOINT_LIMITS, SHOULDERS, UPPER_ARM_LENGTH
        from rnnpb.vectors import MOTOR_NAMES

        running = self.shelf.running
        model = running.model if running is not None else None
        learned = list(model.patterns) if model is not None else []
        recording = self.recording_path
        demonstrator = self.demonstrator
        return {
            "type": "state",
            "models": list(self.shelf.offered),
            "model": self.shelf.name,
            "loading": self.loading,
            "loading_model": self.shelf.loading,
            "running": self.running,
            "run": self.run_id,
            "mode": self.mode,
            "dt": self.dt,
            "camera_index": self.webcam.index,
            "perception": self.webcam.perception,
            "demonstrator_pattern": PAUSE if demonstrator.paused else demonstrator.pattern,
            "patterns": learned,
            "demonstrator_patterns": list(demonstrator.patterns),
            "novel_patterns": [p for p in demonstrator.patterns if p not in learned],
            "pattern_pb": {k: listed(v) for k, v in model.pattern_pb.items()}
            if model is not None
            else {},
            "steps": self.loop.steps if self.loop is not None else 0,
            "recording": recording is not None and recording.exists(),
            "recording_error": self.recorder.failed if self.recorder is not None else None,
            "error": self.last_error,
            "model_error": self.shelf.error,
            "rest_hands": listed(self._user_view.rest),
            "user_shoulders": UserBody().shoulders.tolist(),
            "robot": {
                "shoulders": SHOULDERS.tolist(),
                "upper_arm": UPPER_ARM_LENGTH,
                "forearm": FOREARM_LENGTH,
                "joint_limits": JOINT_LIMITS.tolist(),
                "joint_names": list(MOTOR_NAMES),
            },
            "safety": running.safety_state() if running is not None else ReadyModel.no_safety(),
            "movement_descriptions": {
                p: MOVEMENT_DESCRIPTIONS.get(p, "") for p in demonstrator.patterns
            },
            "teaching": self.teaching.state(),
            "routines": self.routines.state(model),
        }

    # --- what teaching uses (rnnpb.web._teaching.TeachingHost) ----------------------------
    def hands_3d(self) -> np.ndarray | None:
        """The webcam's last hands in 3-D (from the balls' size); None while it is closed."""
        return self.webcam.hands_3d()

    def swap(self, ready: ReadyModel) -> None:
        """Run ``ready`` (a version teaching made ready, gone on from the running interaction)
        from the next step on, between two steps on the session thread: the running loop hands
        over to its mirror system over a few steps, so the arm does not jump
        (:mod:`rnnpb.web._handover`)."""
        from rnnpb.robot import joint_step_limit

        old = self.shelf.running
        self.shelf.run(ready)
        if self.loop is None:
            return
        if old is None or old.mirror is ready.mirror:
            self.loop.mirror = ready.mirror
            return
        step = joint_step_limit(self.loop.config.dt)
        self.loop.mirror = Handover(old.mirror, ready.mirror, self._last_command, step)

    def report(self, text: str) -> None:
        """Say ``text`` on every page as the session's error (and in the log)."""
        log.warning("session: %s", text)
        self.last_error = text
        self.broadcast.publish({"type": "error", "message": text})

    def publish_state(self) -> None:
        self.broadcast.publish(self.state())

    # --- the session thread ---------------------------------------------------------------
    def _idle(self) -> float:
        self.teaching.between_steps()
        return 0.1 if self.teaching.teacher else 0.5

    def _stopped(self, reason: str) -> None:
        self.running = False
        self.report(reason)
        self.publish_state()

    def _apply_safely(self, command: dict[str, Any]) -> None:
        try:
            self._apply(command)
            self.last_error = None
        except RnnpbError as error:
            self.report(str(error))
        except Exception as error:  # keep serving whatever one command did
            log.exception("session: command %r failed", command)
            self.report(f"{command.get('type')} failed: {error}")
        self._thread.loop = self.loop if self.running else None
        self.publish_state()

    def _apply(self, command: dict[str, Any]) -> None:
        """Apply one control message (on the session thread); raises what it cannot do."""
        kind = command["type"]
        if kind == "model":
            self._load_model(command["name"])
        elif kind == "control":
            action = command["action"]
            if action == "start":
                if self.mirror is None:
                    error = self.shelf.error
                    raise ConfigError("no model is loaded" + (f": {error}" if error else ""))
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
            self.webcam.index = command["index"]
        elif kind == "perception":
            opened = self.webcam.set_perception(command["perception"])
            if opened is not None:
                self._source.inner = opened
        elif kind == "pattern":
            self.demonstrator.perform(command["pattern"])
        elif kind == "teach_mode":
            self.teaching.set_mode(command["mode"])
        elif kind == "teach":
            if command["action"] == "confirm":
                self.teaching.confirm(command.get("pattern"))
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
        was_running = self.running
        self.running = False
        try:
            ready = self.shelf.load(name, announce=self.publish_state)
        except ConfigError:
            self.running = was_running and self.shelf.running is not None
            raise
        # Teaching first: whoever sees the new mirror sees its teaching too.
        self.teaching.open(ready, name=name)
        self.shelf.run(ready, name)
        # a person's bare hands framed as the model learned people
        try:
            opened = self.webcam.frame_for(ready.model.framing)
        except RnnpbError as error:
            self.report(f"the camera could not be opened again for the model's framing: {error}")
        else:
            if self.mode == "webcam" and opened is not None:
                self._source.inner = opened
        self.routines.follower(ready.model, name)  # the model's routine level, if any
        self._new_run()
        self.running = was_running

    def _new_run(self) -> None:
        """Forget the interaction so far: fresh window, new loop and a new recording."""
        from rnnpb.interaction import InteractionLoop, LoopConfig

        self._close_run()
        running = self.shelf.running
        if running is None:
            return
        running.mirror.reset()
        self.routines.reset()
        self._last_command = None
        run = self.broadcast.new_run()
        try:
            self.recorder = self.recordings.start(run, running.model.network.pb_size, self.report)
        except OSError as error:
            self.recorder = None
            self.report(f"cannot record this run: {error}; the robot runs without recording")
        command_filter = running.safety.command_filter if running.safety is not None else None
        if command_filter is not None:
            command_filter.reset()
        self.loop = InteractionLoop(
            running.mirror,
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

    def _close_run(self) -> None:
        if self.recorder is not None:
            self.recorder.close()
        self.loop = None

    def _set_mode(self, mode: str) -> None:
        if mode == self.mode:
            return
        if mode == "webcam":
            self._source.inner = self.webcam.open()
        else:
            self._source.inner = self.pointer if mode == "pointer" else self.demonstrator
            self.webcam.close()
        self.mode = mode
        self._thread.source_name = mode

    def _publish_step(self, record) -> None:
        self._last_command = record.motor
        model = self.model
        message = step_message(
            record, model=model, loop=self.loop, mode=self.mode, dt=self.dt, view=self._user_view
        )
        message["teaching"] = self.teaching.status()
        message.update(self.routines.step_fields(record, model, self.shelf.name))
        self.broadcast.publish(message)
        if record.frame is not None and self.webcam.is_open:
            frame = self.webcam.frame_message(record.frame)
            if frame is not None:
                self.broadcast.publish(frame)
