"""Takes joined and resampled to the step: averaged over each step, sampled every dt, slowed
by the time scale; a movement too fast for the step is refused with what would work."""

from __future__ import annotations

import numpy as np
import pytest

from rnnpb.demonstrator import PatternConfig, pattern_offsets
from rnnpb.errors import ConfigError
from rnnpb.mocap import capture_stream, movement_period

from .bvh_files import demonstrator_hands, write_bvh

FPS = 30


def _take(tmp_path, name, pattern, period, seconds, **variant):
    times = np.arange(round(seconds * FPS) + 1) / FPS
    hands = demonstrator_hands(pattern, times, period)
    return str(write_bvh(tmp_path / name, hands, 1 / FPS, **variant))


def _averaged(pattern, times, period, width_frames):
    """The demonstrator's hands averaged over ``width_frames`` frames (odd) about ``times``."""
    config = PatternConfig()
    omega = 2 * np.pi / period
    h = 1 / FPS
    gain = np.sin(width_frames * omega * h / 2) / (width_frames * np.sin(omega * h / 2))
    return config.body.hand_centres + gain * pattern_offsets(pattern, omega * times, config)


def test_a_take_is_averaged_over_each_step_and_sampled_every_dt(tmp_path):
    path = _take(tmp_path, "a.bvh", "3", period=2.4, seconds=12)
    stream = capture_stream([path], dt=0.4)
    assert stream.hands.shape == (31, 2, 3)
    assert stream.period == pytest.approx(2.4, rel=0.25)
    inner = slice(1, -1)  # the ends are averaged with the held first and last frame
    expected = _averaged("3", np.arange(31) * 0.4, 2.4, width_frames=13)
    np.testing.assert_allclose(stream.hands[inner], expected[inner], atol=1e-4)
    # slowed twice: twice the steps, the same movement, each step the recording's 0.2 s
    slow = capture_stream([path], dt=0.4, time_scale=2.0)
    assert slow.hands.shape == (61, 2, 3)
    expected = _averaged("3", np.arange(61) * 0.2, 2.4, width_frames=7)
    np.testing.assert_allclose(slow.hands[inner], expected[inner], atol=1e-4)


def test_a_movement_too_fast_for_the_step_is_refused_with_what_would_work(tmp_path):
    path = _take(tmp_path, "fast.bvh", "2", period=1.0, seconds=8)
    with pytest.raises(ConfigError) as error:
        capture_stream([path], dt=0.4)
    message = str(error.value)
    assert "\n" not in message and message.startswith(f"{path}: the movement repeats every")
    assert "fewer than 4 (it would alias)" in message
    scale = float(message.split("--time-scale ")[2].split()[0])
    dt = float(message.split("--dt ")[1].split()[0])
    assert 1.6 <= scale <= 2.2 and 0.18 <= dt <= 0.25
    # what the message proposes works
    assert capture_stream([path], dt=0.4, time_scale=scale).period >= 4 * 0.4
    assert capture_stream([path], dt=dt).period >= 4 * dt


def test_the_period_of_a_movement(tmp_path):
    duration = 20.0
    times = np.arange(round(duration * FPS)) / FPS
    for period in (0.8, 2.0, 5.0):
        hands = demonstrator_hands("4", times, period)
        # on the safe side by at most one cycle per take: one frequency bin of its spectrum
        shortest = 1 / (1 / period + 1 / duration)
        assert shortest - 1e-9 <= movement_period(hands, 1 / FPS) <= 1.05 * period
    assert movement_period(np.zeros((50, 2, 3)), 1 / FPS) == np.inf


def test_takes_are_joined_in_order_with_a_short_cross_fade(tmp_path):
    first = _take(tmp_path, "one.bvh", "1", period=2.0, seconds=4)
    second = _take(tmp_path, "two.bvh", "2", period=2.0, seconds=4, naming="underscore")
    stream = capture_stream([first, second], dt=0.1, crossfade=0.5)
    assert len(stream.hands) == round((4 + 4 - 0.5) / 0.1) + 1
    assert [t.body.hands[0] for t in stream.takes] == ["LeftHand", "Hand_L"]
    # pattern 1 moves the hands sideways only, pattern 2 up and down only
    start, end = stream.hands[5:30], stream.hands[-30:-5]

    def spread(x):
        return np.ptp(x, axis=0).max()

    assert spread(start[..., 2]) < 1e-3 < spread(start[..., 1])
    assert spread(end[..., 1]) < 1e-3 < spread(end[..., 2])
    # no jump at the join: no step moves a hand further than the movement does within a take
    jumps = np.linalg.norm(np.diff(stream.hands, axis=0), axis=-1).max()
    within = np.linalg.norm(np.diff(start, axis=0), axis=-1).max()
    assert jumps < 1.5 * within
