"""The mirror game (``/game``): a person finds the robot's movements, or two robots play.

The person moves two points with the mouse or the fingers (the hands, as the robot's camera
would see them); the robot (:class:`rnnpb.interaction.dyad.RobotAgent`) follows what it
recognises and takes the initiative on its own — another of its patterns after a stable while
(its persistence), or when it is left alone. In ``robots`` mode two robots with the same model
play with each other. Each step publishes the synchrony meter, the patterns found so far, who
led the last switch, a hint and the time (docs/dashboard.md, "The mirror game").

A pointer has no body: where on the page a person plays, and how large, is theirs to choose.
The robot sees the person's movement in the person's own frame (:class:`PlayerFrame`): its
centre placed where the robot's camera saw its teachers' hands and its size scaled to theirs,
so that a small movement off to one side is seen as the movement it is and answered with the
robot's pattern, not with a damped copy. The measures judge that same movement; the meter is
the agreement of the two movements' velocities (:func:`velocity_agreement`), which neither
size nor place changes.
"""

from __future__ import annotations

import contextlib
import csv
import json
import logging
import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb.analysis import dyad as measures
from rnnpb.demonstrator import PatternConfig
from rnnpb.interaction.dyad import AgentConfig, AgentStep, Dyad, RobotAgent, robot_pair
from rnnpb.model.io import TrainedModel
from rnnpb.robot.camera import RobotCamera
from rnnpb.structure import repeating_stretches

log = logging.getLogger("rnnpb.web")

GAME_MODES = ("person", "robots")
HISTORY = 240  # steps of both agents kept for the measures (96 s at 0.4 s)
PERSISTENCE = 60  # stable steps (24 s at 0.4 s) after which the robot tries another pattern
FRAME_STEPS = 24  # steps (two cycles) over which the person's frame is measured
FRAME_FLOOR = 0.02  # view units: a movement smaller than this is not enlarged (still hands)
MAX_GAIN = 4.0  # a movement is enlarged at most this much (0.25 of the taught size)
AGREEMENT_WINDOW = 12  # steps (one cycle) of velocities the meter compares
AGREEMENT_LAG = 2  # steps of lag the meter tolerates either way (each sees the other late)
TEMPOS = (8, 10, 12, 14, 17)  # cycle lengths (steps) a movement is recognised at
SMALL = 0.35  # below this share of the taught size the game says "bigger"
TEMPO_SLACK = 1.3  # a cycle this much shorter (longer) than the robot's: "slower" ("faster")
IN_STEP = 0.6  # meter from which the two move in step: no hint, only time is needed
PERIOD_LAGS = (5, 24)  # shortest and longest cycle (steps) the tempo hints look for
PERIOD_STEPS = 48  # steps a cycle is looked for in: two cycles of the longest tempo and more


def taught_frame(
    config: PatternConfig | None = None, camera: RobotCamera | None = None
) -> tuple[np.ndarray, float]:
    """Where the robot saw its teachers' hands, (4,), and how large their movements were: the
    RMS about that centre over the four coordinates and a cycle, averaged over the patterns."""
    config = config or PatternConfig()
    camera = camera or RobotCamera()
    centre = camera.sensory_from_hands(config.body.hand_centres)
    sizes = [float(np.sqrt(np.mean(t**2))) for t in measures.movement_templates().values()]
    return np.asarray(centre, dtype=np.float64), float(np.mean(sizes))


class PlayerFrame:
    """The person's own frame: the centre and size of their last ``FRAME_STEPS`` steps (the
    mean of each coordinate, and the RMS distance from it over the four coordinates).

    ``seen(view)`` places a view of the person's hands (4,) in the taught frame: its offset
    from the person's centre, scaled by the taught size over the person's (at most
    ``MAX_GAIN``; a movement under ``FRAME_FLOOR`` is not enlarged), from the taught centre.
    ``back(view)`` is the inverse (the robot drawn where the person plays). The frame moves
    only when ``push`` adds a step; NaN views pass as NaN and are not pushed."""

    def __init__(self, centre: np.ndarray, size: float, steps: int = FRAME_STEPS) -> None:
        self.taught_centre = np.asarray(centre, dtype=np.float64)
        self.taught_size = float(size)
        self.steps = steps
        self._recent: list[np.ndarray] = []
        self.centre = self.taught_centre.copy()
        self.size = self.taught_size

    @property
    def gain(self) -> float:
        return min(self.taught_size / max(self.size, FRAME_FLOOR), MAX_GAIN)

    def push(self, view: np.ndarray) -> None:
        view = np.asarray(view, dtype=np.float64)
        if not np.isfinite(view).all():
            return
        self._recent.append(view)
        del self._recent[: -self.steps]
        recent = np.asarray(self._recent)
        self.centre = recent.mean(axis=0)
        self.size = float(np.sqrt(np.mean((recent - self.centre) ** 2)))

    def seen(self, view: np.ndarray) -> np.ndarray:
        view = np.asarray(view, dtype=np.float64)
        return np.clip(self.taught_centre + self.gain * (view - self.centre), 0.0, 1.0)

    def back(self, view: np.ndarray) -> np.ndarray:
        view = np.asarray(view, dtype=np.float64)
        return np.clip(self.centre + (view - self.taught_centre) / self.gain, 0.0, 1.0)


def velocity_agreement(
    a: np.ndarray, b: np.ndarray, window: int = AGREEMENT_WINDOW, max_lag: int = AGREEMENT_LAG
) -> float:
    """How well two movements' velocities agree over the last ``window`` steps, in [0, 1].

    The velocities (step differences of the four coordinates) of the two are compared as one
    vector each by their cosine, at the lag of at most ``max_lag`` steps either way where it
    is highest; negative agreement counts as 0. Adding a constant to either movement (moving
    it elsewhere) or scaling it (larger, smaller) changes nothing; a follower a step or two
    behind agrees fully. 0 where either is still or unknown over the window. (n, 4) each."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    need = window + max_lag + 1
    if len(a) < need or len(b) < need:
        return 0.0
    va, vb = np.diff(a[-need:], axis=0), np.diff(b[-need:], axis=0)
    if not (np.isfinite(va).all() and np.isfinite(vb).all()):
        return 0.0
    n = len(va)
    best = 0.0
    for lag in range(-max_lag, max_lag + 1):
        if lag >= 0:  # b ``lag`` steps behind a: a's past against b's present
            x, y = va[n - window - lag : n - lag], vb[n - window :]
        else:
            x, y = va[n - window :], vb[n - window + lag : n + lag]
        norm = float(np.sqrt(np.sum(x**2) * np.sum(y**2)))
        if norm > 1e-12:
            best = max(best, float(np.sum(x * y)) / norm)
    return min(best, 1.0)


class PersonAgent:
    """The person at the page: the hands the page last sent (NaN until placed), ``raw`` as the
    page has them and ``view`` in the taught frame (:class:`PlayerFrame`), as the robot sees
    them. The frame takes one step of the person's movement each step (``act``)."""

    name = "person"

    def __init__(self, frame: PlayerFrame | None = None) -> None:
        self._lock = threading.Lock()
        self._hands_view = np.full(4, np.nan)
        self.frame = frame or PlayerFrame(*taught_frame())

    def set_view(self, values: list[float]) -> None:
        with self._lock:
            self._hands_view = np.asarray(values, dtype=np.float64)

    @property
    def hands(self) -> np.ndarray:
        """No body: the robot sees the page's hands directly (``view``)."""
        return np.full((2, 3), np.nan)

    @property
    def raw(self) -> np.ndarray:
        with self._lock:
            return self._hands_view.copy()

    @property
    def view(self) -> np.ndarray:
        return self.frame.seen(self.raw)

    def act(self, view: np.ndarray) -> AgentStep:
        self.frame.push(self.raw)
        return AgentStep(hands=np.full((2, 3), np.nan), view=np.asarray(view, dtype=np.float64))


class _PersonDyad(Dyad):
    """A dyad whose second agent is seen directly as the page's view values."""

    def view(self, of: Any) -> np.ndarray:
        if isinstance(of, PersonAgent):
            return of.view
        return super().view(of)


class GameSession:
    """Runs the game in a thread, paced at ``dt``; publishes one JSON message per step."""

    def __init__(
        self, models: dict[str, Path], dt: float = 0.4, log_dir: str | Path | None = None
    ) -> None:
        self.models = dict(models)
        self.dt = dt
        self.log_dir = Path(log_dir) if log_dir is not None else None
        self.log: GameLog | None = None
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
            "log": self.log.json_path.name if self.log is not None else None,
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
                self.person = PersonAgent()
                dyad = _PersonDyad(RobotAgent(model, robot, name="robot"), self.person)
            person = self.person if mode == "person" else None
            tracker = _Tracker(
                model.patterns, mode, self.dt, person.frame if person is not None else None
            )
            if self.log_dir is not None:
                self.log = GameLog(self.log_dir, mode=mode, model=name, dt=self.dt)
            self.status = "running"
            self._publish(self.state())
            # The game's clock starts with its first step: the compilation before it (seconds,
            # a minute on a busy machine) is nobody's playing time.
            started: list[float] = []

            def on_step(record: Any) -> None:
                now = time.perf_counter()
                if not started:
                    started.append(now)
                raw = person.raw if person is not None else None
                message = tracker.update(record, now - started[0], raw)
                if self.log is not None:
                    self.log.add(record, message, raw, tracker.found, tracker.last_leader)
                self._publish(message)

            dyad.run(
                10**9,
                dt=self.dt,
                paced=True,
                should_stop=self._stop.is_set,
                between_steps=lambda wait: None if self._stop.wait(min(wait, 0.05)) else None,
                on_step=on_step,
            )
        except Exception as error:  # the page says what went wrong; the server stays up
            log.exception("the game stopped")
            self._publish({"type": "game_error", "message": str(error)[:300]})
        finally:
            if self.log is not None:
                self.log.close()
            self.status = "stopped"
            self._publish(self.state())


LOG_COLUMNS = (
    ["step", "time_s"]
    + [f"robot_{c}" for c in ("lhy", "lhz", "rhy", "rhz")]
    + [f"partner_{c}" for c in ("lhy", "lhz", "rhy", "rhz")]
    + [f"page_{c}" for c in ("lhy", "lhz", "rhy", "rhz")]
    + ["synchrony", "together", "pattern", "hint", "robot_initiative"]
)


class GameLog:
    """The record of one game in ``folder``: ``game-<time>.csv``, one row per step (the robot's
    hands and its partner's as the robot sees them, the page's hands as sent, the meter, the
    joint pattern, the hint) and ``game-<time>.json``: the model, the step time, and each
    movement found, when and who led it (rewritten as the game goes on)."""

    def __init__(self, folder: Path, *, mode: str, model: str, dt: float) -> None:
        folder.mkdir(parents=True, exist_ok=True)
        stamp = time.strftime("%Y%m%d-%H%M%S")
        base = folder / f"game-{stamp}"
        k = 1
        while base.with_suffix(".json").exists():
            k += 1
            base = folder / f"game-{stamp}-{k}"
        self.json_path = base.with_suffix(".json")
        self.csv_path = base.with_suffix(".csv")
        self.summary: dict[str, Any] = {
            "mode": mode,
            "model": model,
            "dt": dt,
            "started": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
            "steps": 0,
            "found": [],
            "last_leader": "",
            "csv": self.csv_path.name,
        }
        self._file = self.csv_path.open("w", newline="", encoding="utf-8")
        self._csv = csv.writer(self._file)
        self._csv.writerow(LOG_COLUMNS)
        self._found = 0
        self._write_summary()

    def add(
        self,
        record: Any,
        message: dict[str, Any],
        raw: np.ndarray | None,
        found: list[Found],
        last_leader: str,
    ) -> None:
        page = np.full(4, np.nan) if raw is None else raw
        self._csv.writerow(
            [message["step"], message["time_s"]]
            + [_cell(v) for v in record.shown_a]
            + [_cell(v) for v in record.shown_b]
            + [_cell(v) for v in page]
            + [
                message["synchrony"],
                int(message["coherent"]),
                message["pattern"],
                message["hint"],
                int(message["robot_initiative"]),
            ]
        )
        self.summary["steps"] = message["step"] + 1
        self.summary["last_leader"] = last_leader
        if len(found) != self._found:
            self._found = len(found)
            self.summary["found"] = [
                {
                    "pattern": f.pattern,
                    "step": f.step,
                    "time_s": f.time_s,
                    "game_time_s": round(f.step * self.summary["dt"], 1),
                    "episode_started": f.started,
                    "led_by": f.led_by,
                }
                for f in found
            ]
            self._file.flush()
            self._write_summary()

    def _write_summary(self) -> None:
        partial = self.json_path.with_suffix(".json.part")
        partial.write_text(json.dumps(self.summary, indent=1), encoding="utf-8")
        partial.replace(self.json_path)

    def close(self) -> None:
        if not self._file.closed:
            self._file.close()
            self._write_summary()


def _cell(value: float) -> str:
    return f"{float(value):.4f}" if math.isfinite(value) else ""


@dataclass(frozen=True)
class Found:
    """A learned movement found: at ``step`` (``time_s`` into the game), its first joint
    episode having started at ``started``; ``led_by`` names who moved it first, ``""`` if
    both at once."""

    pattern: str
    step: int
    time_s: float
    started: int
    led_by: str


def _period(views: np.ndarray) -> float:
    """A movement's cycle in steps, found as recognition and the learning phase find one
    (:func:`rnnpb.structure.repeating_stretches`: each cycle compared with the one before at
    every lag): the period of the repeating stretch that reaches the last step; NaN where the
    movement does not repeat there. (n, 4)"""
    views = np.asarray(views, dtype=np.float64)
    if not np.isfinite(views).all():
        return math.nan
    stretches = repeating_stretches(views, *PERIOD_LAGS)
    if not stretches or stretches[-1].stop != len(views):
        return math.nan
    return float(stretches[-1].period)


def _coupling(views: np.ndarray) -> tuple[int, int]:
    """How the right hand moves with the left, per axis (horizontal, vertical): +1 with it,
    -1 against it, 0 where one of them does not move. (n, 4)"""
    centred = views - views.mean(axis=0)
    spread = np.sqrt(np.mean(centred**2, axis=0))
    out = []
    for left, right in ((0, 2), (1, 3)):
        # An axis on which a hand hardly moves (beside the largest movement) says nothing.
        if min(spread[left], spread[right]) < 0.3 * max(spread.max(), FRAME_FLOOR):
            out.append(0)
        else:
            out.append(1 if float(np.sum(centred[:, left] * centred[:, right])) > 0 else -1)
    return out[0], out[1]


COUPLING_NAMES = {"mirror": "mirror", "parallel": "parallel", "opposite": "opposite phase"}


def coupling_name(signs: tuple[int, int]) -> str:
    """The page's name for a coupling of the two hands (:func:`_coupling`): the other hand
    ``mirror`` (left–right reflected), ``parallel`` or ``opposite`` (half a turn)."""
    horizontal, vertical = signs
    if vertical < 0:
        return "opposite"
    if horizontal < 0:
        return "mirror"
    return "parallel"


def hint(
    raw: np.ndarray,
    person: np.ndarray,
    robot: np.ndarray,
    frame: PlayerFrame,
    meter: float,
    found_already: str = "",
) -> str:
    """What the person might try, from their last ``FRAME_STEPS`` steps as the page has them
    (``raw``), as the robot sees them (``person``) and the robot's (``robot``), (n, 4) each,
    and the meter now; ``""`` when there is nothing to say (in step with the robot: the
    recognition needs a cycle or two). While the robot moves a movement found already
    (``found_already`` names it), nothing leads the person to it: they are sent on to
    another."""
    if len(raw) == 0 or not np.isfinite(raw[-1]).all():
        return "press on a blue hand and move it"
    recent = raw[-FRAME_STEPS:]
    if not np.isfinite(recent).all() or len(recent) < AGREEMENT_WINDOW:
        return ""
    spread = np.sqrt(np.mean((recent - recent.mean(axis=0)) ** 2, axis=0))
    if spread.max() < 0.5 * FRAME_FLOOR:
        return "move: swing or circle a hand"
    if frame.size < SMALL * frame.taught_size:
        return "bigger"
    if meter >= IN_STEP:
        return ""
    hands = np.array([np.hypot(spread[0], spread[1]), np.hypot(spread[2], spread[3])])
    if hands.min() < 0.25 * hands.max():
        return "the other hand too (choose how it follows: Other hand)"
    if found_already:
        return (
            f"another movement: movement {found_already}, which the robot moves now, is found"
            " — lead it somewhere new"
        )
    theirs = _coupling(robot[-AGREEMENT_WINDOW:])
    yours = _coupling(person[-AGREEMENT_WINDOW:])
    if (
        all(np.isfinite(robot[-AGREEMENT_WINDOW:]).ravel())
        and any(theirs)
        and coupling_name(theirs) != coupling_name(yours)
    ):
        return f"the other hand {COUPLING_NAMES[coupling_name(theirs)]}"
    yours_period, theirs_period = _period(person[-PERIOD_STEPS:]), _period(robot[-PERIOD_STEPS:])
    if math.isfinite(yours_period) and math.isfinite(theirs_period):
        if yours_period * TEMPO_SLACK < theirs_period:
            return "slower"
        if yours_period > TEMPO_SLACK * theirs_period:
            return "faster"
    return ""


def classify(views: np.ndarray, templates: dict[int, dict[str, np.ndarray]]) -> np.ndarray:
    """The movement class of each step (:func:`rnnpb.analysis.dyad.classify_movement`) against
    each pattern at every tempo of ``templates`` (cycle length -> templates), the best fit
    over tempi: a person and the robot following them move a pattern at the person's tempo;
    ``""`` where still or none fits. (n,) of str."""
    views = np.asarray(views, dtype=np.float64)
    best = np.full(len(views), np.inf)
    out = np.full(len(views), "", dtype=object)
    for bank in templates.values():
        found = measures.classify_movement(views, bank)
        better = (found.misfit < best) & (found.pattern != "")
        out[better] = found.pattern[better]
        best = np.minimum(best, found.misfit)
    return np.where(measures.moving(views), out, "").astype(object)


@dataclass(frozen=True)
class _Measured:
    class_a: np.ndarray
    class_b: np.ndarray
    coherent: np.ndarray
    episodes: list[measures.Episode]


def _measure(
    a: np.ndarray,
    b: np.ndarray,
    learned: tuple[str, ...],
    templates: dict[int, dict[str, np.ndarray]],
) -> _Measured:
    """The joint measures of :func:`rnnpb.analysis.dyad.measure_dyad` (classes, lock,
    coherence, episodes) with the classes judged at every tempo (:func:`classify`)."""
    ca, cb = classify(a, templates), classify(b, templates)
    lock = measures.phase_lock(a, b)
    coherent = measures.coherence(ca, cb, lock.locked, learned)
    found = measures.episodes(coherent, ca)
    return _Measured(ca, cb, coherent, found)


class _Tracker:
    """Keeps the recent steps of both agents and measures them for the page and the log."""

    def __init__(
        self, learned: tuple[str, ...], mode: str, dt: float, frame: PlayerFrame | None = None
    ) -> None:
        self.learned = learned
        self.mode = mode
        self.dt = dt
        self.frame = frame
        self.names = ("robot", "you") if mode == "person" else ("robot A", "robot B")
        self.templates = {k: measures.movement_templates(period=k) for k in TEMPOS}
        self.shown: list[tuple[np.ndarray, np.ndarray]] = []
        self.raw: list[np.ndarray] = []
        self.found: list[Found] = []
        self.last_leader = ""

    def update(self, record: Any, elapsed: float, raw: np.ndarray | None = None) -> dict[str, Any]:
        self.shown.append((record.shown_a, record.shown_b))
        del self.shown[:-HISTORY]
        if raw is not None:
            self.raw.append(np.asarray(raw, dtype=np.float64))
            del self.raw[:-FRAME_STEPS]
        a = np.array([s[0] for s in self.shown])
        b = np.array([s[1] for s in self.shown])
        measured = _measure(a, b, self.learned, self.templates)
        offset = int(record.step) - (len(a) - 1)  # the absolute step of row 0
        known = {f.pattern for f in self.found}
        previous_end = 0
        for episode in measured.episodes:
            # Who moved the joint movement first: the leader of the switch into it (into the
            # first one, from no joint movement at all).
            leader, _ = measures.shift_leader(
                measured.class_a, measured.class_b, episode.start, episode.pattern, previous_end
            )
            named = {"a": self.names[0], "b": self.names[1]}.get(leader, "")
            if episode.pattern not in known and episode.pattern in self.learned:
                self.found.append(
                    Found(
                        episode.pattern,
                        int(record.step),
                        round(elapsed, 1),
                        offset + episode.start,
                        named,
                    )
                )
                known.add(episode.pattern)
            self.last_leader = named
            previous_end = episode.end - 1
        meter = velocity_agreement(a, b)
        coherent = bool(measured.coherent[-1])
        advice = ""
        shown_b = record.shown_b
        if self.mode == "person" and self.frame is not None and raw is not None:
            robot_now = str(measured.class_a[-1])
            found_already = robot_now if robot_now in known else ""
            advice = (
                ""
                if coherent
                else hint(np.asarray(self.raw), b, a, self.frame, meter, found_already)
            )
        return {
            "type": "game_step",
            "step": int(record.step),
            "time_s": round(elapsed, 1),
            "synchrony": round(meter, 3),
            "coherent": coherent,
            "pattern": str(measured.class_a[-1]) if coherent else "",
            "found": [f.pattern for f in self.found],
            "found_at": [
                {"pattern": f.pattern, "time_s": f.time_s, "led_by": f.led_by} for f in self.found
            ],
            "learned": len(self.learned),
            "last_leader": self.last_leader,
            "hint": advice,
            "names": list(self.names),
            "robot_initiative": bool(record.a.initiative),
            # In a person's game the robot is drawn in the person's frame, over their hands.
            "a": _finite(
                self.frame.back(record.shown_a)
                if self.mode == "person" and self.frame is not None
                else record.shown_a
            ),
            "b": _finite(shown_b),
        }


def _finite(values: np.ndarray) -> list[float | None]:
    return [round(float(v), 4) if math.isfinite(v) else None for v in values]
