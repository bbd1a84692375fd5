"""End to end: a video of a user performing a learned pattern, through the colour-ball tracker,
drives the mirror system as well as the true hand positions do."""

import numpy as np
import pytest

from rnnpb.analysis import metrics
from rnnpb.demonstrator import held_scenario
from rnnpb.interaction import open_source
from rnnpb.model import MirrorSystem
from rnnpb.perception import SceneConfig, SyntheticCamera, VideoWriter
from rnnpb.robot import JOINT_LIMITS


@pytest.fixture(scope="module")
def model(set1_model):
    return set1_model


def _drive(model, observations, truth_motor):
    mirror = MirrorSystem(model)
    motor, predicted, observed, pbs = [], [], [], []
    last_prediction = np.full(4, np.nan)
    for u in observations:
        result = mirror.step(u)
        motor.append(result.motor)
        predicted.append(last_prediction)
        observed.append(u)
        pbs.append(result.pb)
        last_prediction = result.predicted_hands
    motor_errors = metrics.motor_error(np.array(motor), truth_motor, JOINT_LIMITS)
    sensory_errors = metrics.sensory_error(np.array(predicted), np.array(observed))
    return metrics.steps_to_lock(motor_errors, sensory_errors), pbs[-1]


@pytest.mark.parametrize("pattern", ["1", "3"])
def test_video_through_the_tracker_locks_on_as_fast_as_true_positions(model, tmp_path, pattern):
    scenario = held_scenario(pattern, n_steps=40, seed=9)
    video = tmp_path / f"user{pattern}.mp4"
    # A cluttered, noisy scene, one frame per network step, written as an mp4 video.
    scene = SceneConfig(seed=4, occlusion_probability=0.0)
    writer = VideoWriter(video, fps=2.5)
    with SyntheticCamera(scenario.hands, scene=scene) as camera:
        while (frame := camera.read()) is not None:
            writer.write(frame)
    writer.close()

    observed = []
    with open_source(f"video:{video}", frame_step=1) as source:
        while (observation := source.read()) is not None:
            observed.append(observation.sensory)
    observed = np.array(observed)
    assert observed.shape == (40, 4)
    # The tracker measures what the demonstrator's camera model says the robot sees (to a few
    # pixels after the lossy mp4 round trip; 0.01 is 6 pixels across the image).
    assert np.mean(np.abs(observed - scenario.sensory)) < 0.005
    assert np.max(np.abs(observed - scenario.sensory)) < 0.03

    true_lock, true_pb = _drive(model, scenario.sensory, scenario.motor)
    video_lock, video_pb = _drive(model, observed, scenario.motor)
    assert true_lock is not None and video_lock is not None
    assert abs(video_lock - true_lock) <= 2, (video_lock, true_lock)
    assert model.nearest_pattern(video_pb)[0] == pattern
    assert model.nearest_pattern(true_pb)[0] == pattern
