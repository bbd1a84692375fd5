"""Rendered images show the robot where the kinematics put it."""

import numpy as np
import pytest

from rnnpb.demonstrator import pattern_dataset
from rnnpb.errors import ConfigError
from rnnpb.robot import (
    ROBOT_EYE,
    RobotCamera,
    RobotRenderer,
    forward_kinematics,
    load_model,
    write_video,
)

HAND_GEOMS = ("lhand_geom", "rhand_geom")


def front_camera(model) -> tuple[np.ndarray, np.ndarray, float]:
    cam = model.camera("front")
    import mujoco

    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return (
        data.cam_xpos[cam.id].copy(),
        data.cam_xmat[cam.id].reshape(3, 3).copy(),
        float(model.cam_fovy[cam.id]),
    )


def project(points, cam_pos, cam_mat, fovy_deg, width, height):
    """MuJoCo camera: x right, y up, looking along -z."""
    rel = (points - cam_pos) @ cam_mat
    focal = 0.5 * height / np.tan(np.radians(fovy_deg) / 2)
    col = width / 2 + focal * rel[..., 0] / -rel[..., 2]
    row = height / 2 - focal * rel[..., 1] / -rel[..., 2]
    return np.stack([col, row], -1)


@pytest.fixture(scope="module")
def renderer():
    with RobotRenderer(320, 240) as r:
        yield r


def test_front_view_shows_the_robot_and_both_hands_where_fk_says(renderer):
    model = renderer.model
    seqs = pattern_dataset(seed=0, samples_per_pattern=1, n_steps=12)
    cam = front_camera(model)
    ids = {model.geom(n).id for n in HAND_GEOMS}
    for seq in seqs:
        for joints in seq.motor[::4]:
            seg = renderer.segmentation(joints, "front")
            image = renderer.render(joints, "front")
            robot_pixels = seg > model.geom("floor").id
            assert robot_pixels.mean() > 0.02  # the robot fills a visible part of the view
            hands, _ = forward_kinematics(joints)
            pixels = project(hands, *cam, renderer.width, renderer.height).round().astype(int)
            for (col, row), name in zip(pixels, HAND_GEOMS, strict=True):
                patch = seg[row - 2 : row + 3, col - 2 : col + 3]
                assert model.geom(name).id in patch, f"{name} not at its FK pixel {col, row}"
            assert ids <= set(np.unique(seg))
            # Rendering is deterministic: the same pose gives the same image.
            assert np.array_equal(image, renderer.render(joints, "front"))


def test_robot_eye_sees_the_user_balls_where_robot_camera_projects_them(renderer):
    camera = RobotCamera()
    with RobotRenderer(camera.width, camera.height, camera) as eye:
        seq = pattern_dataset(seed=1, patterns=("3",), samples_per_pattern=1, n_steps=6)[0]
        for t in range(6):
            hands = seq.meta["hands"][t]
            seg = eye.segmentation(seq.motor[t], ROBOT_EYE, user_hands=hands)
            rgb = eye.render(seq.motor[t], ROBOT_EYE, user_hands=hands)
            pixels, _ = camera.project(hands)
            for (col, row), name in zip(
                pixels.round().astype(int), ("user_left_ball", "user_right_ball"), strict=True
            ):
                assert seg[row, col] == eye.model.geom(name).id
            # The user's left ball is red, the right one blue, as rendered.
            (lc, lr), (rc, rr) = pixels.round().astype(int)
            assert rgb[lr, lc, 0] > 150 > rgb[lr, lc, 2]
            assert rgb[rr, rc, 2] > 150 > rgb[rr, rc, 0]


def test_renderer_rejects_unknown_cameras_and_sizes(renderer):
    with pytest.raises(ConfigError, match="unknown camera"):
        renderer.render(np.zeros(8), "ceiling")
    with pytest.raises(ConfigError, match="exceeds"):
        RobotRenderer(4000, 3000, model=load_model())


def test_write_video(tmp_path, renderer):
    import cv2

    frames = [
        renderer.render(np.array([0.1 * k, 0.3, 0, 1.5] * 2), "three_quarter") for k in range(5)
    ]
    path = write_video(tmp_path / "robot.mp4", frames)
    capture = cv2.VideoCapture(str(path))
    count = 0
    while capture.read()[0]:
        count += 1
    capture.release()
    assert count == 5
    with pytest.raises(ConfigError, match="no frames"):
        write_video(tmp_path / "empty.mp4", [])


def test_failed_video_leaves_nothing(tmp_path):
    good = np.zeros((48, 64, 3), np.uint8)
    with pytest.raises(ConfigError):
        write_video(tmp_path / "bad.mp4", [good, np.zeros((48, 64), np.uint8)])
    assert list(tmp_path.iterdir()) == []
