"""Tracking speed and accuracy on rendered frames, for ``benchmarks/bench_tracking.py`` and
``rnnpb bench``."""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.perception._synthetic import SceneConfig, SyntheticCamera, oscillating_hands
from rnnpb.perception._tracker import BallTracker, TrackerConfig


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
    return {
        "mean_px": float(errors_arr.mean()),
        "p95_px": float(np.percentile(errors_arr, 95)),
        "max_px": float(errors_arr.max()),
        "lost_visible": lost,
        "swapped": swapped,
        "n": len(errors),
    }


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


HARD_SCENE_KINDS: dict[str, dict[str, Any]] = {
    # Each on top of SceneConfig.hard (heavy clutter, noise, lighting change, frequent blur).
    "static": {"static_distractors": 4, "occlusion_probability": 0.0},
    "moving": {"moving_distractors": 4, "occlusion_probability": 0.0},
    "flicker": {
        "flicker": 0.25,
        "blur_probability": 0.7,
        "blur_px": 15.0,
        "static_distractors": 2,
        "occlusion_probability": 0.0,
    },
    "occlusion": {
        "static_distractors": 2,
        "moving_distractors": 2,
        "occlusion_probability": 0.03,
        "occlusion_frames": (3, 12),
    },
    "all": {
        "static_distractors": 4,
        "moving_distractors": 4,
        "flicker": 0.2,
        "occlusion_probability": 0.02,
        "occlusion_frames": (3, 12),
    },
}
"""The kinds of hard scene: the changes to :meth:`SceneConfig.hard` each makes."""


def hard_scene(kind: str, seed: int, n_frames: int = 150) -> SyntheticCamera:
    """A hard scene of ``kind`` (a key of :data:`HARD_SCENE_KINDS`): the synthetic user
    performing pattern ``seed % 4 + 1`` in a room with look-alikes of the balls."""
    if kind not in HARD_SCENE_KINDS:
        raise ConfigError(f"no hard scene kind {kind!r} ({', '.join(HARD_SCENE_KINDS)})")
    from rnnpb.perception._user_source import synthetic_user_hands

    pattern = str(seed % 4 + 1)
    hands = synthetic_user_hands(pattern, n_frames, seed)
    scene = SceneConfig.hard(seed=seed, **HARD_SCENE_KINDS[kind])
    return SyntheticCamera(hands, scene=scene, truth={"pattern": pattern, "kind": kind})


@dataclass(frozen=True)
class SceneScore:
    """How the tracker did on one scene, both balls together.

    Attributes
    ----------
    kind : str
    seed : int
    visible : int
        Ball-frames where the ball is fully visible.
    tracked : int
        Of those, the ones where the tracker reported the ball.
    mean_error_px : float
        Mean centre error over the tracked visible ball-frames (NaN if none).
    wrong : int
        Tracked visible ball-frames more than ``wrong_px`` from the true centre.
    false_reports : int
        Ball-frames where the ball is fully hidden and the tracker still reported it.
    """

    kind: str
    seed: int
    visible: int
    tracked: int
    mean_error_px: float
    wrong: int
    false_reports: int

    @property
    def tracked_fraction(self) -> float:
        return self.tracked / self.visible if self.visible else math.nan


def score_scene(
    camera: SyntheticCamera, tracker: BallTracker | None = None, wrong_px: float = 10.0
) -> SceneScore:
    """Track every frame of a synthetic camera without calibration and score it."""
    tracker = tracker or BallTracker()
    errors, visible, hidden_reports = [], 0, 0
    wrong = 0
    with camera:
        for frame in camera:
            result = tracker.track(frame)
            truth = camera.last_truth
            for i, ball in enumerate(result.balls):
                fraction = truth["visible_fraction"][i]
                if fraction <= 0.0:
                    hidden_reports += int(ball.tracked)
                if fraction < 1.0:
                    continue
                visible += 1
                if ball.tracked:
                    d = float(np.linalg.norm(ball.center_px - truth["center_px"][i]))
                    errors.append(d)
                    wrong += int(d > wrong_px)
    extra = camera.extra_truth
    return SceneScore(
        str(extra.get("kind", "")),
        camera.scene.seed,
        visible,
        len(errors),
        float(np.mean(errors)) if errors else math.nan,
        wrong,
        hidden_reports,
    )


def clutter_benchmark(
    seeds: Sequence[int],
    kinds: Sequence[str] | None = None,
    n_frames: int = 150,
    config: TrackerConfig | None = None,
) -> list[SceneScore]:
    """Score the tracker (no calibration) on the hard scenes of ``kinds`` × ``seeds``."""
    kinds = list(kinds or HARD_SCENE_KINDS)
    return [
        score_scene(hard_scene(kind, seed, n_frames), BallTracker(config))
        for kind in kinds
        for seed in seeds
    ]
