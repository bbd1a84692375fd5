"""The on-line mirror system: recognition by PB regression, synchronous generation."""

import jax.numpy as jnp
import numpy as np
import pytest

from rnnpb.errors import ConfigError
from rnnpb.model import MIRROR_SYSTEMS, MirrorSystem, OnlineConfig, TrainedModel
from rnnpb.model.online import phase_candidates

from .synthetic import LIMITS, make_sequences

LOCK_STEPS = 10  # the motor command must be locked on within this many steps
SPAN = LIMITS[:, 1] - LIMITS[:, 0]
# A short regression, so that the NumPy twin runs a test in a second or two.
SHORT = OnlineConfig(window=8, iterations=5)


def _motor_error(result_motor, true_motor):
    return float(np.sqrt(np.mean(((result_motor - true_motor) / SPAN) ** 2)))


@pytest.mark.parametrize("pattern", [0, 1, 2])
def test_pb_converges_to_the_pattern_and_motor_locks_on(trained, pattern):
    # A new demonstration (other seed, other phase) of a learned pattern.
    demo = make_sequences(n_samples=1, n_steps=60, seed=11 + pattern, kinds=(pattern,))[0]
    mirror = MirrorSystem(trained)
    errors, pbs = [], []
    for t in range(demo.n_steps):
        result = mirror.step(demo.sensory[t])
        errors.append(_motor_error(result.motor, demo.motor[t]))
        pbs.append(result.pb)
        assert np.all(result.motor >= LIMITS[:, 0]) and np.all(result.motor <= LIMITS[:, 1])
    # Locked within LOCK_STEPS steps: normalized motor error below 0.05 from then on.
    assert max(errors[LOCK_STEPS:]) < 0.05, np.round(errors, 3)
    # The PB ends nearest to the pattern's learned PB.
    name, _ = trained.nearest_pattern(pbs[-1])
    assert name == str(pattern)


def test_lost_hands_are_filled_by_prediction(trained):
    demo = make_sequences(n_samples=1, n_steps=50, seed=21, kinds=(0,))[0]
    mirror = MirrorSystem(trained)
    for t in range(30):
        mirror.step(demo.sensory[t])
    for t in range(30, 36):  # both hands lost for 6 steps
        result = mirror.step([np.nan] * 4)
        assert not result.seen.any()
        assert np.all(np.isfinite(result.motor)) and np.all(np.isfinite(result.pb))
        # Still moving with the pattern: the prediction carries it.
        assert _motor_error(result.motor, demo.motor[t]) < 0.1
    for t in range(36, 50):
        result = mirror.step(demo.sensory[t])
    assert _motor_error(result.motor, demo.motor[49]) < 0.05


@pytest.mark.parametrize("twin", MIRROR_SYSTEMS)
def test_reset_repeats_exactly(trained, twin):
    demo = make_sequences(n_samples=1, n_steps=12, seed=5, kinds=(1,))[0]
    mirror = MIRROR_SYSTEMS[twin](trained, OnlineConfig() if twin == "compiled" else SHORT)
    first = [mirror.step(u).motor for u in demo.sensory]
    mirror.reset()
    assert mirror.steps == 0 and len(mirror.pb_profile) == 0
    second = [mirror.step(u).motor for u in demo.sensory]
    np.testing.assert_array_equal(np.array(first), np.array(second))


@pytest.mark.parametrize("twin", MIRROR_SYSTEMS)
def test_wrong_shape_is_a_clear_error(trained, twin):
    mirror = MIRROR_SYSTEMS[twin](trained, SHORT)
    with pytest.raises(ConfigError, match="4 values"):
        mirror.step([0.5, 0.5, 0.5])
    with pytest.raises(ConfigError, match="must be 4 numbers"):
        mirror.step(["a", "b", "c", "d"])


def test_numerical_failure_holds_the_last_good_state_in_both_twins(trained):
    broken = TrainedModel(
        network=trained.network,
        params=trained.params._replace(w_out=jnp.full_like(trained.params.w_out, jnp.nan)),
        lower=trained.lower,
        upper=trained.upper,
        sequence_pb=trained.sequence_pb,
        sequence_patterns=trained.sequence_patterns,
        initial_context=trained.initial_context,
    )
    twins = {name: system(broken, SHORT) for name, system in MIRROR_SYSTEMS.items()}
    for _ in range(3):
        results = {name: twin.step([0.5, 0.5, 0.5, 0.5]) for name, twin in twins.items()}
        for result in results.values():
            assert result.held and np.isnan(result.window_error)
            assert np.all(np.isfinite(result.motor)) and np.all(np.isfinite(result.pb))
        compiled, reference = results["compiled"], results["reference"]
        for name in ("motor", "predicted_hands", "pb", "context", "pattern_errors"):
            np.testing.assert_allclose(
                getattr(compiled, name), getattr(reference, name), atol=2e-4, err_msg=name
            )
        assert compiled.novelty == reference.novelty
        assert compiled.recognised == reference.recognised


@pytest.mark.parametrize(
    "motor_input, optimize_onset, restart_span, surprise_gate, phase",
    [
        ("closed_loop", True, 6, 0.0, 0),
        ("closed_loop", False, 0, 0.0, 0),
        ("recorded", True, 3, 0.0, 0),
        ("recorded", False, 6, 0.0, 0),
        ("closed_loop", True, 6, 0.05, 0),
        ("closed_loop", True, 6, 0.05, 3),
        ("recorded", True, 0, 0.0, 2),
    ],
)
def test_float32_step_matches_float64_reference(
    trained, motor_input, optimize_onset, restart_span, surprise_gate, phase
):
    config = OnlineConfig(window=8, iterations=5).with_tuning(
        motor_input=motor_input,
        optimize_onset=optimize_onset,
        restart_span=restart_span,
        surprise_gate=surprise_gate,
        phase_restarts=phase,
    )
    # Pattern 2, then pattern 0: the switch makes the phase restarts start the window over.
    first, second = make_sequences(n_samples=1, n_steps=10, seed=3, kinds=(2, 0))
    sensory = np.concatenate([first.sensory, second.sensory])
    sensory[5, :2] = np.nan  # a lost hand inside the window
    mirror = MIRROR_SYSTEMS["compiled"](trained, config)
    ref = MIRROR_SYSTEMS["reference"](trained, config)
    starts_over = 0
    for t in range(len(sensory)):  # fills the window, then shifts it
        result, expected = mirror.step(sensory[t]), ref.step(sensory[t])
        np.testing.assert_allclose(result.pb, expected.pb, atol=2e-4)
        np.testing.assert_allclose(result.predicted_hands, expected.predicted_hands, atol=2e-4)
        # The motor command compared normalized, as the network computes it.
        np.testing.assert_allclose(result.motor / SPAN, expected.motor / SPAN, atol=2e-4)
        np.testing.assert_allclose(result.context, expected.context, atol=2e-4)
        np.testing.assert_allclose(result.window_error, expected.window_error, atol=1e-6)
        np.testing.assert_allclose(result.prediction_error, expected.prediction_error, atol=1e-6)
        np.testing.assert_array_equal(result.seen, expected.seen)
        # The recognition's evidence: each learned pattern's window error.
        np.testing.assert_allclose(result.pattern_errors, expected.pattern_errors, atol=1e-5)
        assert not result.held and not expected.held
        assert len(mirror.pb_profile) == len(ref.pb_profile)
        starts_over += len(ref.pb_profile) < min(t + 1, config.window)
    assert mirror.steps == ref.steps == len(sensory)
    np.testing.assert_allclose(mirror.pb, ref.pb, atol=2e-4)
    assert (starts_over > 0) == (phase > 0)


def test_phase_restart_starts_the_window_over_after_a_switch_not_while_locked(trained):
    first, second = make_sequences(n_samples=1, n_steps=45, seed=31, kinds=(0, 2))
    sensory = np.concatenate([first.sensory, second.sensory[:25]])
    motor = np.concatenate([first.motor, second.motor[:25]])
    mirror = MirrorSystem(trained, OnlineConfig().with_tuning(phase_restarts=3))
    lengths, errors = [], []
    for u, m in zip(sensory, motor, strict=True):
        result = mirror.step(u)
        lengths.append(len(mirror.pb_profile))
        errors.append(_motor_error(result.motor, m))
    # Locked on pattern 0 (after the first cycle): the window only grows or stays full.
    assert np.all(np.diff(lengths[12:45]) >= 0), lengths
    # After the switch the window starts over from a state on pattern 2's cycle, and the robot
    # follows the new pattern within a few steps.
    assert min(lengths[45:52]) == 4, lengths[45:]
    assert max(errors[52:]) < 0.05, np.round(errors[45:], 3)
    assert trained.nearest_pattern(mirror.pb)[0] == "2"


def test_phase_candidates_lie_on_each_learned_cycle(trained):
    candidates = phase_candidates(trained, skip=6, steps=24)
    net = trained.network
    assert candidates.shape == (3 * 24, net.pb_size + net.motor_size + net.context_size)
    pbs = 1.0 / (1.0 + np.exp(-candidates[:, : net.pb_size]))
    for k, pb in enumerate(trained.pattern_pb.values()):
        np.testing.assert_allclose(pbs[24 * k : 24 * (k + 1)], np.tile(pb, (24, 1)), atol=1e-4)
    # The motor part follows the learned cycle: one period (12 steps) on, nearly the same.
    motor = candidates[:, net.pb_size : net.pb_size + net.motor_size]
    assert np.sqrt(np.mean((motor[12:24] - motor[:12]) ** 2)) < 0.5


def test_surprise_gate_steadies_the_pb_and_keeps_the_lock(trained):
    # A learned pattern, performed anew: once locked, the gated PB barely moves from step to
    # step (the default), while the ungated one keeps fitting the demonstration's noise.
    demo = make_sequences(n_samples=1, n_steps=60, seed=12, kinds=(1,))[0]
    moves = {}
    for name, config in (("gated", OnlineConfig()), ("ungated", OnlineConfig.ungated())):
        mirror = MirrorSystem(trained, config)
        pbs, errors = [], []
        for t in range(demo.n_steps):
            result = mirror.step(demo.sensory[t])
            pbs.append(result.pb)
            errors.append(_motor_error(result.motor, demo.motor[t]))
        assert max(errors[LOCK_STEPS:]) < 0.05, (name, np.round(errors, 3))
        assert trained.nearest_pattern(pbs[-1])[0] == "1"
        moves[name] = np.median(np.abs(np.diff(np.array(pbs[30:]), axis=0)).max(axis=1))
    assert moves["gated"] < 0.5 * moves["ungated"], moves


@pytest.mark.parametrize(
    "change, message",
    [
        ({"surprise_gate": -0.1}, "surprise_gate"),
        ({"gate_power": 0}, "gate_power"),
        ({"gate_floor": 0}, "gate_floor"),
        ({"gate_steps": 0}, "gate_steps"),
        ({"phase_restarts": -1}, "phase_restarts"),
        ({"phase_restarts": 30}, "phase_restarts"),
        ({"phase_restart_ratio": 0}, "phase_restart_ratio"),
        ({"phase_restart_level": -0.1}, "phase_restart_level"),
    ],
)
def test_bad_surprise_gate_settings_are_refused(change, message):
    with pytest.raises(ConfigError, match=message):
        OnlineConfig().with_tuning(**change)


def test_presets_round_trip_and_only_the_default_is_gated():
    assert OnlineConfig().surprise_gate > 0
    assert OnlineConfig.ungated().surprise_gate == 0 == OnlineConfig.paper().surprise_gate
    for config in (OnlineConfig(), OnlineConfig.ungated(), OnlineConfig.paper()):
        assert OnlineConfig.from_dict(config.to_dict()) == config


def _risk_network(pb_size, seed=0):
    """A risk network that calls much of PB space unsafe (for the guard's parity)."""
    from rnnpb.model.meta import MetaParams

    rng = np.random.default_rng(seed)
    hidden = 8
    return MetaParams(
        w1=rng.normal(0, 2.0, (pb_size, hidden)),
        b1=rng.normal(0, 0.5, hidden),
        w2=rng.normal(0, 1 / np.sqrt(hidden), (hidden, hidden)),
        b2=np.zeros(hidden),
        w3=rng.normal(0, 1.0, hidden),
        b3=np.asarray(1.0),
    )


@pytest.mark.parametrize("guard, span", [("barrier", 3), ("barrier", 0), ("projection", 3)])
def test_the_safety_guard_matches_the_reference(trained, guard, span):
    meta = _risk_network(trained.network.pb_size)
    config = OnlineConfig(window=8, iterations=5, safety_guard=guard).with_tuning(
        barrier_span=span,
        barrier_weight=0.5,
        phase_restarts=0,
    )
    sensory = make_sequences(n_samples=1, n_steps=12, seed=4, kinds=(1,))[0].sensory
    mirror = MIRROR_SYSTEMS["compiled"](trained, config, meta=meta)
    ref = MIRROR_SYSTEMS["reference"](trained, config, meta=meta)
    unguarded = MIRROR_SYSTEMS["reference"](trained, config)
    moved = 0.0
    for u in sensory:
        result, expected, plain = mirror.step(u), ref.step(u), unguarded.step(u)
        np.testing.assert_allclose(result.pb, expected.pb, atol=2e-4)
        np.testing.assert_allclose(result.motor / SPAN, expected.motor / SPAN, atol=2e-4)
        np.testing.assert_allclose(result.predicted_hands, expected.predicted_hands, atol=2e-4)
        moved = max(moved, float(np.abs(expected.pb - plain.pb).max()))
    assert moved > 1e-2  # the guard acted: the comparison is not of two unguarded steps


def test_a_mirror_swapped_in_goes_on_from_the_running_one(trained):
    """A new version swapped in while the robot runs (teaching) continues the interaction:
    without it the first command comes from an empty window and jumps."""
    demo = make_sequences(n_samples=1, n_steps=60, seed=31, kinds=(1,))[0]

    def jump_at_swap(carry: bool) -> float:
        running, swapped = MirrorSystem(trained), MirrorSystem(trained)
        motors = [running.step(u).motor for u in demo.sensory[:40]]
        if carry:
            assert swapped.continue_from(running)
            assert swapped.steps == running.steps
            np.testing.assert_allclose(swapped.pb, running.pb)
        motors.append(swapped.step(demo.sensory[40]).motor)
        steps = np.abs(np.diff(np.array(motors), axis=0)) / SPAN
        return float(steps[-1].max()) / float(np.percentile(steps[20:-1].max(axis=1), 95))

    assert jump_at_swap(carry=True) < 1.5  # within the movement's own step sizes
    assert jump_at_swap(carry=False) > 1.5  # the jump it removes


def test_a_mirror_of_another_window_starts_afresh(trained):
    demo = make_sequences(n_samples=1, n_steps=12, seed=5, kinds=(1,))[0]
    running = MirrorSystem(trained)
    for u in demo.sensory:
        running.step(u)
    other = MirrorSystem(trained, OnlineConfig(window=running.config.window + 5))
    assert not other.continue_from(running)
    assert other.steps == 0 and len(other.pb_profile) == 0


def test_the_levels_grow_with_how_far_the_hands_move_a_step():
    """The surprise gate's and the phase restarts' levels are judged against the movement: a
    window whose hands move as far a step as the movement they were tuned on, or less, keeps
    them as they are; one that moves three times as far has them three times higher."""
    from rnnpb.model.online import level_scale
    from rnnpb.model.online_config import TUNED_MOVEMENT

    def scale(step: float) -> float:
        t = np.arange(8, dtype=np.float32)
        sensory = np.stack([0.5 + step * t * (-1) ** k for k in range(4)], axis=1)
        seen = np.broadcast_to(np.arange(8)[:, None] < 6, (8, 4))
        return level_scale(np.where(seen, sensory, 0.0).astype(np.float32), seen.copy(), 6, 4)

    assert scale(0.0) == 1.0  # still hands: the levels as tuned
    assert scale(0.5 * TUNED_MOVEMENT) == 1.0
    assert scale(3 * TUNED_MOVEMENT) == pytest.approx(3.0, rel=1e-5)
