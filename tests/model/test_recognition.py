"""Recognition with a confidence and the novelty detector (rnnpb.model.recognition)."""

from dataclasses import replace

import numpy as np
import pytest

from rnnpb.errors import ConfigError
from rnnpb.model import MirrorSystem, OnlineConfig
from rnnpb.model.recognition import (
    NOVELTY_STATES,
    RecognitionConfig,
    initial_recognition_state,
    recognise,
    recognition_timeline,
)
from rnnpb.model.reference import ReferenceMirrorSystem

from .synthetic import PERIOD, pattern_values

RECOGNISED_WITHIN = 12  # steps: one cycle of evidence


def _answers(mirror, sensory):
    mirror.reset()
    return [mirror.step(u) for u in sensory]


def _cycle(kind, steps, seed):
    rng = np.random.default_rng(seed)
    phase = 2 * np.pi * np.arange(steps) / PERIOD + rng.uniform(0, 2 * np.pi)
    u, _ = pattern_values(kind, phase)
    return u + 0.01 * rng.standard_normal(u.shape)


@pytest.fixture(scope="module")
def mirror(trained):
    return MirrorSystem(trained)


@pytest.mark.parametrize("kind", [0, 2])
def test_a_known_pattern_is_recognised_and_stays_recognised_through_a_pause(mirror, kind):
    u = _cycle(kind, 60, seed=40 + kind)
    paused = np.concatenate([u[:36], np.repeat(u[35:36], 5, axis=0), u[36:]])
    results = _answers(mirror, paused)
    names = [r.recognised for r in results]
    first = names.index(str(kind))
    assert first <= RECOGNISED_WITHIN, names
    # From then on: always this pattern, through the pause (marked still), never another.
    assert names[first:] == [str(kind)] * (len(names) - first), names
    assert "still" in [r.novelty for r in results[36:41]]
    assert all(r.novelty in ("familiar", "still") for r in results[first:])
    confident = [r.confidence for r in results[first:] if r.novelty == "familiar"]
    assert np.median(confident) >= 0.8
    shares = results[-1].pattern_confidence
    assert max(shares, key=shares.get) == str(kind) and sum(shares.values()) <= 1 + 1e-9


def test_a_novel_shape_is_called_novel_and_not_recognised(mirror):
    # Both hands circling half a cycle apart: none of the three learned patterns.
    rng = np.random.default_rng(7)
    phase = 2 * np.pi * np.arange(60) / PERIOD + 1.0
    c, s = np.cos(phase), np.sin(phase)
    u = np.stack([0.5 + 0.25 * c, 0.5 + 0.25 * s, 0.5 - 0.25 * c, 0.5 - 0.25 * s], axis=1)
    results = _answers(mirror, u + 0.01 * rng.standard_normal(u.shape))
    assert all(r.recognised is None for r in results)
    novelty = [r.novelty for r in results]
    assert novelty[30:] == ["novel"] * 30, novelty
    assert "novel" in novelty[: 3 * PERIOD]


def test_a_random_walk_is_never_called_novel(mirror):
    rng = np.random.default_rng(3)
    walk = np.clip(0.5 + np.cumsum(0.05 * rng.standard_normal((60, 4)), axis=0), 0.1, 0.9)
    novelty = [r.novelty for r in _answers(mirror, walk)]
    assert "novel" not in novelty and "familiar" not in novelty
    assert novelty[-20:] == ["unstructured"] * 20, novelty


def test_held_still_hands_are_still_without_a_flickering_label(mirror):
    rng = np.random.default_rng(4)
    still = 0.5 + 0.002 * rng.standard_normal((30, 4))
    results = _answers(mirror, still)
    assert [r.novelty for r in results[5:]] == ["still"] * 25
    assert {r.recognised for r in results} == {None}


def test_bad_input_gives_an_empty_or_still_state_never_a_crash(mirror):
    u = _cycle(1, 30, seed=9)
    mirror.reset()
    for x in u[:20]:
        mirror.step(x)
    lost = mirror.step([np.nan] * 4)
    assert lost.novelty == "" and lost.recognised is None and lost.confidence == 0.0
    half = mirror.step([np.nan, np.nan, *u[21, 2:]])
    assert half.novelty in NOVELTY_STATES + ("",)
    outside = mirror.step([5.0, -3.0, 0.5, np.inf])
    assert outside.novelty in NOVELTY_STATES + ("",) and 0.0 <= outside.confidence <= 1.0
    mirror.reset()
    nothing = [mirror.step([np.nan] * 4) for _ in range(8)]
    assert {(r.recognised, r.novelty) for r in nothing} == {(None, "")}


def test_one_step_of_other_evidence_does_not_change_the_answer():
    config = RecognitionConfig()
    names = ("a", "b")
    learned = np.array([[0.2, 0.2], [0.8, 0.8]])
    rng = np.random.default_rng(0)
    state = initial_recognition_state(1, 2, config)
    said = []
    for t in range(60):
        u = np.array([0.5 + 0.3 * np.sin(2 * np.pi * t / 12)]) + 0.005 * rng.standard_normal(1)
        errors = np.array([1e-4, 0.01]) if t != 40 else np.array([0.01, 1e-4])
        pb = learned[0] if t != 40 else learned[1]
        state, answer = recognise(state, u, np.ones(1, bool), errors, pb, learned, names, config)
        said.append(answer.recognised)
    assert said[20:] == ["a"] * 40


def test_timeline_and_bad_settings():
    steps = [(None, ""), (None, ""), ("1", "familiar"), ("1", "familiar"), (None, "novel")]
    assert recognition_timeline(steps) == [
        {"first": 0, "last": 1, "recognised": None, "novelty": ""},
        {"first": 2, "last": 3, "recognised": "1", "novelty": "familiar"},
        {"first": 4, "last": 4, "recognised": None, "novelty": "novel"},
    ]
    with pytest.raises(ConfigError, match="lags"):
        RecognitionConfig(lags=(10, 5))
    with pytest.raises(ConfigError, match="confidence_level"):
        RecognitionConfig(confidence_level=0.0)
    assert RecognitionConfig.from_dict(RecognitionConfig().to_dict()) == RecognitionConfig()


def test_each_pattern_s_evidence_is_averaged_over_evidence_steps():
    config = RecognitionConfig(evidence_steps=4)
    names = ("a", "b")
    learned = np.array([[0.2, 0.2], [0.8, 0.8]])
    state = initial_recognition_state(1, 2, config)
    errors = [np.array([e, 0.01]) for e in (1e-4, 4e-4, 9e-4, 1.6e-3, 2.5e-3)]
    for t, e in enumerate(errors):
        u = np.array([0.5 + 0.3 * np.sin(2 * np.pi * t / 12)])
        state, answer = recognise(state, u, np.ones(1, bool), e, learned[0], learned, names, config)
    # The RMS of the last four steps' mean squared errors, not the last step's alone.
    assert answer.distances["a"] == pytest.approx(np.sqrt(np.mean([4e-4, 9e-4, 1.6e-3, 2.5e-3])))
    assert answer.distances["b"] == pytest.approx(0.1)
    with pytest.raises(ConfigError, match="evidence_steps"):
        RecognitionConfig(evidence_steps=0)


def test_the_settings_follow_the_model_s_learning(trained):
    # The tests' model is learned with the fast preset: its mirror system takes the fast
    # preset's recognition settings unless given others.
    assert OnlineConfig.for_model(trained).recognition == RecognitionConfig.fast()
    assert MirrorSystem(trained).recognition == RecognitionConfig.fast()
    assert ReferenceMirrorSystem(trained).recognition == RecognitionConfig.fast()
    chosen = RecognitionConfig(switch_steps=2)
    assert MirrorSystem(trained, recognition=chosen).recognition == chosen
    paper = replace(trained, meta={"train_config": {"optimizer": "momentum"}})
    assert OnlineConfig.for_model(paper).recognition == RecognitionConfig()
    assert RecognitionConfig.fast() != RecognitionConfig()
