"""Hands from the bus (``--source zenoh:KEY``): a camera node publishes, the loop reads."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from rnnpb.bridge import BusConfig, HandsMessage, ZenohHandsSource, encode_hands
from rnnpb.errors import ConfigError
from rnnpb.interaction import open_source

from ._robot_process import free_port, wait_until


def test_hands_published_on_the_bus_reach_the_loop_and_silence_is_a_lost_hand():
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    camera = BusConfig(listen=(endpoint,)).open()
    try:
        publisher = camera.declare_publisher("lab/hands")
        with open_source(f"zenoh:lab/hands@{endpoint}", dt=0.2) as source:
            assert isinstance(source, ZenohHandsSource)
            assert wait_until(lambda: bool(camera.info.peers_zid()))
            time.sleep(0.1)  # the subscription reaches the camera's peer
            sent = []
            for seq in range(1, 6):
                values = np.array([0.1 * seq, 0.5, math.nan if seq == 3 else 0.4, 0.6])
                publisher.put(encode_hands(HandsMessage(seq, time.time(), values)))
                sent.append(values)
                observation = source.read()
                assert observation is not None
                np.testing.assert_array_equal(observation.sensory, values)
            publisher.put(b"not hands")
            started = time.monotonic()
            silent = source.read()  # nothing new within a step: not seen
            assert silent is not None
            assert np.all(np.isnan(silent.sensory))
            assert 0.15 < time.monotonic() - started < 0.6
            assert source.malformed == 1 and source.missed == 1
    finally:
        camera.close()


def test_a_bus_source_needs_a_plain_key():
    with pytest.raises(ConfigError, match="not a plain Zenoh key"):
        open_source("zenoh:lab/*")
    with pytest.raises(ConfigError, match="an endpoint follows @"):
        open_source("zenoh:lab/hands@")
    with pytest.raises(ConfigError, match="name the key"):
        open_source("zenoh:@tcp/127.0.0.1:7447")
