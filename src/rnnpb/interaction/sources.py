"""Open a user source from a short specification string (the ``--source`` option).

=========================  ================================================================
``scenario:held:P``        the synthetic demonstrator keeps performing pattern ``P``
``scenario:pause:P``       pattern ``P`` with a 5-step pause in the middle (paper 3.1)
``scenario:switch:A,B,…``  the patterns one after another, 50 steps each (paper 3.2)
``scenario:novel:SET``     the pattern learning set ``SET`` left out (paper 3.3)
``csv:FILE``               a sensory stream file (``step lhy lhz rhy rhz``; empty = not seen)
``video:FILE``             a video, through the colour-ball tracker
``images:DIR``             a folder of images, through the tracker
``webcam:INDEX``           a webcam, through the tracker
``synthetic:P``            a rendered synthetic camera of pattern ``P``, through the tracker
=========================  ================================================================

Camera sources deliver one observation per frame; a video or image folder recorded faster
than the network's step is sampled every ``frame_step``-th frame (for a video, by default the
frame nearest to each ``dt``).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from rnnpb.errors import ConfigError, RnnpbError
from rnnpb.interaction.source import Observation, UserSource
from rnnpb.sequences import read_sensory_stream

SCENARIO_KINDS = ("held", "pause", "switch", "novel")


class ArraySensorySource(UserSource):
    """A sensory stream held in memory (or read from CSV), one row per step."""

    def __init__(self, sensory: np.ndarray, truth: list[dict[str, Any]] | None = None,
                 name: str = "stream") -> None:
        sensory = np.asarray(sensory, dtype=np.float64)
        if sensory.ndim != 2 or sensory.shape[1] != 4:
            raise ConfigError(f"{name}: sensory stream must have shape (n_steps, 4), got "
                              f"{sensory.shape}")
        self.sensory = sensory
        self.truth = truth
        self.name = name
        self.position = 0

    def connect(self) -> None:
        self.position = 0

    def read(self) -> Observation | None:
        if self.position >= len(self.sensory):
            return None
        truth = self.truth[self.position] if self.truth else {}
        observation = Observation(self.sensory[self.position], truth=truth)
        self.position += 1
        return observation


class CsvSensorySource(ArraySensorySource):
    def __init__(self, path: str) -> None:
        super().__init__(read_sensory_stream(path), name=path)


class FrameStepSource(UserSource):
    """Keeps every ``frame_step``-th observation of a camera source (the others are read and
    dropped), so that a video recorded at camera rate drives the network at its own step."""

    def __init__(self, inner: UserSource, frame_step: int) -> None:
        if frame_step < 1:
            raise ConfigError(f"frame step must be >= 1, got {frame_step}")
        self.inner = inner
        self.frame_step = frame_step

    def connect(self) -> None:
        self.inner.connect()

    def read(self) -> Observation | None:
        observation = self.inner.read()
        for _ in range(self.frame_step - 1):
            if self.inner.read() is None:
                break
        return observation

    def close(self) -> None:
        self.inner.close()


def parse_scenario(spec: str, seed: int = 0):
    """``held:1`` → the demonstrator's :class:`Scenario` (see the module doc)."""
    from rnnpb import demonstrator

    kind, _, argument = spec.partition(":")
    if kind not in SCENARIO_KINDS:
        raise ConfigError(f"unknown scenario {kind!r}: use one of "
                          f"{', '.join(k + ':…' for k in SCENARIO_KINDS)}")
    if not argument:
        raise ConfigError(f"scenario {kind!r} needs an argument, e.g. scenario:{kind}:1")
    try:
        if kind == "held":
            return demonstrator.held_scenario(argument, seed=seed)
        if kind == "pause":
            return demonstrator.pause_scenario(argument, seed=seed)
        if kind == "switch":
            return demonstrator.switch_scenario(tuple(argument.split(",")), seed=seed)
        return demonstrator.novel_scenario(argument, seed=seed)
    except (KeyError, ValueError) as error:
        if isinstance(error, RnnpbError):
            raise
        raise ConfigError(f"scenario {spec!r}: {error}") from None


def open_source(spec: str, *, seed: int = 0, dt: float = 0.4, frame_step: int | None = None,
                colors: str | None = None, steps: int | None = None) -> UserSource:
    """Open the user source a specification string names (see the module doc)."""
    scheme, sep, rest = spec.partition(":")
    if not sep or not rest:
        raise ConfigError(f"source {spec!r}: expected KIND:ARGUMENT, e.g. scenario:held:1, "
                          "csv:FILE, video:FILE, webcam:0")
    if scheme == "scenario":
        from rnnpb.demonstrator import ScenarioSource

        return ScenarioSource(parse_scenario(rest, seed))
    if scheme == "csv":
        return CsvSensorySource(rest)
    if scheme in ("video", "images", "webcam", "synthetic"):
        from rnnpb.perception import open_camera_source

        source = open_camera_source(spec, colors=colors, steps=steps, seed=seed)
        if frame_step is None and scheme == "video":
            frame_step = _video_frame_step(rest, dt)
        if frame_step and frame_step > 1:
            return FrameStepSource(source, frame_step)
        return source
    raise ConfigError(f"source {spec!r}: unknown kind {scheme!r} (scenario, csv, video, "
                      "images, webcam, synthetic)")


def _video_frame_step(path: str, dt: float) -> int:
    import cv2

    capture = cv2.VideoCapture(path)
    try:
        fps = capture.get(cv2.CAP_PROP_FPS) if capture.isOpened() else 0.0
    finally:
        capture.release()
    if not fps or not math.isfinite(fps) or fps <= 0:
        return 1
    return max(1, round(fps * dt))
