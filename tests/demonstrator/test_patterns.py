"""Each pattern has its defining property on the sensory side and on the motor side."""

import numpy as np
import pytest

from rnnpb.demonstrator import (
    Imperfection,
    MirrorMapping,
    PatternConfig,
    pattern_dataset,
    perform,
    resolve_pattern,
)
from rnnpb.errors import ConfigError
from rnnpb.robot import forward_kinematics


def corr(a, b):
    return float(np.corrcoef(a, b)[0, 1])


def signed_area(y, z):
    """Shoelace area of a closed path in the view plane: > 0 counter-clockwise."""
    return 0.5 * float(np.sum(y * np.roll(z, -1) - np.roll(y, -1) * z))


def view_paths(sensory):
    """(n, 4) → per hand (Y, Z) with Y to the robot's right, Z up."""
    return sensory[:, 0], sensory[:, 1], sensory[:, 2], sensory[:, 3]


def robot_view_paths(motor):
    """Robot hands from FK as the robot's mirror-partner would see them: (Y, Z) per hand.

    Returned in the user's hand order (the robot's right arm mirrors the user's left hand),
    with Y = -y so that it has the sense of the sensory Y.
    """
    hands, _ = forward_kinematics(motor)
    right, left = hands[:, 1], hands[:, 0]
    return -right[:, 1], right[:, 2], -left[:, 1], left[:, 2]


@pytest.fixture(scope="module")
def dataset():
    return {s.pattern: s for s in pattern_dataset(seed=7, samples_per_pattern=1, n_steps=50)}


@pytest.mark.parametrize("side", ["sensory", "motor"])
def test_pattern_properties(dataset, side):
    paths = view_paths if side == "sensory" else robot_view_paths
    for pattern, seq in dataset.items():
        ly, lz, ry, rz = paths(seq.sensory if side == "sensory" else seq.motor)
        h_extent = np.ptp(ly) + np.ptp(ry)
        v_extent = np.ptp(lz) + np.ptp(rz)
        if pattern == "1":  # horizontal, opposite phase
            assert h_extent > 3 * v_extent
            assert corr(ly, ry) < -0.9
        elif pattern == "2":  # vertical, in phase
            assert v_extent > 3 * h_extent
            assert corr(lz, rz) > 0.9
        else:  # rotation: both extents, counter-clockwise as the robot sees it
            assert 0.5 < h_extent / v_extent < 2.0
            cycle = slice(0, 12)
            for y, z in ((ly, lz), (ry, rz)):
                assert signed_area(y[cycle] - y.mean(), z[cycle] - z.mean()) != 0
            areas = [signed_area(y - y.mean(), z - z.mean()) for y, z in ((ly, lz), (ry, rz))]
            assert all(a > 0 for a in areas), areas
            sign = -1 if pattern == "3" else 1
            assert sign * corr(ly, ry) > 0.8 and sign * corr(lz, rz) > 0.8


def test_motor_side_joint_symmetry():
    """Mirror-symmetric joint senses: patterns 1 and 2 are mirror-symmetric movements, so a
    noise-free user moves both robot arms' joints alike."""
    perfect = PatternConfig(imperfection=Imperfection.none())
    for pattern in ("1", "2"):
        m = pattern_dataset(0, (pattern,), 1, 24, perfect)[0].motor
        for j in range(4):
            if np.std(m[:, j]) > 0.1:  # joints that carry the movement, not the noise
                assert corr(m[:, j], m[:, j + 4]) > 0.99, (pattern, j)


def test_direction_parameter_reverses_rotation():
    rng = np.random.default_rng(0)
    cfg = PatternConfig(direction=-1, imperfection=Imperfection.none())
    motion = perform([("4", 12)], cfg, rng, phase=0.0)
    y = -motion.hands[:, 0, 1]
    z = motion.hands[:, 0, 2]
    assert signed_area(y - y.mean(), z - z.mean()) < 0


def test_perfect_user_is_exactly_periodic_and_imperfect_user_is_not():
    perfect = PatternConfig(imperfection=Imperfection.none())
    motion = perform([("3", 36)], perfect, np.random.default_rng(1), phase=0.3)
    np.testing.assert_allclose(motion.hands[:12], motion.hands[12:24], atol=1e-12)
    np.testing.assert_array_equal(motion.hands, motion.measured)
    noisy = perform([("3", 36)], PatternConfig(), np.random.default_rng(1), phase=0.3)
    cycle_difference = np.abs(noisy.hands[:12] - noisy.hands[12:24]).max()
    assert 0.003 < cycle_difference < 0.08  # not always completely cyclic, still the pattern
    noise = noisy.measured - noisy.hands
    assert 0.002 < noise.std() < 0.006  # 4 mm sensor noise


def test_period_parameter_sets_the_cycle_length():
    for period in (8.0, 12.0, 20.0):
        cfg = PatternConfig(period_steps=period, imperfection=Imperfection.none())
        motion = perform([("2", 100)], cfg, np.random.default_rng(0), phase=0.0)
        z = motion.hands[:, 0, 2] - motion.hands[:, 0, 2].mean()
        spectrum = np.abs(np.fft.rfft(z, n=4000))
        freq = np.fft.rfftfreq(4000)[np.argmax(spectrum)]
        assert abs(1 / freq - period) < 0.05 * period


def test_sensory_values_stay_inside_the_image_with_margin():
    seqs = pattern_dataset(seed=3, samples_per_pattern=5, n_steps=100)
    sensory = np.concatenate([s.sensory for s in seqs])
    assert sensory.min() > 0.1 and sensory.max() < 0.9


def test_mirror_mapping_sides_and_scale():
    mapping = MirrorMapping()
    user = mapping.body.hand_centres
    targets = mapping.robot_hand_targets(user)
    # The user's left hand (robot's right, -y) drives the robot's right arm (index 1, -y).
    assert targets[1, 1] < 0 < targets[0, 1]
    # Moving the user's left hand towards the robot moves the robot's right hand forward.
    moved = user.copy()
    moved[0, 0] -= 0.1
    delta = mapping.robot_hand_targets(moved) - targets
    np.testing.assert_allclose(delta[1], [0.1 * mapping.effective_scale, 0, 0], atol=1e-12)
    np.testing.assert_allclose(delta[0], 0, atol=1e-12)
    assert 0.25 < mapping.effective_scale < 0.45  # robot reach 0.21 m / human reach 0.62 m


def test_resolve_pattern_aliases_and_errors():
    assert resolve_pattern("rotation-in-phase") == "4"
    assert resolve_pattern(2) == "2"
    with pytest.raises(ConfigError, match="unknown movement pattern"):
        resolve_pattern("5")
    with pytest.raises(ConfigError, match="period_steps"):
        PatternConfig(period_steps=1)


def test_new_shapes_repeat_and_unstructured_movements_do_not():
    from rnnpb.analysis.metrics import periodicity
    from rnnpb.demonstrator import NEW_SHAPES, PATTERNS, UNSTRUCTURED, make_scenario

    config = PatternConfig(imperfection=Imperfection.none())
    sensory = {
        m: make_scenario([(m, 72)], seed=2, config=config).sensory
        for m in (*NEW_SHAPES, *UNSTRUCTURED)
    }
    for shape in NEW_SHAPES:
        assert periodicity(sensory[shape]).best_period == 12, shape
        # Each shape differs from every paper pattern and from the other shapes.
        for other in (*PATTERNS, *NEW_SHAPES):
            if other != shape:
                theirs = make_scenario([(other, 72)], seed=2, config=config).sensory
                assert np.abs(theirs - sensory[shape]).max() > 0.05, (shape, other)
    for movement in UNSTRUCTURED:
        x = sensory[movement]
        assert periodicity(x).period is None, movement
        assert x.std(axis=0).min() > 0.02 and 0.0 <= x.min() and x.max() <= 1.0


def test_unstructured_movements_leave_the_paper_patterns_draws_alone():
    from rnnpb.demonstrator import make_scenario

    with_walk = make_scenario([("1", 30), ("random-walk", 30)], seed=5)
    with_pause = make_scenario([("1", 30), ("pause", 30)], seed=5)
    np.testing.assert_array_equal(with_walk.sensory[:30], with_pause.sensory[:30])
    again = make_scenario([("1", 30), ("random-walk", 30)], seed=5)
    np.testing.assert_array_equal(with_walk.sensory, again.sensory)
