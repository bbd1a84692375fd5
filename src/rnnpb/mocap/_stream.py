"""Several BVH takes as one stream of hands, one row per network step.

The takes are played in order, each overlapping the next by a short cross-fade (the hands
blend linearly from one take into the next, so a join is no jump). ``time_scale`` stretches
the recording's time: 2 plays it at half speed, 0.5 at double. The stream is then averaged
over each step (a box filter one step wide: the anti-aliasing) and sampled every ``dt``.

A movement faster than the step cannot be learned from its samples: with fewer than
:data:`MIN_STEPS_PER_PERIOD` steps per period it aliases. The period of a take is ``1 / f``,
``f`` the frequency below which :data:`PERIOD_POWER_SHARE` of the power of the hands'
movement lies (mean removed; for a single gesture, its duration) — an estimate that errs on
the safe, short side by at most one cycle per take length. The shortest period over the takes
is checked, and a movement too fast is refused with the time scale and the ``dt`` that would
work — never undersampled. (``rnnpb record`` does not refuse: its learning phase,
:mod:`rnnpb.learning_phase`, plays such a movement slower by the least factor that gives it
four steps a cycle, and says so.)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rnnpb.demonstrator import UserBody
from rnnpb.errors import ConfigError

from ._body import BodyScale, body_hands
from ._bvh import read_bvh

MIN_STEPS_PER_PERIOD = 4
"""Fewest steps per period of the movement (below it the sampled movement aliases)."""
PERIOD_POWER_SHARE = 0.9
"""Share of the movement's power below the frequency that sets its period."""
CROSSFADE_S = 0.5
"""Seconds (of the recording) over which one take blends into the next."""


@dataclass(frozen=True)
class Take:
    """One BVH file of a stream: what was read and measured."""

    path: str
    frames: int
    frame_time: float
    duration: float
    period: float
    body: BodyScale

    def to_json(self) -> dict:
        return {
            "path": self.path,
            "frames": self.frames,
            "frame_time": self.frame_time,
            "duration_s": round(self.duration, 4),
            "period_s": round(self.period, 4),
            "body": self.body.to_json(),
        }


@dataclass(frozen=True)
class CaptureStream:
    """Hands of one or more takes, resampled to the step.

    Attributes
    ----------
    hands : array, shape (n_steps, 2, 3)
        Left, right hand on the standard user's body, robot frame, metres.
    dt : float
        Seconds per step.
    time_scale : float
        How much slower than recorded the movement is played.
    takes : tuple of Take
    crossfade : float
        Seconds of the recording each join blends over.
    """

    hands: np.ndarray
    dt: float
    time_scale: float
    takes: tuple[Take, ...] = field(default_factory=tuple)
    crossfade: float = CROSSFADE_S

    @property
    def period(self) -> float:
        """The shortest period over the takes, seconds as played."""
        return min(t.period for t in self.takes) * self.time_scale

    def to_json(self) -> dict:
        return {
            "dt": self.dt,
            "time_scale": self.time_scale,
            "crossfade_s": self.crossfade,
            "steps": int(len(self.hands)),
            "shortest_period_s": round(self.period, 4),
            "steps_per_period": round(self.period / self.dt, 2),
            "takes": [t.to_json() for t in self.takes],
        }


def movement_period(hands: np.ndarray, frame_time: float) -> float:
    """Seconds per cycle of the fastest part that matters of a movement (see the module doc).

    ``hands`` shape (n_frames, 2, 3); a still take has an infinite period.
    """
    x = np.asarray(hands, dtype=np.float64).reshape(len(hands), -1)
    x = x - x.mean(axis=0)
    if len(x) < 4 or not np.any(x):
        return math.inf
    spectrum = np.fft.rfft(x * np.hanning(len(x))[:, None], axis=0)
    power = (np.abs(spectrum) ** 2).sum(axis=1)
    power[0] = 0.0
    if power.sum() <= 0:
        return math.inf
    frequencies = np.fft.rfftfreq(len(x), frame_time)
    cumulative = np.cumsum(power) / power.sum()
    f = frequencies[min(int(np.searchsorted(cumulative, PERIOD_POWER_SHARE)), len(power) - 1)]
    # The lowest resolvable frequency of a take is one cycle over its whole duration.
    return float(1.0 / max(f, 1.0 / (frame_time * len(x))))


def check_sampling(period: float, dt: float, time_scale: float, what: str) -> None:
    """Refuse a movement with fewer than :data:`MIN_STEPS_PER_PERIOD` steps per period.

    ``period`` in seconds of the recording; the message says which time scale and which
    ``dt`` would work.
    """
    played = period * time_scale
    if played >= MIN_STEPS_PER_PERIOD * dt:
        return
    scale = math.ceil(MIN_STEPS_PER_PERIOD * dt / period * 100) / 100
    step = math.floor(played / MIN_STEPS_PER_PERIOD * 1000) / 1000
    raise ConfigError(
        f"{what}: the movement repeats every {period:.2f} s, so at --time-scale "
        f"{time_scale:g} a cycle is {played / dt:.1f} steps of {dt:g} s, fewer than "
        f"{MIN_STEPS_PER_PERIOD} (it would alias); use --time-scale {scale:g} or more, "
        f"or record and learn at --dt {step:g} or less"
    )


@dataclass(frozen=True)
class Capture:
    """BVH takes joined into one recording on its finest frame grid, not resampled.

    Attributes
    ----------
    times : array, shape (n,)
        Seconds of the recording.
    hands : array, shape (n, 2, 3)
        Left, right hand on the standard user's body (at 1 m), robot frame, metres.
    takes : tuple of Take
    crossfade : float
        Seconds each join blends over.
    """

    times: np.ndarray
    hands: np.ndarray
    takes: tuple[Take, ...]
    crossfade: float

    @property
    def period(self) -> float:
        """The shortest period over the takes, seconds of the recording."""
        return min(t.period for t in self.takes)

    def to_json(self) -> dict:
        return {
            "crossfade_s": self.crossfade,
            "duration_s": round(float(self.times[-1]), 4),
            "shortest_period_s": round(self.period, 4),
            "takes": [t.to_json() for t in self.takes],
        }


def capture_takes(
    paths: list[str] | tuple[str, ...],
    *,
    crossfade: float = CROSSFADE_S,
    hands: tuple[str, str] | None = None,
    units: str | None = None,
    up_axis: str | None = None,
    body: UserBody | None = None,
) -> Capture:
    """Read the BVH files, put their hands on the standard body and join them (module doc),
    at the finest frame time of the takes."""
    if not paths:
        raise ConfigError("no BVH file given")
    if not (math.isfinite(crossfade) and crossfade >= 0):
        raise ConfigError(f"the cross-fade must be >= 0 s, got {crossfade}")
    takes: list[Take] = []
    motions: list[np.ndarray] = []
    for path in paths:
        bvh = read_bvh(path)
        if bvh.n_frames < 2:
            raise ConfigError(f"{path}: one frame is no movement")
        take_hands, scale = body_hands(bvh, hands=hands, units=units, up_axis=up_axis, body=body)
        period = movement_period(take_hands, bvh.frame_time)
        takes.append(Take(str(path), bvh.n_frames, bvh.frame_time, bvh.duration, period, scale))
        motions.append(take_hands)
    joined, fine, crossfade = _joined(motions, takes, crossfade)
    return Capture(np.arange(len(joined)) * fine, joined, tuple(takes), crossfade)


def capture_stream(
    paths: list[str] | tuple[str, ...],
    *,
    dt: float,
    time_scale: float = 1.0,
    crossfade: float = CROSSFADE_S,
    hands: tuple[str, str] | None = None,
    units: str | None = None,
    up_axis: str | None = None,
    body: UserBody | None = None,
) -> CaptureStream:
    """Read the BVH files, put their hands on the standard body, join
    (:func:`capture_takes`) and resample them."""
    if not paths:
        raise ConfigError("no BVH file given")
    if not (math.isfinite(dt) and dt > 0):
        raise ConfigError(f"dt must be a positive number of seconds, got {dt}")
    if not (math.isfinite(time_scale) and 0.01 <= time_scale <= 100):
        raise ConfigError(f"--time-scale must be from 0.01 to 100, got {time_scale}")
    capture = capture_takes(
        paths, crossfade=crossfade, hands=hands, units=units, up_axis=up_axis, body=body
    )
    takes = capture.takes
    shortest = min(takes, key=lambda t: t.period)
    what = Path(shortest.path).name if len(takes) > 1 else shortest.path
    check_sampling(shortest.period, dt, time_scale, what)
    joined, crossfade = capture.hands, capture.crossfade
    fine = min(t.frame_time for t in takes)
    recorded_step = dt / time_scale
    # An odd width keeps the average centred on its step.
    half = max(0, round((recorded_step / fine - 1) / 2))
    width = 2 * half + 1
    kernel = np.ones(width) / width
    padded = np.concatenate(
        [np.repeat(joined[:1], half, 0), joined, np.repeat(joined[-1:], half, 0)]
    )
    flat = padded.reshape(len(padded), -1)
    smoothed = np.stack(
        [np.convolve(flat[:, k], kernel, mode="valid") for k in range(flat.shape[1])], axis=1
    )
    fine_times = np.arange(len(joined)) * fine
    times = np.arange(int(math.floor(fine_times[-1] / recorded_step + 1e-4)) + 1) * recorded_step
    steps = np.stack(
        [np.interp(times, fine_times, smoothed[:, k]) for k in range(flat.shape[1])], axis=1
    )
    return CaptureStream(steps.reshape(len(times), 2, 3), dt, time_scale, takes, crossfade)


def _joined(
    motions: list[np.ndarray], takes: list[Take], crossfade: float
) -> tuple[np.ndarray, float, float]:
    """The takes one after another on one grid (the finest frame time), each join a linear
    cross-fade (at most half the shorter take); returns (hands (n, 2, 3), seconds per row,
    the cross-fade used)."""
    fine = min(t.frame_time for t in takes)
    if len(takes) > 1:
        crossfade = min(crossfade, *(t.duration / 2 for t in takes))
    else:
        crossfade = 0.0
    starts = [0.0]
    for take in takes[:-1]:
        starts.append(starts[-1] + take.duration - crossfade)
    total = starts[-1] + takes[-1].duration
    times = np.arange(int(math.floor(total / fine + 1e-4)) + 1) * fine
    blended = np.zeros((len(times), 6))
    weights = np.zeros(len(times))
    for i, (motion, take, start) in enumerate(zip(motions, takes, starts, strict=True)):
        local = times - start
        inside = (local >= -fine / 2) & (local <= take.duration + fine / 2)
        weight = inside.astype(np.float64)
        if crossfade > 0:
            if i > 0:
                weight = weight * np.clip(local / crossfade, 0.0, 1.0)
            if i < len(takes) - 1:
                weight = weight * np.clip((take.duration - local) / crossfade, 0.0, 1.0)
        frame_times = np.arange(take.frames) * take.frame_time
        flat = motion.reshape(len(motion), 6)
        values = np.stack([np.interp(local, frame_times, flat[:, k]) for k in range(6)], axis=1)
        blended += weight[:, None] * values
        weights += weight
    assert np.all(weights > 0), "every time of the stream lies in a take"
    return (blended / weights[:, None]).reshape(len(times), 2, 3), fine, crossfade
