"""Each measure on constructed signals whose answer is known."""

import numpy as np
import pytest

from rnnpb.analysis import metrics

LIMITS = np.array([[-1.0, 1.0]] * 8)


def _cycle(n, period=12.0, shift=0.0, dims=8):
    t = np.arange(n)[:, None]
    k = np.arange(dims)[None, :]
    return 0.3 * np.sin(2 * np.pi * (t - shift) / period + k)


def test_pure_phase_shift_is_measured():
    target = _cycle(120)
    assert metrics.phase_lag(_cycle(120, shift=2), target) == pytest.approx(2.0, abs=0.05)
    assert metrics.phase_lag(_cycle(120, shift=-1), target) == pytest.approx(-1.0, abs=0.05)
    # Sub-step shifts are interpolated.
    assert metrics.phase_lag(_cycle(120, shift=0.5), target) == pytest.approx(0.5, abs=0.15)
    assert metrics.phase_lag(target, target) == pytest.approx(0.0, abs=1e-9)


def test_known_lock_time():
    errors = np.r_[np.full(7, 0.3), np.full(30, 0.01)]
    assert metrics.steps_to_lock(errors) == 7
    # A single good step inside the bad part is not a lock: it must hold 6 steps.
    errors[3] = 0.0
    assert metrics.steps_to_lock(errors) == 7
    # Sensory errors count too; NaN (nothing seen) does not count against.
    sensory = np.r_[np.full(12, 0.2), np.full(25, 0.001)]
    sensory[20] = np.nan
    assert metrics.steps_to_lock(errors, sensory) == 12
    assert metrics.steps_to_lock(np.full(20, 0.3)) is None


def test_known_switch_time():
    motor = np.zeros((100, 8))
    truth = np.zeros((100, 8))
    truth[50:] = 0.5  # the user switches at 50 ...
    motor[50:59] = 0.0  # ... the robot keeps the old pattern for 9 steps, then follows
    motor[59:] = 0.5
    errors = metrics.motor_error(motor, truth, LIMITS)
    assert errors[55] == pytest.approx(0.25)
    assert metrics.steps_to_lock(errors, start=50) == 9


def test_periodic_versus_chaotic():
    periodic = _cycle(400, period=12)
    found = metrics.periodicity(periodic)
    assert found.period == 12 and found.return_error < 1e-9
    x = np.empty(400)
    x[0] = 0.3
    for t in range(399):  # the logistic map at r = 3.9 is chaotic
        x[t + 1] = 3.9 * x[t] * (1 - x[t])
    assert metrics.periodicity(x).period is None


def test_cycle_distance_and_response_cases():
    a = _cycle(12, period=12)
    assert metrics.cycle_distance(a, np.roll(a, 5, axis=0)) == pytest.approx(0.0, abs=1e-9)
    other = 0.3 * np.cos(2 * np.pi * np.arange(12)[:, None] / 12 * 2 + np.arange(8))
    assert metrics.cycle_distance(a, other) > 0.1
    learned = {"a": a, "b": other}
    like_a = metrics.classify_response(_cycle(300, period=12, shift=3), learned)
    assert (like_a.case, like_a.nearest_pattern, like_a.period) == (1, "a", 12)
    new = metrics.classify_response(1.5 * _cycle(300, period=12), learned)
    assert new.case == 2
    rng = np.random.default_rng(0)
    unsteady = metrics.classify_response(rng.uniform(0, 1, (300, 8)), learned)
    assert unsteady.case == 3


def test_attractor_distance_compares_runs_as_point_sets():
    """A quasi-periodic run against itself stopped later: one period's windows differ, the
    runs as point sets hardly; an offset run is as far as its offset; bad shapes are refused."""
    t = np.arange(600)[:, None]
    k = np.arange(8)[None, :]
    torus = 0.3 * np.sin(2 * np.pi * t / 12 + k) + 0.1 * np.sin(2 * np.pi * t / (12 * 5.37) + k)
    early, late = torus[200:400], torus[220:420]
    assert metrics.attractor_distance(early, early) == 0.0
    window = metrics.cycle_distance(metrics.last_cycle(early, 12), metrics.last_cycle(late, 12))
    assert metrics.attractor_distance(early, late) < 0.5 * window
    assert metrics.attractor_distance(early, early + 0.05) == pytest.approx(0.05, rel=0.05)
    with pytest.raises(ValueError, match="two runs"):
        metrics.attractor_distance(early, early[:, :4])


def test_pb_settling():
    pbs = np.r_[np.linspace(0, 1, 10)[:, None].repeat(4, 1), np.ones((20, 4))]
    assert metrics.pb_settle_step(pbs) == 10
    assert metrics.pb_settle_step(np.cumsum(np.full((30, 4), 0.05), axis=0)) is None


def test_sensory_error_ignores_unseen_values():
    predicted = np.full((3, 4), 0.5)
    observed = np.array([[0.5, 0.5, 0.5, 0.6], [np.nan] * 4, [np.nan, np.nan, 0.5, 0.5]])
    errors = metrics.sensory_error(predicted, observed)
    assert errors[0] == pytest.approx(0.05)
    assert np.isnan(errors[1])
    assert errors[2] == 0.0


def test_the_targets_are_the_papers():
    assert metrics.TRAIN_ERROR_TARGET == 3e-4
    assert (metrics.LOCK_LIMIT, metrics.SETTLE_LIMIT) == (10, 20)
    # 9 of 10 seeds; with fewer runs, the same share rounded up.
    assert metrics.larger_set_share_met(9, 10) and not metrics.larger_set_share_met(8, 10)
    assert metrics.larger_set_share_met(3, 3) and not metrics.larger_set_share_met(2, 3)


def test_a_cycle_of_eleven_and_a_half_steps_is_periodic():
    # Read at whole periods only, this cycle returns every 23 steps, beyond the 20 allowed.
    x = _cycle(400, period=11.5)
    found = metrics.periodicity(x, max_period=20)
    assert found.period is not None and abs(found.period - 11.5) < 0.05
    assert found.return_error < 0.01
    assert metrics.return_error(x, 11) > 0.1 and metrics.return_error(x, 12) > 0.1


def test_a_fractional_cycle_is_classified_like_the_learned_one():
    learned = {"a": metrics.last_cycle(_cycle(200, period=11.5), 11.5)}
    response = metrics.classify_response(_cycle(400, period=11.5, shift=4), learned)
    assert response.case == 1 and abs(response.period - 11.5) < 0.05
    assert response.distance < 0.01
