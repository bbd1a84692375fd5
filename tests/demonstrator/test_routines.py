"""The demonstrator performs routines: patterns for some cycles each, with a person's timing;
`scenario:routine:…` names one wherever sources are parsed; `--cut whole` keeps it whole."""

from __future__ import annotations

import numpy as np
import pytest

from rnnpb.demonstrator import routine_scenario, routine_segments
from rnnpb.errors import ConfigError
from rnnpb.interaction import open_source
from rnnpb.interaction.sources import parse_scenario
from rnnpb.learning_phase import PhaseOptions, from_source, learning_phase

DANCE = [("1", 3), ("3", 2), ("2", 4)]


def test_a_routine_lasts_its_cycles_give_or_take_a_persons_timing():
    exact = routine_segments(DANCE, seed=0, timing_jitter=0.0)
    assert exact == [("1", 36), ("3", 24), ("2", 48)]
    drawn = [routine_segments(DANCE, seed=s) for s in range(20)]
    steps = np.array([[n for _, n in segments] for segments in drawn])
    assert np.all(np.abs(steps / [36, 24, 48] - 1) <= 0.4)
    assert steps.std(axis=0).min() > 0  # each draw its own timing
    scenario = routine_scenario(DANCE, seed=3, repeats=2)
    parts = [scenario.labels[0], *(scenario.labels[s] for s in scenario.switch_steps)]
    assert parts == ["1", "3", "2", "1", "3", "2"]


def test_the_source_spec_names_a_routine_and_bad_ones_are_one_line():
    scenario = parse_scenario("routine:1*3,3*2,2*4", seed=5)
    assert scenario.labels[0] == "1" and len(scenario.switch_steps) == 2
    for spec, message in [
        ("routine:1*x", "cycles must be an integer"),
        ("routine:1*0", "cycles must be >= 1"),
        ("routine:pause*2", "not pauses"),
        ("routine:9*2", "unknown movement"),
    ]:
        with pytest.raises(ConfigError, match=message):
            parse_scenario(spec)


def test_cut_whole_keeps_a_routine_as_one_sequence():
    with open_source("scenario:routine:1*2,2*2", seed=1) as source:
        performance = from_source(source)
    recording = learning_phase(performance, "dance", PhaseOptions(cut="whole"))
    assert len(recording.sequences) == 1 and recording.sequences[0].n_steps == recording.n_steps
