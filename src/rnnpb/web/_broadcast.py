"""What the session tells its pages: every message to every subscriber (a WebSocket
connection each), and the current run's recent steps for a tab that connects."""

from __future__ import annotations

import json
import logging
import threading
from collections import deque
from collections.abc import Callable
from typing import Any

log = logging.getLogger("rnnpb.web")

RECENT_STEPS = 120
"""Step messages kept for a tab that connects (the page plots this many steps)."""


class Broadcast:
    """Publishes JSON messages to its subscribers; numbers the runs (``run``) and keeps the
    last :data:`RECENT_STEPS` step messages of the current one."""

    def __init__(self) -> None:
        self._subscribers: list[Callable[[str], None]] = []
        self._lock = threading.Lock()
        self._recent: deque[str] = deque(maxlen=RECENT_STEPS)
        self.run = 0

    def subscribe(
        self,
        callback: Callable[[str], None],
        replay: Callable[[], tuple[dict[str, Any], str]] | None = None,
    ) -> Callable[[], None]:
        """``callback(json_text)`` for every message published; returns the unsubscribe.

        With ``replay`` (returning the state message and the run's name), ``callback`` first
        gets that state and a ``history`` message with the run's recent steps, so a new tab
        starts with full plots; no step is both replayed and published to it, nor missed, and
        no run begins in between.
        """
        with self._lock:
            if replay is not None:
                state, run = replay()
                callback(json.dumps(state, separators=(",", ":")))
                steps = ",".join(self._recent)
                callback(f'{{"type":"history","run":{json.dumps(run)},"steps":[{steps}]}}')
            self._subscribers.append(callback)

        def unsubscribe() -> None:
            with self._lock:
                if callback in self._subscribers:
                    self._subscribers.remove(callback)

        return unsubscribe

    @property
    def count(self) -> int:
        with self._lock:
            return len(self._subscribers)

    def new_run(self) -> int:
        """A new run: its number, and its recent steps start empty."""
        with self._lock:
            self._recent.clear()
            self.run += 1
            return self.run

    def publish(self, message: dict[str, Any]) -> None:
        text = json.dumps(message, separators=(",", ":"))
        with self._lock:
            if message["type"] == "step":
                self._recent.append(text)
            callbacks = list(self._subscribers)
        for callback in callbacks:
            try:
                callback(text)
            except Exception:  # a broken subscriber must not stop the robot
                log.exception("dashboard subscriber failed")
