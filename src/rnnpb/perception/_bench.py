"""Tracking speed and accuracy on rendered frames, for ``benchmarks/bench_tracking.py`` and
``rnnpb bench``."""

from __future__ import annotations

import time

import cv2
import numpy as np

from rnnpb.perception._synthetic import SceneConfig, SyntheticCamera, oscillating_hands
from rnnpb.perception._tracker import BallTracker


def center_errors(scene: SceneConfig, n_frames: int) -> dict[str, float]:
    """Track ``n_frames`` rendered frames; centre errors (px) where a ball is fully visible.

    Also counts identity swaps: a ball reported closer to the other ball's true centre.
    """
    camera = SyntheticCamera(oscillating_hands(n_frames, seed=scene.seed), scene=scene)
    tracker = BallTracker()
    errors, lost, swapped = [], 0, 0
    with camera:
        for frame in camera:
            result = tracker.track(frame)
            truth = camera.last_truth
            for i, ball in enumerate(result.balls):
                if truth["visible_fraction"][i] < 1.0:
                    continue
                if not ball.tracked:
                    lost += 1
                    continue
                d = np.linalg.norm(truth["center_px"] - ball.center_px, axis=1)
                errors.append(d[i])
                swapped += int(d[1 - i] < d[i])
    errors_arr = np.asarray(errors)
    return {"mean_px": float(errors_arr.mean()), "p95_px": float(np.percentile(errors_arr, 95)),
            "max_px": float(errors_arr.max()), "lost_visible": lost, "swapped": swapped,
            "n": len(errors)}


def tracking_benchmark(n_frames: int = 300, warmup: int = 20, seed: int = 0) -> dict[str, float]:
    """Tracking speed at 640x480 on one core (``cv2.setNumThreads(1)``) and centre accuracy.

    Renders ``n_frames`` distinct cluttered, noisy frames first (not timed), then times
    ``tracker.track`` on each after ``warmup`` untimed calls.

    Returns
    -------
    dict
        ``frames``, ``median_ms``, ``p90_ms``, ``fps`` (from the median), and the mean centre
        error on clean frames (``clean_error_px``) and on noisy, blurred, cluttered frames
        (``noisy_error_px``), with identity swaps (``swapped``).
    """
    if n_frames < 1:
        raise ValueError("n_frames must be >= 1")
    scene = SceneConfig(seed=seed, occlusion_probability=0.0)
    camera = SyntheticCamera(oscillating_hands(n_frames, seed=seed), scene=scene)
    with camera:
        frames = list(camera)
    threads = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        tracker = BallTracker()
        for i in range(warmup):
            tracker.track(frames[i % len(frames)])
        tracker.reset()
        times = np.empty(len(frames))
        for i, frame in enumerate(frames):
            start = time.perf_counter()
            tracker.track(frame)
            times[i] = time.perf_counter() - start
    finally:
        cv2.setNumThreads(threads)
    median = float(np.median(times))
    n_accuracy = min(n_frames, 200)
    clean = center_errors(SceneConfig.clean(seed=seed), n_accuracy)
    noisy = center_errors(SceneConfig.hard(seed=seed, occlusion_probability=0.0), n_accuracy)
    return {
        "frames": len(frames),
        "width": frames[0].shape[1],
        "height": frames[0].shape[0],
        "median_ms": median * 1e3,
        "p90_ms": float(np.percentile(times, 90)) * 1e3,
        "fps": 1.0 / median,
        "clean_error_px": clean["mean_px"],
        "noisy_error_px": noisy["mean_px"],
        "noisy_p95_px": noisy["p95_px"],
        "swapped": clean["swapped"] + noisy["swapped"],
    }
