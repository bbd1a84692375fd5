"""``rnnpb track`` and ``rnnpb calibrate`` through the command line entry point."""

from __future__ import annotations

import json

import cv2
import numpy as np

from rnnpb.cli import main
from rnnpb.perception import (
    BallTracker,
    SceneConfig,
    SyntheticCamera,
    TrackerConfig,
    VideoWriter,
    load_ball_colors,
    oscillating_hands,
    tracking_benchmark,
)
from rnnpb.sequences import read_sensory_stream


def test_track_synthetic_writes_a_valid_sensory_stream(tmp_path, capsys):
    out, render = tmp_path / "stream.csv", tmp_path / "marked.avi"
    assert (
        main(["track", "synthetic:3", "--steps", "25", "--out", str(out), "--render", str(render)])
        == 0
    )
    stream = read_sensory_stream(out)
    assert stream.shape == (25, 4)
    assert np.nanmin(stream) > 0.0 and np.nanmax(stream) < 1.0
    # the user's left hand (red ball) appears on the robot's right: larger Y than the right hand
    assert np.nanmean(stream[:, 0]) > np.nanmean(stream[:, 2])
    printed = capsys.readouterr().out
    assert "tracked 25 frames" in printed
    left_lost = int(np.isnan(stream[:, 0]).sum())
    right_lost = int(np.isnan(stream[:, 2]).sum())
    assert (
        f"left ball (red) lost in {left_lost} of 25 frames, right ball (blue) lost in "
        f"{right_lost} of 25 frames"
    ) in printed
    capture = cv2.VideoCapture(str(render))
    n = 0
    while capture.read()[0]:
        n += 1
    capture.release()
    assert n == 25


def test_track_video_reports_lost_frames_and_writes_empty_cells(tmp_path, capsys):
    scene = SceneConfig(occlusion_probability=0.0, occlusions=((0, 5, 9),))
    video = tmp_path / "in.mp4"
    with SyntheticCamera(oscillating_hands(20), scene=scene) as camera, VideoWriter(video) as w:
        for frame in camera:
            w.write(frame)
    out = tmp_path / "out.csv"
    assert main(["track", f"video:{video}", "--out", str(out)]) == 0
    assert "left ball (red) lost in 4 of 20 frames" in capsys.readouterr().out
    rows = out.read_text().splitlines()
    assert rows[0] == "step,lhy,lhz,rhy,rhz"
    assert rows[6].startswith("5,,,0.")
    stream = read_sensory_stream(out)
    assert np.isnan(stream[5:9, :2]).all() and not np.isnan(stream[9:, :]).any()


def test_track_errors_are_one_line_and_quick(tmp_path, capsys):
    assert (
        main(["track", f"video:{tmp_path / 'missing.mp4'}", "--out", str(tmp_path / "x.csv")]) == 2
    )
    assert "no such video file" in capsys.readouterr().err
    bad = tmp_path / "colors.json"
    bad.write_text(json.dumps({"left": {"hue": [0, 300]}, "right": {"hue": [100, 120]}}))
    assert (
        main(
            [
                "track",
                "synthetic:1",
                "--steps",
                "3",
                "--colors",
                str(bad),
                "--out",
                str(tmp_path / "x.csv"),
            ]
        )
        == 2
    )
    err = capsys.readouterr().err
    assert str(bad) in err and "'left.hue'" in err
    assert not (tmp_path / "x.csv").exists()


def test_calibrate_from_pixels_and_automatically(tmp_path, capsys):
    scene = SceneConfig(
        seed=3,
        occlusion_probability=0.0,
        left_ball_bgr=(20, 140, 230),  # an orange ball on the left hand
        right_ball_bgr=(60, 200, 40),
    )  # a green one on the right
    camera = SyntheticCamera(oscillating_hands(3), scene=scene)
    frame, truth = camera.render(2)
    folder = tmp_path / "frames"
    folder.mkdir()
    for t in range(3):
        cv2.imwrite(str(folder / f"{t}.png"), camera.render(t)[0])
    (lx, ly), (rx, ry) = truth["center_px"].astype(int)
    out = tmp_path / "colors.json"
    assert (
        main(
            [
                "calibrate",
                f"images:{folder}",
                "--frame",
                "2",
                "--left-pixel",
                f"{lx},{ly}",
                "--right-pixel",
                f"{rx},{ry}",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    colors = load_ball_colors(out)
    assert (colors.left.name, colors.right.name) == ("orange", "green")
    assert (tmp_path / "colors.png").exists()
    # the fitted ranges track these balls (the tracker takes a ball once it has seen it move:
    # the scene has other green things)
    tracker = BallTracker(TrackerConfig(colors=colors))
    for t in range(3):
        result = tracker.track(camera.render(t)[0])
    assert np.linalg.norm(result.balls[0].center_px - truth["center_px"][0]) < 1.0
    assert np.linalg.norm(result.balls[1].center_px - truth["center_px"][1]) < 1.0
    assert "left ball (orange)" in capsys.readouterr().out

    # automatic: the default red and blue balls
    auto = tmp_path / "auto.json"
    assert (
        main(
            [
                "calibrate",
                "synthetic:2",
                "--frame",
                "4",
                "--out",
                str(auto),
                "--preview",
                str(tmp_path / "auto_preview.png"),
            ]
        )
        == 0
    )
    colors = load_ball_colors(auto)
    assert colors.left.wraps and 100 <= colors.right.hue[0] <= colors.right.hue[1] <= 135
    preview = cv2.imread(str(tmp_path / "auto_preview.png"))
    assert preview.shape == (480, 3 * 640, 3)


def test_calibrate_refuses_a_grey_pixel(tmp_path, capsys):
    assert (
        main(
            ["calibrate", "synthetic:1", "--left-pixel", "2,470", "--out", str(tmp_path / "c.json")]
        )
        == 2
    )
    assert "grey" in capsys.readouterr().err
    assert not (tmp_path / "c.json").exists()


def test_tracking_benchmark_reports_speed_and_accuracy():
    figures = tracking_benchmark(n_frames=20, warmup=3)
    assert figures["frames"] == 20 and (figures["width"], figures["height"]) == (640, 480)
    assert figures["fps"] > 0 and figures["median_ms"] > 0
    assert figures["clean_error_px"] < 1.0
    assert figures["noisy_error_px"] < 3.0
    assert figures["swapped"] == 0


def test_track_and_calibrate_read_their_source_with_the_one_grammar(tmp_path, capsys):
    for command in ("track", "calibrate"):
        out = str(tmp_path / f"{command}.out")
        assert main([command, "csv:stream.csv", "--out", out]) == 2
        assert "'csv:stream.csv': a csv source cannot be used here" in capsys.readouterr().err
        assert main([command, "webcam:front", "--out", out]) == 2
        assert "the webcam index must be an integer" in capsys.readouterr().err
    # The kind is case-insensitive for every command, as the grammar says.
    assert main(["track", "Synthetic:2", "--steps", "3", "--out", str(tmp_path / "s.csv")]) == 0
    assert read_sensory_stream(tmp_path / "s.csv").shape == (3, 4)
