"""Runs stepped together: the demo's runs in one batched call are what each is alone, and the
measures come back by draw in the order asked."""

import numpy as np

from rnnpb.experiments import paper
from rnnpb.model import OnlineConfig
from rnnpb.robot import JOINT_LIMITS

# A short regression keeps the compiled step and the runs cheap.
SHORT = OnlineConfig(window=8, iterations=5)


def test_runs_stepped_together_are_the_runs_alone(set1_model, monkeypatch):
    limits = JOINT_LIMITS
    scenarios = [
        paper._pause_scenario("1", seed=100),
        paper._switch_scenario(("2", "3"), seed=200),
        paper._pause_scenario("3", seed=200),
    ]
    monkeypatch.setattr(paper, "BATCHED_STEPS", 0)
    together = paper.run_scenarios(set1_model, scenarios, SHORT, limits)
    for scenario, run in zip(scenarios, together, strict=True):
        alone = paper.run_scenario(set1_model, scenario, SHORT, limits)
        assert (run.name, run.labels, run.switch_steps) == (
            alone.name,
            alone.labels,
            alone.switch_steps,
        )
        np.testing.assert_array_equal(run.observed, alone.observed)
        np.testing.assert_allclose(run.predicted, alone.predicted, atol=1e-4)
        np.testing.assert_allclose(run.pb, alone.pb, atol=1e-4)
        np.testing.assert_allclose(run.motor, alone.motor, atol=1e-3)
        np.testing.assert_allclose(run.motor_error, alone.motor_error, atol=1e-4)
        assert run.recognised == alone.recognised


def test_draws_come_back_by_draw_with_every_pattern_and_pair(set1_model):
    # Few steps: the runs go one by one (the pooled runs are the test above's), in the order
    # draws() hands them back.
    by_seed = paper.draws(set1_model, SHORT, JOINT_LIMITS, (100, 200))
    assert list(by_seed) == [100, 200]
    for draw in by_seed.values():
        assert [s.pattern for s in draw.synchronization] == list(set1_model.patterns)
        assert set(draw.switching.pairs) == {"1->2", "1->3", "2->1", "2->3", "3->1", "3->2"}
    alone = paper.synchronization(set1_model, "2", SHORT, JOINT_LIMITS, seed=200)
    together = by_seed[200].synchronization[1]
    assert together.pause_start == alone.pause_start
    np.testing.assert_array_equal(together.run.pb, alone.run.pb)
    switched = paper.switching(set1_model, SHORT, JOINT_LIMITS, seed=100)
    assert by_seed[100].switching == switched


def test_the_novelty_studys_streams_run_together_as_each_alone(set1_model, monkeypatch):
    from rnnpb.demonstrator import PAUSE
    from rnnpb.experiments.scenarios import novelty
    from rnnpb.model import OnlineConfig as Online

    recognition = Online.for_model(set1_model).recognition
    cases = [
        ("learned", "1", 1000, 0, [("1", 30)], 1.0),
        ("novel-slow", "figure-eight", 1000, 10, [("2", 10), ("figure-eight", 25)], 0.5),
        ("still", PAUSE, 1001, 0, [(PAUSE, 20)], 1.0),
    ]
    alone = novelty.run_streams_of(set1_model, SHORT, recognition, "set1", cases)
    monkeypatch.setattr(paper, "BATCHED_STEPS", 0)
    together = novelty.run_streams_of(set1_model, SHORT, recognition, "set1", cases)
    for a, t in zip(alone, together, strict=True):
        assert (t.kind, t.movement, t.seed, t.start, t.speed) == (
            a.kind,
            a.movement,
            a.seed,
            a.start,
            a.speed,
        )
        assert t.novelty == a.novelty and t.recognised == a.recognised
        np.testing.assert_array_equal(t.sensory, a.sensory)
        np.testing.assert_allclose(t.pb, a.pb, atol=1e-4)
