"""Interaction scenarios with ground truth, and the scenario user source."""

import numpy as np
import pytest

from rnnpb.demonstrator import (
    PAUSE,
    ScenarioSource,
    held_scenario,
    make_scenario,
    novel_scenario,
    pause_scenario,
    scenario_arrays,
    switch_scenario,
)
from rnnpb.errors import ConfigError
from rnnpb.robot import JOINT_LIMITS
from rnnpb.sources import Observation, UserSource


def test_switch_scenario_truth_and_motion():
    sc = switch_scenario(("1", "2", "3"), steps_each=50, seed=2)
    assert sc.n_steps == 150 and sc.switch_steps == (50, 100)
    assert sc.labels[49] == "1" and sc.labels[50] == "2" and sc.labels[100] == "3"
    assert sc.sensory.shape == (150, 4) and sc.hands.shape == (150, 2, 3)
    assert sc.motor.shape == (150, 8)
    assert np.all(sc.motor >= JOINT_LIMITS[:, 0]) and np.all(sc.motor <= JOINT_LIMITS[:, 1])
    # Pattern 1 moves the hands sideways, pattern 2 up and down.
    first, second = sc.sensory[5:50], sc.sensory[55:100]
    assert np.ptp(first[:, 0]) > 3 * np.ptp(first[:, 1])
    assert np.ptp(second[:, 1]) > 3 * np.ptp(second[:, 0])
    # The hands blend into the new pattern rather than jump.
    jumps = np.linalg.norm(np.diff(sc.hands, axis=0), axis=-1).max()
    assert jumps < 0.12


def test_pause_scenario_freezes_the_hands():
    sc = pause_scenario("2", before=40, pause=5, after=20, seed=1)
    assert sc.labels[40:45] == (PAUSE,) * 5 and sc.switch_steps == (40, 45)
    still = np.linalg.norm(np.diff(sc.hands[40:45], axis=0), axis=-1).max()
    moving = np.linalg.norm(np.diff(sc.hands[30:40], axis=0), axis=-1).mean()
    assert still < 0.01 and moving > 0.03  # only the slow drift moves them in the pause
    assert sc.truth(42)["pause"] and not sc.truth(39)["pause"]


def test_novel_and_held_scenarios():
    sc = novel_scenario("1", n_steps=30)
    assert set(sc.labels) == {"4"} and sc.novel == ("4",) and sc.truth(0)["novel"]
    held = held_scenario("rotation-opposite", n_steps=30, seed=4)
    assert set(held.labels) == {"3"} and held.switch_steps == () and not held.truth(3)["novel"]
    again = held_scenario("3", n_steps=30, seed=4)
    np.testing.assert_array_equal(held.sensory, again.sensory)


def test_scenario_arrays_and_source_agree():
    sc = make_scenario([("1", 10), (PAUSE, 3), ("4", 10)], seed=5)
    sensory, truth = scenario_arrays(sc)
    source = ScenarioSource(sc)
    assert isinstance(source, UserSource)
    seen = []
    with source:
        while (obs := source.read()) is not None:
            assert isinstance(obs, Observation)
            seen.append(obs)
    assert len(seen) == sc.n_steps == len(truth)
    np.testing.assert_array_equal(np.array([o.sensory for o in seen]), sensory)
    assert [o.truth["pattern"] for o in seen] == [t["pattern"] for t in truth]
    assert seen[10].truth["switch"] and seen[10].truth["pause"]
    np.testing.assert_array_equal(seen[3].truth["motor"], sc.motor[3])


def test_looping_source_and_errors():
    sc = held_scenario("1", n_steps=4)
    with ScenarioSource(sc, loop=True) as source:
        steps = [source.read().truth["step"] for _ in range(6)]
    assert steps == [0, 1, 2, 3, 0, 1]
    with pytest.raises(ConfigError, match="connect"):
        ScenarioSource(sc).read()
    with pytest.raises(ConfigError, match="unknown movement pattern"):
        make_scenario([("9", 5)])
