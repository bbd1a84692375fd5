"""The tracker against rendered frames with known ground truth."""

from __future__ import annotations

import numpy as np
import pytest

from rnnpb.demonstrator import PatternConfig, perform
from rnnpb.errors import ConfigError
from rnnpb.perception import (
    BallTracker,
    SceneConfig,
    SyntheticCamera,
    TrackerConfig,
    center_errors,
    oscillating_hands,
)


def _track(camera: SyntheticCamera, tracker: BallTracker | None = None):
    tracker = tracker or BallTracker()
    out = []
    with camera:
        for frame in camera:
            out.append((tracker.track(frame), camera.last_truth))
    return out


def test_clean_frames_centre_error_below_one_pixel_and_identity_right():
    stats = center_errors(SceneConfig.clean(seed=1), 80)
    assert stats["n"] == 160
    assert stats["mean_px"] < 1.0
    assert stats["max_px"] < 1.0
    assert stats["lost_visible"] == 0
    assert stats["swapped"] == 0


def test_noisy_blurred_cluttered_frames_centre_error_below_three_pixels():
    stats = center_errors(SceneConfig.hard(seed=2, occlusion_probability=0.0), 120)
    assert stats["mean_px"] < 3.0
    assert stats["lost_visible"] == 0
    assert stats["swapped"] == 0


@pytest.mark.parametrize("pattern", ["1", "2", "3", "4"])
def test_synthetic_user_every_visible_ball_found_with_its_own_hand(pattern):
    hands = perform([(pattern, 40)], PatternConfig(), np.random.default_rng(5)).hands
    camera = SyntheticCamera(hands, scene=SceneConfig(seed=5, occlusion_probability=0.0))
    errors = []
    for result, truth in _track(camera):
        for i, ball in enumerate(result.balls):
            if truth["visible_fraction"][i] < 1.0:
                continue
            assert ball.tracked
            d = np.linalg.norm(truth["center_px"] - ball.center_px, axis=1)
            assert d[i] < d[1 - i], "a ball was reported for the wrong hand"
            errors.append(d[i])
            # the sensory values are the centre normalized: Y = col / w, Z = 1 - row / h
            np.testing.assert_allclose(
                result.sensory[2 * i : 2 * i + 2],
                truth["sensory"][2 * i : 2 * i + 2],
                atol=3.0 / 480,
            )
    assert len(errors) > 60
    assert np.mean(errors) < 3.0


def test_depth_from_apparent_size_within_five_percent():
    camera = SyntheticCamera(oscillating_hands(30), scene=SceneConfig.clean())
    for result, truth in _track(camera):
        for i, ball in enumerate(result.balls):
            assert abs(ball.depth_m - truth["depth_m"][i]) < 0.05 * truth["depth_m"][i]
            # the 3-D position is back-projected at that depth: near the true hand
            assert np.linalg.norm(ball.position - camera.hands[truth["frame"], i]) < 0.06


def test_occluded_ball_is_lost_with_nan_then_tracked_again():
    scene = SceneConfig(seed=3, occlusion_probability=0.0, occlusions=((0, 10, 17), (1, 25, 28)))
    camera = SyntheticCamera(oscillating_hands(40), scene=scene)
    results = _track(camera)
    for t, (result, truth) in enumerate(results):
        for i in (0, 1):
            hidden = truth["occluded"][i]
            assert result.balls[i].tracked == (not hidden), (t, i)
            assert np.isnan(result.sensory[2 * i : 2 * i + 2]).all() == hidden
    assert [r.status for r, _ in results[9:11]] == [("tracked", "tracked"), ("lost", "tracked")]
    # recovered at the first frame it shows again, at the right place
    result, truth = results[17]
    assert result.status == ("tracked", "tracked")
    assert np.linalg.norm(result.balls[0].center_px - truth["center_px"][0]) < 1.0


def test_distractors_of_the_ball_colours_do_not_steal_the_balls():
    scene = SceneConfig(seed=4, distractors=8, occlusion_probability=0.0)
    camera = SyntheticCamera(oscillating_hands(40, seed=4), scene=scene)
    for result, truth in _track(camera):
        for i, ball in enumerate(result.balls):
            if truth["visible_fraction"][i] == 1.0:
                assert np.linalg.norm(ball.center_px - truth["center_px"][i]) < 3.0


def test_smoothing_reduces_jitter_of_a_still_ball():
    hands = np.repeat(oscillating_hands(1), 40, axis=0)
    scene = SceneConfig.hard(seed=6, occlusion_probability=0.0)
    raw = [r.balls[0].center_px for r, _ in _track(SyntheticCamera(hands, scene=scene))]
    smooth_tracker = BallTracker(TrackerConfig(smoothing=0.7))
    smooth = [
        r.balls[0].center_px for r, _ in _track(SyntheticCamera(hands, scene=scene), smooth_tracker)
    ]
    assert (
        np.std(np.asarray(smooth)[10:], axis=0).sum() < np.std(np.asarray(raw)[10:], axis=0).sum()
    )


def test_rendering_is_deterministic_for_a_seed_and_differs_across_seeds():
    hands = oscillating_hands(5)
    a, _ = SyntheticCamera(hands, scene=SceneConfig(seed=7)).render(3)
    b, _ = SyntheticCamera(hands, scene=SceneConfig(seed=7)).render(3)
    c, _ = SyntheticCamera(hands, scene=SceneConfig(seed=8)).render(3)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


def test_ball_leaving_the_image_is_lost_not_an_error():
    hands = oscillating_hands(6)
    hands[3:, 1, 1] = 3.0  # right hand far to the robot's left: out of view
    results = _track(SyntheticCamera(hands, scene=SceneConfig.clean()))
    assert [r.balls[1].tracked for r, _ in results] == [True] * 3 + [False] * 3
    assert all(r.balls[0].tracked for r, _ in results)


def test_tracker_config_and_frame_are_validated():
    with pytest.raises(ConfigError, match="smoothing"):
        TrackerConfig(smoothing=1.0)
    with pytest.raises(ConfigError, match="min_circularity"):
        TrackerConfig(min_circularity=2.0)
    with pytest.raises(ConfigError, match="BGR uint8"):
        BallTracker().track(np.zeros((48, 64), np.uint8))
