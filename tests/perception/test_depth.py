"""Depth from the balls' apparent size, and the fixed plane of sources without depth."""

from __future__ import annotations

import numpy as np
import pytest

from rnnpb.errors import ConfigError
from rnnpb.perception import (
    MOUSE_PLANE_X,
    DepthConfig,
    depth_from_size,
    fill_gaps,
    hands_from_balls,
    hands_on_plane,
    oscillating_hands,
    running_median,
)
from rnnpb.robot.camera import RobotCamera


def test_depth_from_size_inverts_the_apparent_radius():
    camera = RobotCamera()
    depth = np.array([0.4, 0.65, 1.2])
    radius = camera.apparent_radius_px(depth, 0.04)
    assert np.allclose(depth_from_size(radius, camera, 0.04), depth)
    # the same ball measured in frames half the model's size looks half as large
    assert np.allclose(depth_from_size(radius / 2, camera, 0.04, image_height=240), depth)
    assert np.isnan(depth_from_size(np.array([0.0, np.nan]), camera, 0.04)).all()


def test_exact_centres_and_radii_give_back_the_hands():
    camera = RobotCamera()
    hands = oscillating_hands(30)
    centers, depth = camera.project(hands)
    radius = camera.apparent_radius_px(depth, 0.04)
    recovered = hands_from_balls(centers, radius, camera, DepthConfig(median_steps=1))
    assert np.allclose(recovered, hands, atol=1e-9)


def test_a_one_frame_outlier_in_size_is_filtered_and_short_gaps_are_filled():
    camera = RobotCamera()
    hands = oscillating_hands(40, period=30.0)
    centers, depth = camera.project(hands)
    radius = camera.apparent_radius_px(depth, 0.04)
    radius[10, 0] *= 0.5  # half hidden: looks twice as far
    centers[20:23, 1] = np.nan  # lost for three frames
    radius[20:23, 1] = np.nan
    centers[30:39, 0] = np.nan  # lost for nine: too long to guess
    radius[30:39, 0] = np.nan
    recovered = hands_from_balls(centers, radius, camera, DepthConfig(max_gap_steps=5))
    # unfiltered, the half-hidden ball would be placed about 0.9 m too far; the median keeps
    # it within what the hand moves in one step
    assert abs(recovered[10, 0, 0] - hands[10, 0, 0]) < 0.01
    assert np.isfinite(recovered[20:23, 1]).all()
    assert np.abs(recovered[20:23, 1] - hands[20:23, 1]).max() < 0.02
    assert np.isnan(recovered[30:39, 0]).all()


def test_running_median_and_fill_gaps_leave_what_they_cannot_know():
    values = np.array([1.0, 1.0, 9.0, 1.0, 1.0, np.nan, 1.0])
    assert np.array_equal(running_median(values, 3)[:5], [1.0, 1.0, 1.0, 1.0, 1.0])
    assert np.isnan(running_median(values, 3)[5])
    edge = np.array([np.nan, 1.0, np.nan, 3.0, np.nan])
    assert np.allclose(fill_gaps(edge, 2)[1:4], [1.0, 2.0, 3.0])
    assert np.isnan(fill_gaps(edge, 2)[[0, 4]]).all()  # no measurement on one side


def test_hands_on_the_plane_are_seen_where_the_mouse_put_them():
    camera = RobotCamera()
    sensory = np.array([[0.7, 0.5, 0.3, 0.6], [0.5, 0.9, 0.45, 0.1]])
    hands = hands_on_plane(sensory, camera)
    assert hands.shape == (2, 2, 3)
    assert np.allclose(hands[..., 0], MOUSE_PLANE_X)
    assert np.allclose(camera.sensory_from_hands(hands), sensory)
    assert np.isnan(hands_on_plane(np.full(4, np.nan), camera)).all()
    with pytest.raises(ConfigError, match="in front of the camera"):
        hands_on_plane(sensory, camera, plane_x=0.0)


def test_depth_config_is_validated():
    with pytest.raises(ConfigError, match="odd"):
        DepthConfig(median_steps=4)
    with pytest.raises(ConfigError, match="ball_radius_m"):
        DepthConfig(ball_radius_m=0.0)
