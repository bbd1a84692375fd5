"""Bare hands: the pose tracker's normalisation to the body (no model needed), the learning
phase through it, and the commands without the extra. The model itself: test_pose_model.py."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from rnnpb.cli import main
from rnnpb.commands._perception import PERCEPTION_CHOICES
from rnnpb.demonstrator import UserBody
from rnnpb.errors import ConfigError, RnnpbError
from rnnpb.interaction import open_source
from rnnpb.learning_phase import from_source, resampled, sensory_at
from rnnpb.perception import (
    HANDS_INSTALL,
    PERCEPTIONS,
    BodyLandmarks,
    DepthConfig,
    PoseConfig,
    PoseTracker,
    TrackedUserSource,
    hands_from_pose,
    hands_relative_to_body,
    open_camera_source,
    open_frame_source,
    pose_available,
    synthetic_user_hands,
)
from rnnpb.robot.camera import RobotCamera
from rnnpb.web._protocol import ProtocolError, parse_client_message

SIZE = (640, 480)


def seen_by_robot(hands: np.ndarray, body: UserBody | None = None) -> BodyLandmarks:
    """The landmarks of the standard user with these 3-D hands (2, 3), as the robot's camera
    sees them: what a perfect pose model would report from the synthetic user."""
    body = body or UserBody()
    camera = RobotCamera()
    shoulders, _ = camera.project(body.shoulders)
    wrists, _ = camera.project(hands)
    span_m = 2 * body.shoulder_half_width
    return BodyLandmarks(
        shoulders=shoulders,
        wrists=wrists,
        wrist_depth=(hands[:, 0] - body.distance) / span_m,
        visibility=np.ones(4),
    )


def moved(landmarks: BodyLandmarks, scale: float, shift: tuple[float, float]) -> BodyLandmarks:
    """The same person seen bigger or smaller and elsewhere in the frame."""
    return BodyLandmarks(
        landmarks.shoulders * scale + shift,
        landmarks.wrists * scale + shift,
        landmarks.wrist_depth,
        landmarks.visibility,
    )


HANDS = synthetic_user_hands("3", 40, seed=1)


def test_the_standard_user_gives_the_sensory_values_of_the_balls():
    camera = RobotCamera()
    for hands in HANDS[::7]:
        result = hands_relative_to_body(seen_by_robot(hands), SIZE)
        np.testing.assert_allclose(result.sensory, camera.sensory_from_hands(hands), atol=1e-9)
        np.testing.assert_allclose(result.hands_3d, hands, atol=1e-9)
        assert result.status == ("tracked", "tracked")


def test_a_person_nearer_farther_or_off_centre_makes_the_same_gesture():
    for hands in HANDS[::9]:
        landmarks = seen_by_robot(hands)
        reference = hands_relative_to_body(landmarks, SIZE).sensory
        for scale, shift in ((0.5, (40.0, 200.0)), (1.7, (-150.0, -60.0)), (1.0, (90.0, 0.0))):
            result = hands_relative_to_body(moved(landmarks, scale, shift), SIZE)
            np.testing.assert_allclose(result.sensory, reference, atol=1e-9)
        # a person higher in the frame is not a person whose hands are lower
        assert not np.allclose(
            hands_relative_to_body(
                BodyLandmarks(
                    landmarks.shoulders,
                    landmarks.wrists + (0.0, 30.0),
                    landmarks.wrist_depth,
                    landmarks.visibility,
                ),
                SIZE,
            ).sensory,
            reference,
        )


def test_lost_hands_are_nan():
    landmarks = seen_by_robot(HANDS[0])
    hidden_right = BodyLandmarks(
        landmarks.shoulders, landmarks.wrists, landmarks.wrist_depth, np.array([1, 1, 0.9, 0.2])
    )
    result = hands_relative_to_body(hidden_right, SIZE)
    assert result.status == ("tracked", "lost")
    assert np.isfinite(result.sensory[:2]).all() and np.isnan(result.sensory[2:]).all()
    assert np.isnan(result.hands_3d[1]).all() and np.isfinite(result.hands_3d[0]).all()
    # no body scale: a shoulder unseen, or shoulders too close together (a person side-on)
    for unseen in (
        BodyLandmarks(
            landmarks.shoulders, landmarks.wrists, landmarks.wrist_depth, np.array([1, 0.1, 1, 1])
        ),
        BodyLandmarks(
            landmarks.shoulders.mean(axis=0) + np.array([[-5.0, 0.0], [5.0, 0.0]]),
            landmarks.wrists,
            landmarks.wrist_depth,
            np.ones(4),
        ),
    ):
        result = hands_relative_to_body(unseen, SIZE)
        assert result.status == ("lost", "lost") and np.isnan(result.sensory).all()
    # a wrist landmark far beyond an arm's reach is on something else
    astray = BodyLandmarks(
        landmarks.shoulders,
        landmarks.wrists + np.array([[0.0, 0.0], [900.0, 0.0]]),
        landmarks.wrist_depth,
        np.ones(4),
    )
    assert hands_relative_to_body(astray, SIZE).status == ("tracked", "lost")


def test_depth_comes_from_the_wrists_relative_depth_in_shoulder_spans():
    body = UserBody()
    landmarks = seen_by_robot(HANDS[0])
    span_m = 2 * body.shoulder_half_width
    for spans, expected_x in (
        (0.0, body.distance),  # hands in the shoulders' plane
        (-0.5, body.distance - 0.5 * span_m),
        (-10.0, body.distance - body.arm_reach),  # no farther than an arm reaches
        (3.0, body.distance),  # not behind the body
        (np.nan, body.hand_depth),  # no depth: the standard hands' plane
    ):
        result = hands_relative_to_body(
            BodyLandmarks(
                landmarks.shoulders, landmarks.wrists, np.full(2, spans), landmarks.visibility
            ),
            SIZE,
        )
        np.testing.assert_allclose(result.hands_3d[:, 0], expected_x, atol=1e-9)
        # the sensory values do not depend on the depth estimate
        np.testing.assert_allclose(
            result.sensory, hands_relative_to_body(landmarks, SIZE).sensory, atol=1e-12
        )


def test_a_recording_filters_the_depth_and_bridges_short_gaps():
    hands = np.repeat(HANDS[:1], 12, axis=0).copy()
    hands[5, 0, 0] -= 0.2  # a one-step spike in depth
    hands[8:10, 1] = np.nan  # a short loss
    hands[0, 0] = np.nan  # at the start: nothing to bridge from
    filtered = hands_from_pose(hands, DepthConfig(median_steps=3, max_gap_steps=5))
    np.testing.assert_allclose(filtered[5, 0, 0], HANDS[0, 0, 0])
    np.testing.assert_allclose(filtered[8:10, 1], np.repeat(HANDS[:1, 1], 2, axis=0))
    assert np.isnan(filtered[0, 0]).all()
    with pytest.raises(ConfigError):
        hands_from_pose(np.zeros((3, 4)))


class _PerfectPoseTracker(PoseTracker):
    """The pose tracker with the model replaced by the synthetic camera's truth."""

    def __init__(self, frames) -> None:
        self.config = PoseConfig()
        self.frames = frames

    def reset(self) -> None:
        pass

    def landmarks(self, frame):
        return seen_by_robot(self.frames.hands[self.frames.frame_index])


def test_recording_bare_hands_gives_the_users_hands_and_pose_depth():
    frames = open_frame_source("synthetic", "3", steps=30, seed=2)
    source = TrackedUserSource(frames, _PerfectPoseTracker(frames))
    assert source.perception == "pose"
    with source:
        performance = from_source(source)
    assert performance.depth == "pose" and performance.body
    # y and z as the user's; the depth through a 3-step running median (within 5 mm here)
    np.testing.assert_allclose(performance.hands[..., 1:], frames.hands[..., 1:], atol=1e-6)
    np.testing.assert_allclose(performance.hands[..., 0], frames.hands[..., 0], atol=0.005)
    # framed where the synthetic user stands, the camera sees the user's own hands
    steps = resampled(performance, 0.4)
    np.testing.assert_allclose(
        sensory_at(steps, performance, 1.0, RobotCamera()),
        RobotCamera().sensory_from_hands(frames.hands),
        atol=1e-9,
    )


def test_the_commands_and_the_page_offer_the_same_perceptions():
    assert PERCEPTION_CHOICES == PERCEPTIONS
    assert parse_client_message('{"type": "perception", "perception": "pose"}') == {
        "type": "perception",
        "perception": "pose",
    }
    for bad in ('"skeleton"', "1", '["pose"]'):
        with pytest.raises(ProtocolError):
            parse_client_message(f'{{"type": "perception", "perception": {bad}}}')


def test_perception_pose_applies_to_cameras_only():
    with pytest.raises(ConfigError, match="camera sources"):
        open_source("scenario:held:1", perception="pose")
    with pytest.raises(ConfigError, match="perception must be one of"):
        open_camera_source("synthetic", "1", perception="skeleton")


@pytest.fixture
def without_extra(monkeypatch):
    """As on a machine without ``rnnpb[hands]``: importing the model's package fails."""
    for name in [n for n in sys.modules if n == "mediapipe" or n.startswith("mediapipe.")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "mediapipe", None)


def test_without_the_extra_one_line_names_the_install_command(without_extra, tmp_path, capsys):
    assert not pose_available()
    with pytest.raises(RnnpbError) as error:
        open_camera_source("synthetic", "1", steps=3, perception="pose")
    assert HANDS_INSTALL in str(error.value) and "\n" not in str(error.value)
    out = tmp_path / "bare.csv"
    assert main(["track", "synthetic:1", "--steps", "3", "--perception", "pose", "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert err.startswith("rnnpb: error:") and HANDS_INSTALL in err and "\n" not in err
    assert not out.exists()


def test_the_dashboard_switch_says_what_to_install_and_keeps_the_balls(without_extra, tmp_path):
    from rnnpb.models import default_model
    from rnnpb.web import find_models
    from rnnpb.web._session import Session

    session = Session(find_models(default_model()), workdir=tmp_path)
    try:
        with pytest.raises(RnnpbError, match=r"pip install 'rnnpb\[hands\]'"):
            session._apply({"type": "perception", "perception": "pose"})
        assert session.perception == "balls"
        session._apply({"type": "perception", "perception": "balls"})  # unchanged: nothing to do
        assert session.perception == "balls"
    finally:
        session.close()
