"""Recognition with a confidence and the novelty detector (rnnpb.model.recognition)."""

from dataclasses import replace

import numpy as np
import pytest

from rnnpb.errors import ConfigError
from rnnpb.model import MirrorSystem, OnlineConfig
from rnnpb.model.mirror import ReferenceMirrorSystem
from rnnpb.model.recognition import (
    NOVELTY_STATES,
    RecognitionConfig,
    initial_recognition_state,
    recognise,
    recognition_timeline,
    taught_distances,
    taught_stretches,
)

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


def test_a_pattern_with_rests_in_every_cycle_is_recognised(mirror):
    # A person's gesture (raise, hold, lower, rest): half a cycle of movement, then the hands
    # at rest for 4 steps, twice a cycle, so that no stretch of movement is as long as the
    # taught shapes' window. The rests are called still and left out of the shape: the
    # pattern is recognised within three cycles and held through every rest.
    u = _cycle(0, 96, seed=45)
    half, rest = PERIOD // 2, 4
    rows = []
    for start in range(0, 96, half):
        rows += list(u[start : start + half])
        rows += [u[start + half - 1]] * rest
    results = _answers(mirror, np.array(rows))
    names = [r.recognised for r in results]
    assert "0" in names and names.index("0") <= 3 * (PERIOD + 2 * rest), names
    first = names.index("0")
    assert names[first:] == ["0"] * (len(names) - first), names
    assert [r.novelty for r in results[first:]].count("still") >= 4


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
    # Undecided until every period up to the longest could be measured, then unstructured.
    rng = np.random.default_rng(3)
    walk = np.clip(0.5 + np.cumsum(0.05 * rng.standard_normal((110, 4)), axis=0), 0.1, 0.9)
    novelty = [r.novelty for r in _answers(mirror, walk)]
    assert "novel" not in novelty and "familiar" not in novelty
    assert novelty[-20:] == ["unstructured"] * 20, novelty


def _circles(period, steps, seed, hands=2):
    """Both hands circling half a cycle apart (none of the learned patterns), or (one hand)
    the left hand swinging up and down while the right one rests."""
    rng = np.random.default_rng(seed)
    phase = 2 * np.pi * np.arange(steps) / period + 1.0
    c, s = np.cos(phase), np.sin(phase)
    if hands == 2:
        u = np.stack([0.5 + 0.25 * c, 0.5 + 0.25 * s, 0.5 - 0.25 * c, 0.5 - 0.25 * s], axis=1)
    else:
        rest = np.full(steps, 0.5)
        u = np.stack([0.3 + 0.0 * s, 0.5 + 0.25 * s, rest + 0.2, rest], axis=1)
    return u + 0.005 * rng.standard_normal(u.shape)


@pytest.mark.parametrize("hands", [1, 2])
@pytest.mark.parametrize("speed", [0.5, 2.0])
def test_a_new_shape_is_novel_at_half_and_twice_the_speed(mirror, speed, hands):
    # The same shape at half speed (24-step cycles, slow turns of one hand at its turning
    # points) and at twice the speed (6-step cycles): called novel once two of its cycles
    # were seen, and on every step after.
    period = round(PERIOD / speed)
    steps = 2 * period + 40 + 48
    results = _answers(mirror, _circles(period, steps, seed=11, hands=hands))
    novelty = [r.novelty for r in results]
    assert all(r.recognised is None for r in results)
    assert novelty[-48:] == ["novel"] * 48, novelty
    assert "unstructured" not in novelty[2 * period + 12 :], novelty


def test_a_slow_and_a_fast_shape_repeat_and_random_movement_does_not():
    # The structure test alone, on the user's one- and two-handed new shapes at half and
    # twice the usual speed, and on unstructured movement and a smooth random scribble.
    from rnnpb.demonstrator import NEW_SHAPES, UNSTRUCTURED, PatternConfig, make_scenario
    from rnnpb.model.recognition import _structure

    config = RecognitionConfig.fast()
    size = config.history

    def least(sensory):
        values = [_structure(sensory[t - size : t], config) for t in range(size, len(sensory))]
        assert all(every for _, every, _ in values)
        return np.array([value for value, _, _ in values])

    for speed in (0.5, 2.0):
        shape_config = PatternConfig(period_steps=12 / speed)
        for shape in NEW_SHAPES:
            sensory = make_scenario([(shape, size + 30)], seed=3, config=shape_config).sensory
            assert least(sensory).max() < config.structure_level, (shape, speed)
    rng = np.random.default_rng(4)
    scribble = 0.5 + np.cumsum(rng.standard_normal((size + 40, 4)), axis=0) * 0.01
    smooth = np.apply_along_axis(lambda x: np.convolve(x, np.ones(5) / 5, "same"), 0, scribble)
    movements = [make_scenario([(m, size + 30)], seed=3).sensory for m in UNSTRUCTURED]
    for sensory in [*movements, smooth[5:-5]]:
        assert least(sensory).min() > config.structure_level


def test_after_a_stop_a_slow_shape_is_undecided_until_it_repeats_then_novel(mirror):
    # What came before the stop does not count: the slow shape is not called unstructured
    # while its own cycles are too few to tell.
    rng = np.random.default_rng(6)
    walk = np.clip(0.5 + np.cumsum(0.05 * rng.standard_normal((90, 4)), axis=0), 0.1, 0.9)
    held = walk[-1] + 0.002 * rng.standard_normal((15, 4))
    slow = _circles(2 * PERIOD, 100, seed=13)
    novelty = [r.novelty for r in _answers(mirror, np.concatenate([walk, held, slow]))]
    after = novelty[len(walk) + len(held) :]
    assert "unstructured" not in after and after[-40:] == ["novel"] * 40, after


@pytest.mark.parametrize("before", ["novel", "walk"])
def test_stillness_is_decided_within_a_few_steps_of_the_hands_stopping(mirror, before):
    rng = np.random.default_rng(5)
    if before == "novel":
        moving = _circles(PERIOD, 60, seed=12)
    else:
        moving = np.clip(0.5 + np.cumsum(0.05 * rng.standard_normal((90, 4)), axis=0), 0.1, 0.9)
    held = moving[-1] + 0.002 * rng.standard_normal((30, 4))
    novelty = [r.novelty for r in _answers(mirror, np.concatenate([moving, held]))]
    stopped = novelty[len(moving) :]
    assert stopped[5:] == ["still"] * 25, stopped


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


TWO_LEARNED = (("a", "b"), np.array([[0.2, 0.2], [0.8, 0.8]]))  # names, their PBs


def _recognise_a_swing(steps: int, evidence, seed: int):
    """Recognition over a 12-step swing of one value, each step's pattern errors and PB from
    ``evidence(t)``; the last state and every step's answer."""
    config = RecognitionConfig()
    names, learned = TWO_LEARNED
    rng = np.random.default_rng(seed)
    state = initial_recognition_state(1, 2, config)
    answers = []
    for t in range(steps):
        u = np.array([0.5 + 0.3 * np.sin(2 * np.pi * t / 12)]) + 0.005 * rng.standard_normal(1)
        errors, pb = evidence(t)
        state, answer = recognise(state, u, np.ones(1, bool), errors, pb, learned, names, config)
        answers.append(answer)
    return state, answers


def test_one_step_of_other_evidence_does_not_change_the_answer():
    _, learned = TWO_LEARNED

    def evidence(t):
        return (
            (np.array([0.01, 1e-4]), learned[1])
            if t == 40
            else (np.array([1e-4, 0.01]), learned[0])
        )

    _, answers = _recognise_a_swing(60, evidence, seed=0)
    assert [a.recognised for a in answers[20:]] == ["a"] * 40


def test_the_structure_test_runs_only_where_no_pattern_is_recognised():
    """While a learned pattern is recognised the structure test's answer is not used (it is not
    measured: NaN); once no pattern fits, a repeating movement is measured and called novel."""
    _, learned = TWO_LEARNED

    def evidence(t):
        return (
            (np.array([1e-4, 0.01]), learned[0])
            if t < 60
            else (np.full(2, 0.05), np.array([0.5, 0.1]))
        )

    state, answers = _recognise_a_swing(160, evidence, seed=1)
    familiar = [a for a in answers[30:60] if a.novelty == "familiar"]
    assert familiar and all(np.isnan(a.structure) for a in familiar)
    novel = [a for a in answers[100:] if a.novelty == "novel"]
    config = RecognitionConfig()
    assert len(novel) > 40 and all(a.structure < config.structure_level for a in novel)
    assert state.period in (11, 12, 13)
    # A novel call says how many of the latest steps it rests on: the last cycle and the one
    # before it; no other answer says any.
    span = state.period + max(state.period, config.structure_steps)
    assert novel[-1].repeating == span
    assert all(a.repeating == 0 for a in answers if a.novelty != "novel")


def test_timeline_and_bad_settings():
    steps = [(None, ""), (None, ""), ("1", "familiar"), ("1", "familiar"), (None, "novel")]
    assert recognition_timeline(steps) == [
        {"first": 0, "last": 1, "recognised": None, "novelty": ""},
        {"first": 2, "last": 3, "recognised": "1", "novelty": "familiar"},
        {"first": 4, "last": 4, "recognised": None, "novelty": "novel"},
    ]
    with pytest.raises(ConfigError, match="lags"):
        RecognitionConfig().with_tuning(lags=(10, 5))
    with pytest.raises(ConfigError, match="confidence_level"):
        RecognitionConfig().with_tuning(confidence_level=0.0)
    assert RecognitionConfig.from_dict(RecognitionConfig().to_dict()) == RecognitionConfig()


def test_each_pattern_s_evidence_is_averaged_over_evidence_steps():
    config = RecognitionConfig().with_tuning(evidence_steps=4)
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
        RecognitionConfig().with_tuning(evidence_steps=0)


def test_the_settings_follow_the_model_s_learning(trained):
    # The tests' model is learned with the fast preset: its mirror system takes the fast
    # preset's recognition settings unless given others.
    assert OnlineConfig.for_model(trained).recognition == RecognitionConfig.fast()
    assert MirrorSystem(trained).recognition == RecognitionConfig.fast()
    assert ReferenceMirrorSystem(trained).recognition == RecognitionConfig.fast()
    chosen = RecognitionConfig().with_tuning(switch_steps=2)
    assert MirrorSystem(trained, recognition=chosen).recognition == chosen
    paper = replace(trained, meta={"train_config": {"optimizer": "momentum"}})
    assert OnlineConfig.for_model(paper).recognition == RecognitionConfig()
    assert RecognitionConfig.fast() != RecognitionConfig()
    # A model that kept no taught hands (a file of format 1 or 2) gets the settings chosen for
    # the network's evidence alone.
    untaught = replace(trained, taught_sensory=None)
    assert MirrorSystem(untaught).recognition == RecognitionConfig.untaught(fast=True)
    untaught_paper = replace(paper, taught_sensory=None)
    assert OnlineConfig.for_model(untaught_paper).recognition == RecognitionConfig.untaught()
    assert RecognitionConfig.untaught() != RecognitionConfig()


def _taught(kinds=(0, 1), steps=50):
    """Two patterns' taught hands, as a model keeps them (one noisy sequence each)."""
    rng = np.random.default_rng(11)
    out = {}
    for kind in kinds:
        u, _ = pattern_values(kind, 2 * np.pi * np.arange(steps) / PERIOD)
        out[str(kind)] = [u + 0.01 * rng.standard_normal(u.shape)]
    return out


def test_the_hands_as_taught_tell_apart_patterns_the_network_confuses():
    # Both patterns' dynamics predict what is seen equally well and the PB lies between them:
    # the network's evidence cannot decide. The taught shapes can.
    config = RecognitionConfig()
    names = ("0", "1")
    learned = np.array([[0.4, 0.4], [0.6, 0.6]])
    taught = taught_stretches(_taught(), names, config)
    assert taught is not None
    for kind in (0, 1):
        for stretches in (taught, None):
            state = initial_recognition_state(4, 2, config)
            said = []
            for u in _cycle(kind, 48, seed=20 + kind):
                equal = np.array([1e-5, 1e-5])
                state, answer = recognise(
                    state, u, np.ones(4, bool), equal, [0.5, 0.5], learned, names, config, stretches
                )
                said.append((answer.recognised, answer.novelty))
            if stretches is None:
                assert all(name is None for name, _ in said[24:])  # an even split: not sure
            else:
                assert said[24:] == [(str(kind), "familiar")] * 24, said


def test_the_taught_shape_ignores_the_size_of_the_movement_but_not_a_missing_arm():
    config = RecognitionConfig()
    taught = taught_stretches(_taught(), ("0", "1"), config)
    assert taught is not None
    u, _ = pattern_values(1, 2 * np.pi * np.arange(12) / PERIOD + 0.3)
    smaller = 0.5 + 0.4 * (u - 0.5)  # the same movement at 40 % of the size
    assert taught_distances(smaller, taught)[1] < 0.12  # seen between two taught stretches
    assert taught_distances(smaller, taught)[0] > 0.95  # vertical is nothing like horizontal
    one_arm = u.copy()
    one_arm[:, 2:] = 0.5  # the right hand rests
    assert taught_distances(one_arm, taught)[1] > 0.6
    # Slower than taught: one of the template speeds fits it.
    slow, _ = pattern_values(1, 2 * np.pi * np.arange(12) / (1.2 * PERIOD))
    assert taught_distances(slow, taught)[1] < 0.1
    # A pattern with too few taught steps for a stretch: none to match against.
    assert taught_stretches({"0": [u[:5]], "1": [u]}, ("0", "1"), config) is None
    # Nor for a pattern taught without moving: it has no shape.
    assert taught_stretches({"0": [np.full((50, 4), 0.5)], "1": [u]}, ("0", "1"), config) is None
    with pytest.raises(ConfigError, match="template"):
        RecognitionConfig().with_tuning(template_speeds=())


def test_one_hand_swinging_while_the_other_rests_is_movement_not_stillness():
    # At the turning points of a one-arm swing, the four values together hardly move; the
    # swinging hand does.
    # The demonstrator's size (0.14 of the view) and sensor noise.
    config = RecognitionConfig()
    u = np.full((60, 4), 0.5)
    u[:, 1] += 0.14 * np.sin(2 * np.pi * np.arange(60) / PERIOD + np.pi / 12)
    u += 0.004 * np.random.default_rng(2).standard_normal(u.shape)
    state = initial_recognition_state(4, 2, config)
    novelty = []
    for x in u:
        state, answer = recognise(
            state,
            x,
            np.ones(4, bool),
            np.array([1e-5]),
            [0.5, 0.5],
            np.array([[0.5, 0.5]]),
            ("a",),
            config,
        )
        novelty.append(answer.novelty)
    assert "still" not in novelty, novelty
