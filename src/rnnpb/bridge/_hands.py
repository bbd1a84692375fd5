"""Hands from the bus: ``--source zenoh:KEY``, a camera node elsewhere publishing the person's
hands (:class:`~rnnpb.bridge._messages.HandsMessage`, ``lhy lhz rhy rhz`` in [0, 1]).

Each :meth:`ZenohHandsSource.read` returns the newest hands that arrived since the last read,
waiting up to one step for them; when none arrive in that time the hands are not seen this step
(NaN), so the loop runs on the network's own prediction, as it does when a camera loses a ball.
The stream does not end by itself (``--steps`` or Ctrl-C ends the run).
"""

from __future__ import annotations

import math
import threading
from typing import Any

import numpy as np

from rnnpb.bridge._bus import BusConfig
from rnnpb.bridge._messages import HandsMessage, MessageError, decode_hands
from rnnpb.sources import Observation, UserSource
from rnnpb.vectors import SENSORY_SIZE


class ZenohHandsSource(UserSource):
    """The person's hands from Zenoh key ``key``, one observation per step of ``dt``."""

    def __init__(self, key: str, dt: float = 0.4, bus: BusConfig | None = None) -> None:
        self.key = key
        self.dt = float(dt)
        self.bus = bus or BusConfig()
        self._session: Any = None
        self._subscriber: Any = None
        self._latest: HandsMessage | None = None
        self._read_seq: int | None = None
        self._arrived = threading.Condition()
        self.malformed = 0
        self.missed = 0
        """Steps on which no hands arrived."""

    def connect(self) -> None:
        self._session = self.bus.open()
        self._subscriber = self._session.declare_subscriber(self.key, self._on_hands)

    def _on_hands(self, sample: Any) -> None:
        try:
            hands = decode_hands(bytes(sample.payload.to_bytes()))
        except MessageError:
            self.malformed += 1
            return
        with self._arrived:
            self._latest = hands
            self._arrived.notify_all()

    def _fresh(self) -> bool:
        return self._latest is not None and self._latest.seq != self._read_seq

    def read(self) -> Observation | None:
        with self._arrived:
            self._arrived.wait_for(self._fresh, timeout=self.dt)
            if not self._fresh():
                self.missed += 1
                return Observation(np.full(SENSORY_SIZE, math.nan))
            assert self._latest is not None
            self._read_seq = self._latest.seq
            return Observation(self._latest.values.copy())

    def close(self) -> None:
        session, self._session = self._session, None
        if session is not None:
            session.close()
