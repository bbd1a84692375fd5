"""The tracker without calibration in a cluttered room: look-alikes of the balls' colours and
sizes, flicker and blur (short forms of ``benchmarks/tracking_clutter.py``)."""

from __future__ import annotations

import numpy as np
import pytest

from rnnpb.perception import BallTracker, hard_scene, score_scene


@pytest.mark.parametrize("kind", ["static", "flicker"])
def test_still_look_alikes_flicker_and_blur_do_not_take_the_balls(kind):
    score = score_scene(hard_scene(kind, seed=5, n_frames=60))
    assert score.mean_error_px <= 3.0
    assert score.tracked_fraction >= 0.95
    assert score.wrong == 0


def test_a_still_book_of_the_ball_colour_is_given_up_once_the_ball_moves():
    # A dark-blue book and a still blue round object in the room: on the first frame either
    # could be the ball, so the tracker waits; from the first frames of motion on it is the
    # ball, never the book.
    camera = hard_scene("static", seed=6, n_frames=30)
    tracker = BallTracker()
    with camera:
        for frame in camera:
            result = tracker.track(frame)
            truth = camera.last_truth
            ball = result.balls[1]
            if ball.tracked:
                assert np.linalg.norm(ball.center_px - truth["center_px"][1]) < 3.0
            elif truth["frame"] > 3:
                pytest.fail(f"right ball lost at frame {truth['frame']}")
