"""The mirror game (``/game``): a person finds the robot's movements, or two robots play.

The person moves two points with the mouse or the fingers (the hands, as the robot's camera
would see them); the robot (:class:`rnnpb.interaction.dyad.RobotAgent`) follows what it
recognises and takes the initiative on its own — another of its patterns after a stable while
(its persistence), or when it is left alone. In ``robots`` mode two robots with the same model
play with each other. Each step publishes the synchrony meter, the patterns found so far, who
led the last switch and the time (docs/dashboard.md, "The mirror game").
"""

from __future__ import annotations

import contextlib
import json
import logging
import math
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb.analysis import dyad as measures
from rnnpb.interaction.dyad import AgentConfig, AgentStep, Dyad, RobotAgent, robot_pair
from rnnpb.model.io import TrainedModel

log = logging.getLogger("rnnpb.web")

GAME_MODES = ("person", "robots")
HISTORY = 240  # steps of both agents kept for the measures (96 s at 0.4 s)
PERSISTENCE = 60  # stable steps (24 s at 0.4 s) after which the robot tries another pattern
METER_SCALE = 0.1  # synchrony error (view units) at which the meter shows 0


class PersonAgent:
    """The person at the page: shows the hands the page last sent (NaN until placed)."""

    name = "person"

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._hands_view = np.full(4, np.nan)

    def set_view(self, values: list[float]) -> None:
        with self._lock:
            self._hands_view = np.asarray(values, dtype=np.float64)

    @property
    def view(self) -> np.ndarray:
        with self._lock:
            return self._hands_view.copy()

    def act(self, view: np.ndarray) -> AgentStep:
        return AgentStep(hands=np.full((2, 3), np.nan), view=np.asarray(view, dtype=np.float64))


class _PersonDyad(Dyad):
    """A dyad whose second agent is seen directly as the page's view values."""

    def view(self, of: Any) -> np.ndarray:
        if isinstance(of, PersonAgent):
            return of.view
        return super().view(of)


class GameSession:
    """Runs the game in a thread, paced at ``dt``; publishes one JSON message per step."""

    def __init__(self, models: dict[str, Path], dt: float = 0.4) -> None:
        self.models = dict(models)
        self.dt = dt
        self.person = PersonAgent()
        self._subscribers: list[Callable[[str], None]] = []
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self.mode = "person"
        self.model_name: str | None = None
        self.status = "stopped"

    # --- the page's commands -----------------------------------------------------------
    def submit(self, message: dict[str, Any]) -> None:
        if message["type"] == "game_hands":
            self.person.set_view(message["hands"])
        elif message["action"] == "stop":
            self.stop()
        else:
            self.start(message["mode"], message.get("model"))

    def start(self, mode: str, model: str | None = None) -> None:
        self.stop()
        name = model if model in self.models else next(iter(self.models))
        self.mode, self.model_name = mode, name
        self._stop.clear()
        self._thread = threading.Thread(
            target=self._run, args=(mode, name), daemon=True, name="rnnpb-game"
        )
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        thread, self._thread = self._thread, None
        if thread is not None:
            thread.join(timeout=10)
        self.status = "stopped"

    def subscribe(self, callback: Callable[[str], None]) -> Callable[[], None]:
        with self._lock:
            self._subscribers.append(callback)

        def unsubscribe() -> None:
            with self._lock, contextlib.suppress(ValueError):
                self._subscribers.remove(callback)

        return unsubscribe

    def state(self) -> dict[str, Any]:
        return {
            "type": "game_state",
            "status": self.status,
            "mode": self.mode,
            "model": self.model_name,
            "models": list(self.models),
        }

    def _publish(self, message: dict[str, Any]) -> None:
        text = json.dumps(message, allow_nan=False)
        with self._lock:
            subscribers = list(self._subscribers)
        for callback in subscribers:
            callback(text)

    # --- the game ----------------------------------------------------------------------
    def _run(self, mode: str, name: str) -> None:
        try:
            self.status = "starting"
            self._publish(self.state())
            model = TrainedModel.load(self.models[name])
            robot = AgentConfig(persistence=PERSISTENCE, patience=None)
            if mode == "robots":
                dyad = robot_pair(
                    model,
                    model,
                    robot,
                    AgentConfig(persistence=PERSISTENCE, patience=6),
                    seed=int(time.time()),
                )
            else:
                dyad = _PersonDyad(RobotAgent(model, robot, name="robot"), self.person)
            tracker = _Tracker(model.patterns, mode)
            self.status = "running"
            self._publish(self.state())
            started = time.perf_counter()
            dyad.run(
                10**9,
                dt=self.dt,
                paced=True,
                should_stop=self._stop.is_set,
                between_steps=lambda wait: self._stop.wait(min(wait, 0.05)),
                on_step=lambda record: self._publish(
                    tracker.update(record, time.perf_counter() - started)
                ),
            )
        except Exception as error:  # the page says what went wrong; the server stays up
            log.exception("the game stopped")
            self._publish({"type": "game_error", "message": str(error)[:300]})
        finally:
            self.status = "stopped"
            self._publish(self.state())


class _Tracker:
    """Keeps the recent steps of both agents and measures them for the page."""

    def __init__(self, learned: tuple[str, ...], mode: str) -> None:
        self.learned = learned
        self.names = ("robot", "you") if mode == "person" else ("robot A", "robot B")
        self.templates = measures.movement_templates()
        self.shown: list[tuple[np.ndarray, np.ndarray]] = []
        self.found: list[str] = []
        self.last_leader = ""
        self.episodes_seen = 0

    def update(self, record: Any, elapsed: float) -> dict[str, Any]:
        self.shown.append((record.shown_a, record.shown_b))
        del self.shown[:-HISTORY]
        a = np.array([s[0] for s in self.shown])
        b = np.array([s[1] for s in self.shown])
        measured = measures.measure_dyad(a, b, self.learned, templates=self.templates)
        for episode in measured.episodes:
            if episode.pattern not in self.found:
                self.found.append(episode.pattern)
        if measured.shifts:
            leader = measured.shifts[-1].leader
            self.last_leader = {"a": self.names[0], "b": self.names[1]}.get(leader, "")
        sync = measured.sync_error[-1]
        meter = 0.0 if not math.isfinite(sync) else float(np.clip(1 - sync / METER_SCALE, 0, 1))
        coherent = bool(measured.coherent[-1])
        return {
            "type": "game_step",
            "step": int(record.step),
            "time_s": round(elapsed, 1),
            "synchrony": round(meter, 3),
            "coherent": coherent,
            "pattern": str(measured.class_a[-1]) if coherent else "",
            "found": list(self.found),
            "learned": len(self.learned),
            "last_leader": self.last_leader,
            "names": list(self.names),
            "robot_initiative": bool(record.a.initiative),
            "a": _finite(record.shown_a),
            "b": _finite(record.shown_b),
        }


def _finite(values: np.ndarray) -> list[float | None]:
    return [round(float(v), 4) if math.isfinite(v) else None for v in values]
