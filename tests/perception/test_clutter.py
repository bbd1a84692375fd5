"""The tracker without calibration in a cluttered room: look-alikes of the balls' colours and
sizes, flicker and blur (short forms of ``benchmarks/tracking_clutter.py``)."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from rnnpb.perception import BallTracker, hard_scene, score_scene, split_disk


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


_BLUE = (195, 70, 30)  # the synthetic right-hand ball's colour (BGR)


def _disk(frame, center, radius, color=_BLUE):
    c = (int(round(center[0] * 16 - 8)), int(round(center[1] * 16 - 8)))
    cv2.circle(frame, c, int(round(radius * 16)), color, -1, cv2.LINE_AA, shift=4)


def test_split_disk_finds_a_ball_touching_a_book_of_its_colour():
    mask = np.zeros((200, 240), np.uint8)
    cv2.circle(mask, (int(100.3 * 16), int(80.7 * 16)), 20 * 16, 255, -1, shift=4)
    cv2.rectangle(mask, (118, 60), (170, 120), 255, -1)  # overlaps the disk's right side
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    assert len(contours) == 1  # one merged blob
    found = split_disk(mask, contours[0], np.array([104.0, 78.0]), 20.0)
    assert found is not None
    center, area = found
    # the mask's pixel (i, j) is centred at (i + 0.5, j + 0.5)
    assert np.linalg.norm(center - [100.8, 81.2]) < 0.6
    assert abs(math.sqrt(area / math.pi) - 20.0) < 1.5
    # a book alone holds no ball
    book = np.zeros_like(mask)
    cv2.rectangle(book, (118, 60), (170, 100), 255, -1)
    contours, _ = cv2.findContours(book, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    assert split_disk(book, contours[0], np.array([144.0, 80.0]), 20.0) is None


def _run(frames_and_truth):
    tracker = BallTracker()
    errors, lost = [], 0
    for frame, truth in frames_and_truth:
        ball = tracker.track(frame).balls[1]
        if ball.tracked:
            errors.append(float(np.linalg.norm(ball.center_px - truth)))
        else:
            lost += 1
    return np.asarray(errors), lost


def test_a_ball_running_into_a_still_book_of_its_colour_is_followed_through_the_merge():
    def frames():
        for t in range(40):
            frame = np.full((240, 320, 3), 170, np.uint8)
            cv2.rectangle(frame, (196, 104), (230, 136), (120, 40, 20), -1)  # dark-blue book
            center = np.array([160.0 - 42.0 * math.cos(t * 2 * math.pi / 20), 120.0])
            _disk(frame, center, 18.0)
            yield frame, center

    errors, lost = _run(frames())
    assert lost <= 3  # the first frames: nothing has moved yet
    assert errors.max() < 2.0  # merged with the book in half of the frames, yet never off


def test_a_round_look_alike_crossing_the_ball_does_not_take_the_track():
    def frames():
        for t in range(50):
            frame = np.full((240, 320, 3), 170, np.uint8)
            # a blue round object going straight across, behind the hand
            _disk(frame, np.array([-40.0 + 6.0 * t, 120.0]), 19.0, (190, 75, 35))
            center = np.array([160.0, 120.0 + 60.0 * math.sin(t * 2 * math.pi / 16)])
            _disk(frame, center, 18.0)
            yield frame, center

    errors, lost = _run(frames())
    assert lost <= 3  # the first frames: nothing has moved yet
    # where the two overlap most the centre is pulled a little; the track is never taken
    assert np.all(errors < 8.0), "the look-alike took the ball's track"
    assert np.sum(errors > 2.0) <= 2
    assert np.mean(errors) < 0.5
