"""Perception: camera sources (webcam, video file, image folder, synthetic render) and the
colour-ball tracker that turns the user's hands into the sensory vector ``lhy lhz rhy rhz``.

Open a camera with the tracker from its kind and argument (``"webcam", 0``, ``"video",
"clip.mp4"``, ``"images", "frames/"``, ``"synthetic", "1"``) with :func:`open_camera_source`; it
is a :class:`rnnpb.sources.UserSource` yielding one observation per frame. Spec strings such as
``webcam:0`` are parsed by :func:`rnnpb.interaction.parse_source_spec`, the one grammar.
"""

from rnnpb.perception._bench import (
    HARD_SCENE_KINDS,
    SceneScore,
    center_errors,
    clutter_benchmark,
    hard_scene,
    score_scene,
    tracking_benchmark,
)
from rnnpb.perception._calibrate import (
    BROAD_BLUE,
    BROAD_RED,
    BallCalibration,
    calibrate_automatically,
    calibrate_from_pixel,
    calibration_preview,
    fit_color,
    locate_ball,
)
from rnnpb.perception._colors import (
    BLUE,
    RED,
    BallColor,
    BallColors,
    ball_colors_from_json,
    load_ball_colors,
    save_ball_colors,
)
from rnnpb.perception._depth import (
    MOUSE_PLANE_X,
    DepthConfig,
    depth_from_size,
    fill_gaps,
    hands_from_balls,
    hands_on_plane,
    running_median,
)
from rnnpb.perception._sources import (
    ArraySource,
    FrameSource,
    ImageFolderSource,
    LimitedSource,
    VideoFileSource,
    VideoWriter,
    WebcamSource,
    call_with_timeout,
)
from rnnpb.perception._synthetic import SceneConfig, SyntheticCamera, oscillating_hands
from rnnpb.perception._tracker import (
    LOST,
    TRACKED,
    BallMeasurement,
    BallTracker,
    TrackerConfig,
    TrackingResult,
    draw_tracking,
    split_disk,
)
from rnnpb.perception._user_source import (
    TrackedUserSource,
    open_camera_source,
    open_frame_source,
    synthetic_user_hands,
)

__all__ = [
    "BLUE",
    "MOUSE_PLANE_X",
    "BROAD_BLUE",
    "BROAD_RED",
    "HARD_SCENE_KINDS",
    "LOST",
    "RED",
    "TRACKED",
    "ArraySource",
    "BallCalibration",
    "BallColor",
    "BallColors",
    "BallMeasurement",
    "DepthConfig",
    "BallTracker",
    "FrameSource",
    "ImageFolderSource",
    "LimitedSource",
    "SceneConfig",
    "SceneScore",
    "SyntheticCamera",
    "TrackedUserSource",
    "TrackerConfig",
    "TrackingResult",
    "VideoFileSource",
    "VideoWriter",
    "WebcamSource",
    "ball_colors_from_json",
    "calibrate_automatically",
    "calibrate_from_pixel",
    "calibration_preview",
    "call_with_timeout",
    "center_errors",
    "clutter_benchmark",
    "depth_from_size",
    "draw_tracking",
    "fill_gaps",
    "fit_color",
    "hands_from_balls",
    "hands_on_plane",
    "hard_scene",
    "load_ball_colors",
    "locate_ball",
    "oscillating_hands",
    "open_camera_source",
    "open_frame_source",
    "running_median",
    "save_ball_colors",
    "score_scene",
    "split_disk",
    "synthetic_user_hands",
    "tracking_benchmark",
]
