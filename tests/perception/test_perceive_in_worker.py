"""A camera source that perceives in a worker thread (``TrackedUserSource(in_worker=True)``):
without a deadline it gives the direct call's observations; with one, a frame whose perception
is late is not waited for, the latest observation comes again marked ``reused``, and the late
frame's hands are used by a later read unless that read's own frame is ready in time."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

from rnnpb.errors import RnnpbError
from rnnpb.perception import (
    TRACKED,
    ArraySource,
    BallMeasurement,
    FrameSource,
    PerceivedObservation,
    TrackedUserSource,
    TrackingResult,
    open_camera_source,
)


def numbered_frames(n: int) -> ArraySource:
    """Tiny frames whose pixels hold their index, so that a fake tracker can tell them apart."""
    return ArraySource(np.arange(n, dtype=np.uint8).repeat(4 * 4 * 3).reshape(n, 4, 4, 3))


class NumberTracker:
    """Sees frame ``k``'s left hand at ``lhy = k / 100``; the frames in ``held`` wait until the
    test releases them, and say when they are done."""

    def __init__(self, held: tuple[int, ...] = ()) -> None:
        self.release = {k: threading.Event() for k in held}
        self.finished = {k: threading.Event() for k in held}
        self.tracked: list[int] = []

    def reset(self) -> None:
        self.tracked.clear()

    def track(self, frame: np.ndarray) -> TrackingResult:
        k = int(frame[0, 0, 0])
        if k in self.release:
            assert self.release[k].wait(10), f"frame {k} was never released"
        self.tracked.append(k)
        seen = BallMeasurement(TRACKED, np.zeros(2))
        result = TrackingResult((seen, seen), np.array([k / 100, 0.5, 0.5, 0.5]))
        if k in self.finished:
            self.finished[k].set()
        return result


def frame_numbers(observations) -> list[int]:
    return [round(o.sensory[0] * 100) for o in observations]


SOON = 0.05  # seconds: a deadline a held frame misses
AMPLE = 5.0  # seconds: a deadline any frame that is not held meets


def read_by(source: TrackedUserSource, seconds: float):
    source.perceive_by(time.perf_counter() + seconds)
    return source.read()


def test_without_a_deadline_the_worker_gives_the_direct_calls_observations():
    kinds = {}
    for in_worker in (False, True):
        source = open_camera_source("synthetic", "2", steps=12, seed=3, in_worker=in_worker)
        with source:
            observations = list(iter(source.read, None))
        kinds[in_worker] = (observations, source.lost_frames.tolist(), source.n_frames)
    (direct, direct_lost, direct_n), (worker, worker_lost, worker_n) = kinds[False], kinds[True]
    assert len(worker) == len(direct) == worker_n == direct_n == 12
    for a, b in zip(direct, worker, strict=True):
        np.testing.assert_array_equal(a.sensory, b.sensory)
        np.testing.assert_array_equal(a.frame, b.frame)
        assert a.truth.keys() == b.truth.keys()
        for key in a.truth:
            np.testing.assert_array_equal(a.truth[key], b.truth[key])
        assert isinstance(b, PerceivedObservation) and not b.reused
    assert worker_lost == direct_lost


def test_a_late_frame_is_not_waited_for_and_its_hands_come_at_a_later_read():
    tracker = NumberTracker(held=(3, 6, 7))
    with TrackedUserSource(numbered_frames(10), tracker, in_worker=True) as source:
        got = [read_by(source, AMPLE) for _ in range(3)]  # frames 0, 1, 2
        start = time.perf_counter()
        got.append(read_by(source, SOON))  # frame 3 held: frame 2 again
        assert time.perf_counter() - start < 1.0  # the deadline, not the frame
        got.append(read_by(source, SOON))  # frame 3 still held: frame 2 again, no new frame read
        tracker.release[3].set()
        assert tracker.finished[3].wait(5)
        # Frame 3 is done, but frame 4, read now, is ready in time: the newer hands win.
        got.append(read_by(source, AMPLE))
        got.append(read_by(source, AMPLE))  # frame 5
        got.append(read_by(source, SOON))  # frame 6 held: frame 5 again
        tracker.release[6].set()
        assert tracker.finished[6].wait(5)
        # Frame 7 is held too: the late frame 6 is what this read has, new if not fresh.
        got.append(read_by(source, SOON))
        tracker.release[7].set()
        got.extend(iter(lambda: read_by(source, AMPLE), None))
    assert frame_numbers(got) == [0, 1, 2, 2, 2, 4, 5, 5, 6, 7, 8, 9]
    assert [o.reused for o in got] == [False] * 3 + [True, True] + [False] * 2 + [True] + [
        False
    ] * 4
    assert tracker.tracked == list(range(10))  # every frame perceived, in order
    assert source.reused_reads == 3 and source.late_frames == 3 and source.n_frames == 10
    # A reused observation is the latest one again: its frame too, not a newer one.
    assert int(got[3].frame[0, 0, 0]) == 2


def test_before_any_frame_is_perceived_a_late_read_sees_no_hands():
    tracker = NumberTracker(held=(0,))
    with TrackedUserSource(numbered_frames(3), tracker, in_worker=True) as source:
        first = read_by(source, SOON)
        tracker.release[0].set()
        assert tracker.finished[0].wait(5)
        rest = list(iter(lambda: read_by(source, AMPLE), None))
    assert first.reused and first.frame is None and np.isnan(first.sensory).all()
    assert not first.seen.any()
    # Frame 0 came after its deadline; frame 1, read at the next read, came in time.
    assert frame_numbers(rest) == [1, 2]


class BrokenCamera(FrameSource):
    description = "broken camera"

    def read(self):
        self.frame_index += 1
        if self.frame_index == 2:
            raise RnnpbError("broken camera: the camera stopped delivering frames")
        return np.full((4, 4, 3), self.frame_index, dtype=np.uint8)


def test_a_camera_error_in_the_worker_is_raised_by_the_read():
    with TrackedUserSource(BrokenCamera(), NumberTracker(), in_worker=True) as source:
        assert frame_numbers([source.read(), source.read()]) == [0, 1]
        with pytest.raises(RnnpbError, match="stopped delivering frames"):
            source.read()


def test_closing_waits_for_the_frame_in_perception():
    tracker = NumberTracker(held=(1,))
    frames = numbered_frames(4)
    closed = []
    frames.close = lambda: closed.append(len(tracker.tracked))  # type: ignore[method-assign]
    source = TrackedUserSource(frames, tracker, in_worker=True)
    with source:
        read_by(source, AMPLE)
        assert read_by(source, SOON).reused
        threading.Timer(0.2, tracker.release[1].set).start()
    # The camera was closed only after frame 1's perception ended.
    assert closed == [2]
    with pytest.raises(RnnpbError, match="before connect"):
        source.read()


@pytest.mark.parametrize("in_worker", [False, True])
def test_a_video_sampled_every_nth_frame_tracks_only_the_frames_kept(in_worker):
    """Every third frame kept (a 30 frames/s video at dt 0.1): the frames between are read
    and dropped untracked, so the tracker's time goes to the kept frames alone."""
    from rnnpb.sources import FrameStepSource

    tracker = NumberTracker()
    source = FrameStepSource(
        TrackedUserSource(numbered_frames(10), tracker, in_worker=in_worker), 3
    )
    with source:
        observations = []
        while (observation := source.read()) is not None:
            observations.append(observation)
    assert frame_numbers(observations) == [0, 3, 6, 9]
    assert tracker.tracked == [0, 3, 6, 9]
