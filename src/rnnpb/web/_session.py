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
"""

from __future__ import annotations

import base64
import json
import logging
import math
import queue
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb.errors import ConfigError, RnnpbError
from rnnpb.sources import UserSource
from rnnpb.web._sources import PAUSE, DemonstratorSource, PointerSource, SwitchableSource

log = logging.getLogger("rnnpb.web")

FRAME_WIDTH = 320
"""Width (pixels) of the camera image sent to the page."""


def find_models(model_or_dir: str | Path) -> dict[str, Path]:
    """The models ``--model`` offers: a ``.npz`` file, or every ``*.npz`` under a folder."""
    path = Path(model_or_dir)
    if path.is_file():
        return {path.name: path}
    if path.is_dir():
        # A model's safety map (M.safety.npz, docs/safety.md) lies beside it: not a model.
        found = sorted(p for p in path.rglob("*.npz") if not p.name.endswith(".safety.npz"))
        if not found:
            raise ConfigError(f"{path}: no model files (*.npz) in this folder; train one with "
                              "`rnnpb train`")
        return {str(p.relative_to(path)): p for p in found}
    raise ConfigError(f"{path}: no such model file or folder")


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
    workdir : path
        Where session recordings are written.
    """

    def __init__(self, models: dict[str, Path], dt: float = 0.4,
                 workdir: str | Path | None = None) -> None:
        if not models:
            raise ConfigError("the dashboard needs at least one model")
        import tempfile

        self.models = dict(models)
        self.dt = float(dt)
        self._own_workdir = workdir is None
        self.workdir = Path(workdir or tempfile.mkdtemp(prefix="rnnpb-serve-"))
        self.pointer = PointerSource()
        self.demonstrator = DemonstratorSource()
        self.camera_index = 0
        self.mode = "demonstrator"
        self.running = False
        self.loading = False
        self.model_name: str | None = None
        self.model = None
        self.mirror = None
        self.loop = None
        self.recorder = None
        self.recording_path: Path | None = None
        self.last_error: str | None = None
        self._webcam: UserSource | None = None
        self._source = SwitchableSource(self.demonstrator)
        self._user_view = _UserView()
        self._commands: queue.Queue[dict[str, Any]] = queue.Queue()
        self._subscribers: list[Callable[[str], None]] = []
        self._subscribers_lock = threading.Lock()
        self._closed = threading.Event()
        self._thread: threading.Thread | None = None
        self._recordings = 0
        # Safety (docs/safety.md): the command filter always and the model's map when one
        # lies beside it; ``rnnpb serve --no-safety`` sets this False before start().
        self.safety_enabled = True
        self.safety = None  # rnnpb.safety.OnlineSafety of the loaded model
        self._risk_views: dict[str, Any] = {}

    # --- life cycle -----------------------------------------------------------------------
    def start(self, model_name: str | None = None) -> None:
        """Start the session thread and load the first model in it."""
        name = model_name or next(iter(self.models))
        self._commands.put({"type": "model", "name": name})
        self._thread = threading.Thread(target=self._run, name="rnnpb-session", daemon=True)
        self._thread.start()

    def close(self) -> None:
        self._closed.set()
        self._commands.put({"type": "_wake"})
        if self._thread is not None:
            self._thread.join(timeout=10)
        self._close_run()
        self._close_webcam()

    # --- what clients use -----------------------------------------------------------------
    def submit(self, command: dict[str, Any]) -> None:
        """Queue a validated control message for the session thread."""
        self._commands.put(command)

    def subscribe(self, callback: Callable[[str], None]) -> Callable[[], None]:
        """``callback(json_text)`` for every message the session publishes."""
        with self._subscribers_lock:
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

    def state(self) -> dict[str, Any]:
        """The session's state as the ``state`` message carries it."""
        from rnnpb.robot import FOREARM_LENGTH, JOINT_LIMITS, SHOULDERS, UPPER_ARM_LENGTH
        from rnnpb.vectors import MOTOR_NAMES

        model = self.model
        learned = list(model.patterns) if model is not None else []
        return {
            "type": "state",
            "models": list(self.models),
            "model": self.model_name,
            "loading": self.loading,
            "running": self.running,
            "mode": self.mode,
            "dt": self.dt,
            "camera_index": self.camera_index,
            "demonstrator_pattern": PAUSE if self.demonstrator.paused
            else self.demonstrator.pattern,
            "patterns": learned,
            "novel_patterns": [p for p in self.demonstrator.patterns if p not in learned],
            "pattern_pb": {k: _listed(v) for k, v in model.pattern_pb.items()}
            if model is not None else {},
            "steps": self.loop.steps if self.loop is not None else 0,
            "recording": self.recording_path is not None and self.recording_path.exists(),
            "error": self.last_error,
            "rest_hands": _listed(self._user_view.rest),
            "robot": {"shoulders": SHOULDERS.tolist(), "upper_arm": UPPER_ARM_LENGTH,
                      "forearm": FOREARM_LENGTH, "joint_limits": JOINT_LIMITS.tolist(),
                      "joint_names": list(MOTOR_NAMES)},
            "safety": self._safety_state(),
        }

    # --- the session thread ---------------------------------------------------------------
    def _publish(self, message: dict[str, Any]) -> None:
        text = json.dumps(message, separators=(",", ":"))
        with self._subscribers_lock:
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
            loop = self.loop
            if self.running and loop is not None:
                self._drive(loop)
            else:
                self._apply_commands(timeout_s=0.5)

    def _drive(self, loop) -> None:
        """Let ``loop`` run (it paces itself) until a command stops or replaces it, the session
        closes, or its source ends or fails; the queued commands are applied between steps."""

        def between_steps(wait_s: float) -> None:
            self._apply_commands(timeout_s=wait_s)
            if self._closed.is_set() or not self.running or self.loop is not loop:
                loop.stop()

        try:
            loop.run(between_steps=between_steps)
        except RnnpbError as error:
            self.running = False
            self._error(f"the {self.mode} source failed: {error}")
            self._publish_state()
            return
        if self.running and self.loop is loop and not self._closed.is_set():
            self.running = False
            self._error(f"the {self.mode} source has ended")
            self._publish_state()

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
                    raise ConfigError("no model is loaded yet")
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
        elif kind == "pattern":
            self.demonstrator.perform(command["pattern"])
        elif kind == "dt":
            self.dt = command["dt"]
            if self.loop is not None:
                self.loop.set_dt(self.dt)

    def _load_model(self, name: str) -> None:
        from rnnpb.model import MirrorSystem, OnlineConfig, TrainedModel

        if name not in self.models:
            raise ConfigError(f"no model {name!r} (this server offers: "
                              f"{', '.join(self.models)})")
        self.running = False
        self.loading = True
        self._publish_state()
        try:
            from rnnpb.robot import JOINT_LIMITS

            model = TrainedModel.load(self.models[name], joint_limits=JOINT_LIMITS)
            safety, risk = self._load_safety(self.models[name], model, OnlineConfig())
            mirror = MirrorSystem(model, safety.config, meta=safety.meta)
            started = time.perf_counter()
            mirror.step(np.full(model.network.sensory_size, 0.5))  # compiles the step
            mirror.reset()
            log.info("model %s ready (step compiled in %.1f s)", name,
                     time.perf_counter() - started)
        finally:
            self.loading = False
        self.model, self.mirror, self.model_name = model, mirror, name
        self.safety, self._risk_views = safety, risk
        self._new_run()

    def _new_run(self) -> None:
        """Forget the interaction so far: fresh window, new loop and a new recording."""
        from rnnpb.interaction import InteractionLoop, LoopConfig, SessionRecorder

        self._close_run()
        if self.mirror is None:
            return
        self.mirror.reset()
        self._recordings += 1
        self.recording_path = self.workdir / f"session-{self._recordings:03d}.csv"
        self.recorder = SessionRecorder(self.recording_path, self.model.network.pb_size)
        self.recorder.open()
        command_filter = self.safety.command_filter if self.safety is not None else None
        if command_filter is not None:
            command_filter.reset()
        self.loop = InteractionLoop(self.mirror, self._source, recorder=self.recorder,
                                    config=LoopConfig(dt=self.dt, paced=True),
                                    command_filter=command_filter)
        # The loop calls subscribers once a step's timings are complete, so the step message
        # carries this step's sections.
        self.loop.subscribe(self._publish_step)

    def _load_safety(self, path: Path, model, online) -> tuple[Any, dict[str, Any]]:
        """The model's safety (filter; map if beside it) and the risk on the PB plot's
        views, computed once per model (sent with the state message)."""
        from rnnpb.safety import online_safety, risk_views

        safety = online_safety(path, model, online, enabled=self.safety_enabled)
        log.info("%s", safety.note)
        views = ({} if safety.safety_map is None
                 else risk_views(safety.safety_map, model.pattern_pb))
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
            self.recorder = None
        self.loop = None

    def _set_mode(self, mode: str) -> None:
        if mode == self.mode:
            return
        if mode == "webcam":
            from rnnpb.perception import open_camera_source

            webcam = open_camera_source("webcam", self.camera_index)
            try:
                webcam.connect()
            except RnnpbError as error:
                webcam.close()
                raise RnnpbError(f"no camera: {error}") from None
            self._close_webcam()
            self._webcam = webcam
            self._source.inner = webcam
        else:
            self._source.inner = self.pointer if mode == "pointer" else self.demonstrator
            self._close_webcam()
        self.mode = mode

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
            "prediction_error": _listed([record.prediction_error])[0],
            "window_error": _listed([record.window_error])[0],
            "held": record.held,
            "truth": str(record.truth.get("pattern", "")),
            "dt": self.dt,
            "user_hands": self._user_view.hands(record.observed),
            "arms": {"elbows": np.round(elbows, 5).tolist(), "hands": np.round(hands, 5).tolist()},
            "timings_ms": {k: round(v * 1e3, 3) for k, v in record.timings.items()},
            "missed_deadlines": self.loop.missed_deadlines if self.loop is not None else 0,
            **self._step_safety(record),
        }
        self._publish(message)
        if record.frame is not None and self._webcam is not None:
            self._publish_frame(record.frame)

    def _step_safety(self, record) -> dict[str, Any]:
        """The step message's safety fields: why the generated command was unsafe (empty
        when safe), what the filter did, and how many commands it has changed this run."""
        return {"unsafe": record.unsafe, "filtered": record.filtered,
                "prevented": self.loop.prevented_commands if self.loop is not None else 0}

    def _publish_frame(self, frame: np.ndarray) -> None:
        import cv2

        from rnnpb.perception import draw_tracking

        result = getattr(self._webcam, "last_result", None)
        image = draw_tracking(frame, result) if result is not None else frame
        height = int(round(image.shape[0] * FRAME_WIDTH / image.shape[1]))
        image = cv2.resize(image, (FRAME_WIDTH, height), interpolation=cv2.INTER_AREA)
        ok, jpeg = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 70])
        if ok:
            self._publish({"type": "frame",
                           "jpeg": base64.b64encode(jpeg.tobytes()).decode("ascii")})
