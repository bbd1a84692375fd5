"""On-line regression under hostile sensory streams: never NaN, always within the joint limits,
and a non-finite value means "not seen" wherever it arrives."""

import math

import numpy as np
import pytest

from rnnpb.errors import ConfigError, DataFileError
from rnnpb.interaction import InteractionLoop, LoopConfig, SessionRecorder, read_session
from rnnpb.model import MirrorSystem
from rnnpb.model.native import native_regression
from rnnpb.model.online import OnlineState, network_arrays
from rnnpb.robot import JOINT_LIMITS, KinematicRobot
from rnnpb.sources import ArraySensorySource, CsvSensorySource


def _check(result):
    assert np.all(np.isfinite(result.motor)), result
    assert np.all(result.motor >= JOINT_LIMITS[:, 0]) and np.all(result.motor <= JOINT_LIMITS[:, 1])
    assert np.all(np.isfinite(result.pb)) and np.all((result.pb >= 0) & (result.pb <= 1))
    assert np.all(np.isfinite(result.predicted_hands))


def _swing(t):
    phase = 2 * np.pi * t / 12
    return np.array([0.5 + 0.3 * np.sin(phase), 0.5, 0.5 - 0.3 * np.sin(phase), 0.5])


@pytest.fixture(scope="module")
def mirror(model):
    return MirrorSystem(model)


HOSTILE = {
    "alternating extremes": lambda t: np.full(4, 1e30 if t % 2 else -1e30),
    "NaN bursts": lambda t: np.full(4, np.nan) if (t // 7) % 2 else _swing(t),
    "infinities": lambda t: np.array([np.inf, -np.inf, _swing(t)[2], np.nan]),
    "1e30": lambda t: np.full(4, 1e30),
    "subnormal and negative zero": lambda t: np.array([5e-324, -0.0, 1 - 1e-16, 2.0]),
    "one hand always lost": lambda t: np.concatenate([[np.nan, np.nan], _swing(t)[2:]]),
}


@pytest.mark.parametrize("name", list(HOSTILE))
def test_hostile_inputs_give_finite_commands_within_limits(mirror, name):
    mirror.reset()
    for t in range(60):
        _check(mirror.step(HOSTILE[name](t)))


def test_long_run_of_nan_then_recovery(mirror):
    """150 steps with nothing seen: the robot keeps generating; then it follows the user again."""
    mirror.reset()
    for t in range(30):
        mirror.step(_swing(t))
    motors = []
    for _ in range(150):
        result = mirror.step(np.full(4, np.nan))
        _check(result)
        assert math.isnan(result.prediction_error) and not result.seen.any()
        motors.append(result.motor)
    # Running on its own prediction, the network keeps moving rather than freezing.
    assert np.ptp(np.asarray(motors), axis=0).max() > 0.05
    errors = []
    for t in range(30):
        result = mirror.step(_swing(t))
        _check(result)
        errors.append(result.prediction_error)
    assert np.isfinite(errors[1:]).all()


def _saved(mirror: MirrorSystem) -> OnlineState:
    """A copy of the mirror system's state (the step changes it in place), to step from
    again."""
    return OnlineState(*(np.array(part) for part in mirror._state))


def test_infinity_is_treated_like_nan(mirror):
    mirror.reset()
    for t in range(10):
        mirror.step(_swing(t))
    state = _saved(mirror)
    with_nan = mirror.step([np.nan, 0.4, np.nan, 0.6])
    mirror._state = state
    mirror.steps -= 1
    with_inf = mirror.step([np.inf, 0.4, -np.inf, 0.6])
    np.testing.assert_array_equal(with_nan.seen, [False, True, False, True])
    np.testing.assert_array_equal(with_inf.seen, with_nan.seen)
    np.testing.assert_array_equal(with_inf.motor, with_nan.motor)
    np.testing.assert_array_equal(with_inf.pb, with_nan.pb)


def test_far_outside_values_are_clipped_to_the_view_plane(mirror):
    mirror.reset()
    state = _saved(mirror)
    far = mirror.step([1e30, -1e30, 7.0, -3.0])
    mirror._state = state
    edge = mirror.step([1.0, 0.0, 1.0, 0.0])
    np.testing.assert_array_equal(far.motor, edge.motor)
    assert far.held is False


def test_constant_input_for_thousands_of_steps(mirror):
    mirror.reset()
    held = 0
    for _ in range(1000):
        result = mirror.step([0.5, 0.5, 0.5, 0.5])
        _check(result)
        held += result.held
    assert held == 0


def _poisoned_steps(mirror, n_good, n_poisoned):
    mirror.reset()
    for t in range(n_good):
        good = mirror.step(_swing(t))
    # The weights poisoned where the step reads them: the compiled step's and the native loop's.
    healthy = mirror._net, mirror._native
    params = mirror.model.params
    poisoned = params._replace(w_out=np.asarray(params.w_out) * np.nan)
    net = mirror.model.network
    mirror._net = network_arrays(poisoned, net.sensory_size, net.motor_size, np.float32)
    mirror._native = native_regression(poisoned, net, mirror.config)
    try:
        results = [mirror.step(_swing(n_good + t)) for t in range(n_poisoned)]
    finally:
        mirror._net, mirror._native = healthy
    return good, results


def test_held_state_when_the_regression_fails(mirror):
    """Steps whose compiled regression yields NaN repeat the last good command; the first
    such step also reports the last good PB; the next good step carries on."""
    good, results = _poisoned_steps(mirror, 20, 5)
    for result in results:
        assert result.held is True
        np.testing.assert_allclose(result.motor, good.motor)
        _check(result)
    np.testing.assert_allclose(results[0].pb, good.pb, atol=1e-6)
    after = mirror.step(_swing(25))
    assert after.held is False
    _check(after)


def test_held_pb_stays_put_over_consecutive_failures(mirror):
    good, results = _poisoned_steps(mirror, 20, 3)
    for result in results:
        np.testing.assert_allclose(result.pb, good.pb, atol=1e-6)


@pytest.mark.parametrize("bad", [np.zeros(3), np.zeros(5), np.zeros((2, 4)), [], None])
def test_wrong_lengths_are_a_config_error(mirror, bad):
    with pytest.raises(ConfigError, match="observed hands must have 4 values"):
        mirror.step(bad)


def test_loop_with_a_hostile_stream_records_every_step(model, tmp_path):
    rng = np.random.default_rng(3)
    stream = rng.uniform(-0.5, 1.5, (80, 4))
    stream[10:30] = np.nan
    stream[40, 1] = np.inf
    stream[50:60:2] = 1e30
    path = tmp_path / "stream.csv"
    path.write_text(
        "step,lhy,lhz,rhy,rhz\n"
        + "".join(f"{t},{','.join(repr(float(v)) for v in row)}\n" for t, row in enumerate(stream))
    )
    source = CsvSensorySource(str(path))
    robot = KinematicRobot()
    with source, robot, SessionRecorder(tmp_path / "session.csv") as recorder:
        summary = InteractionLoop(MirrorSystem(model), source, robot, recorder, LoopConfig()).run()
    # The stream stopping ends the loop cleanly; every step is in the recording.
    assert summary.steps == 80 and summary.lost_steps == 21
    session = read_session(tmp_path / "session.csv")
    assert session["step"].tolist() == list(range(80))
    motor = np.column_stack(
        [session[n] for n in ("lshp", "lshr", "lshy", "lelp", "rshp", "rshr", "rshy", "relp")]
    )
    assert np.all(np.isfinite(motor))
    assert np.all(motor >= JOINT_LIMITS[:, 0] - 1e-6) and np.all(motor <= JOINT_LIMITS[:, 1] + 1e-6)
    assert session["lost_left"][40] == 1 and np.isnan(session["lhz"][40])


def test_stream_shapes_and_missing_columns(tmp_path):
    with pytest.raises(ConfigError, match="must have shape"):
        ArraySensorySource(np.zeros((5, 3)))
    path = tmp_path / "stream.csv"
    path.write_text("step,lhy,lhz,rhy\n0,1,1,1\n")
    with pytest.raises(DataFileError, match="missing column"):
        CsvSensorySource(str(path))
