"""Many sessions in one call: BatchedMirror gives what separate mirror systems give."""

import numpy as np
import pytest

from rnnpb.errors import ConfigError
from rnnpb.model import BatchedMirror, MirrorSystem, OnlineConfig, run_streams
from rnnpb.model.batched import pool_size

from .synthetic import LIMITS, make_sequences

SPAN = LIMITS[:, 1] - LIMITS[:, 0]
# A short regression with the default's restarts and phase restarts, so the test runs fast.
SHORT = OnlineConfig(window=8, iterations=5)


def _sessions(steps: int) -> np.ndarray:
    """Three users, (steps, 3, 4): patterns 2, 0 and 1, another phase each; the third loses
    its left hand for two steps inside the window, the first switches pattern."""
    first, second, third, switched = make_sequences(
        n_samples=1, n_steps=steps, seed=7, kinds=(2, 0, 1, 0)
    )
    hands = np.stack([first.sensory, second.sensory, third.sensory], axis=1).copy()
    hands[steps // 2 :, 0] = switched.sensory[: steps - steps // 2]
    hands[5:7, 2, :2] = np.nan
    return hands


def _assert_same(result, expected, context: str) -> None:
    # One compiled call for all sessions is a different program from one session's: the
    # products may round differently, within the compiled step's tolerance to its reference.
    for name in ("pb", "predicted_hands", "context", "pattern_errors"):
        np.testing.assert_allclose(
            getattr(result, name), getattr(expected, name), atol=2e-5, err_msg=f"{name} {context}"
        )
    np.testing.assert_allclose(result.motor / SPAN, expected.motor / SPAN, atol=2e-5)
    np.testing.assert_allclose(result.window_error, expected.window_error, atol=1e-6)
    np.testing.assert_allclose(result.prediction_error, expected.prediction_error, atol=1e-6)
    np.testing.assert_array_equal(result.seen, expected.seen)
    assert result.held == expected.held
    assert (result.recognised, result.novelty) == (expected.recognised, expected.novelty), context
    assert result.confidence == pytest.approx(expected.confidence, abs=1e-3), context


def test_sessions_step_as_separate_mirror_systems(trained):
    hands = _sessions(20)
    starts = np.array(list(trained.pattern_pb.values()))[[0, 2, 1]]
    starts[0] = 0.5  # one session starts at the centre of PB space, the others at a pattern
    batched = BatchedMirror(trained, sessions=3, config=SHORT, initial_pb=starts)
    separate = [MirrorSystem(trained, SHORT) for _ in range(3)]
    for mirror, pb in zip(separate, starts, strict=True):
        mirror.reset(initial_pb=pb)
    answers = set()
    for t in range(len(hands)):
        results = batched.step(hands[t])
        for b, mirror in enumerate(separate):
            expected = mirror.step(hands[t, b])
            _assert_same(results[b], expected, f"session {b}, step {t}")
            answers.add(expected.novelty)
    np.testing.assert_allclose(batched.pb, [m.pb for m in separate], atol=2e-5)
    assert batched.steps == 20
    assert "familiar" in answers  # the comparison covered recognition's answers, not only ""


def test_a_session_starts_afresh_while_the_others_go_on(trained):
    hands = _sessions(14)
    batched = BatchedMirror(trained, sessions=3, config=SHORT)
    separate = [MirrorSystem(trained, SHORT) for _ in range(3)]
    for t in range(8):
        batched.step(hands[t])
        for b, mirror in enumerate(separate):
            mirror.step(hands[t, b])
    batched.reset_session(1)
    separate[1] = MirrorSystem(trained, SHORT)
    for t in range(8, 14):
        results = batched.step(hands[t])
        for b, mirror in enumerate(separate):
            _assert_same(results[b], mirror.step(hands[t, b]), f"session {b}, step {t}")


def test_wrong_shapes_are_clear_errors(trained):
    with pytest.raises(ConfigError, match="sessions must be"):
        BatchedMirror(trained, sessions=0, config=SHORT)
    with pytest.raises(ConfigError, match="initial_pb must have shape"):
        BatchedMirror(trained, sessions=2, config=SHORT, initial_pb=np.full((3, 4), 0.5))
    batched = BatchedMirror(trained, sessions=2, config=SHORT)
    with pytest.raises(ConfigError, match="one row per session"):
        batched.step(np.full((3, 4), 0.5))
    with pytest.raises(ConfigError, match="4 values"):
        batched.step(np.full((2, 3), 0.5))
    with pytest.raises(ConfigError, match="does not exist"):
        batched.reset_session(2)


def test_streams_of_any_length_run_in_a_pool_as_each_would_alone(trained):
    """Five streams in two sessions: the longest start, and a session whose stream ends takes
    the next one afresh; each stream's results are its own mirror system's."""
    hands = _sessions(16)
    streams = [hands[:16, 0], hands[:6, 1], hands[:11, 2], hands[3:12, 0], hands[:0, 1]]
    pooled = run_streams(trained, streams, SHORT, sessions=2)
    assert [len(r) for r in pooled] == [16, 6, 11, 9, 0]
    for i, (stream, results) in enumerate(zip(streams, pooled, strict=True)):
        alone = MirrorSystem(trained, SHORT)
        for t, u in enumerate(stream):
            _assert_same(results[t], alone.step(u), f"stream {i}, step {t}")


def test_the_pool_is_as_narrow_as_its_rounds_allow():
    assert [pool_size(n) for n in (1, 9, 16, 17, 27, 33)] == [1, 9, 16, 9, 14, 11]


def test_a_stream_of_the_wrong_shape_is_a_clear_error(trained):
    with pytest.raises(ConfigError, match="stream 1 must be"):
        run_streams(trained, [np.full((3, 4), 0.5), np.full((3, 3), 0.5)], SHORT)
