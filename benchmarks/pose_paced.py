"""Bare hands in real time: a video of a real person paced through the interaction loop with
the pose tracker, the frame's perception in a worker thread against read directly.

Each way is the loop `rnnpb interact --perception pose --paced` runs: the shipped model with
the on-line regression that suits it, the safety guard and the command filter, the kinematic
robot and a session recording, one step every ``--dt`` seconds (the shipped model was learned
at 0.4 s; a step's work does not depend on dt). The frames are the clip's, letterboxed to
``--size`` (640x480, a webcam's) and looped as needed, decoded before the run as a camera
delivers them. The two ways run in alternate blocks of ``--block`` steps, each carrying on
where its last block ended, so that both see the same machine; ``--busy N`` adds N processes
that keep a core busy, as other people's jobs do.

Per way: missed deadlines (a step's sections over dt), each put down to the section that took
longest in it, the steps that reused an observation because the frame's perception was late,
the frames perceived late, the pose tracker's own time per frame, and each section's median,
p95, p99 and max; the load average (1 minute) before each block, for the machine's share. The
first step of each way (the network's compilation and the pose graph's first frame) is left
out of the sections' figures but not of the deadlines.

Run: ``PYTHONPATH=src .venv-hands/bin/python benchmarks/pose_paced.py [--video FILE]
[--steps 1000] [--dt 0.1] [--block 100] [--busy 0] [--json FILE]``.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import multiprocessing
import os
import platform
import tempfile
import time
from collections import Counter
from dataclasses import replace
from pathlib import Path

import numpy as np

CLIP = Path(__file__).resolve().parents[1].parent / "shared/data/video/wave_both_hands.mp4"
WAYS = ("direct", "worker")
SECTIONS = ("perceive", "mirror", "act", "record", "step")


def letterboxed(frame: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    import cv2

    width, height = size
    scale = min(width / frame.shape[1], height / frame.shape[0])
    shape = (round(frame.shape[1] * scale), round(frame.shape[0] * scale))
    resized = cv2.resize(frame, shape, interpolation=cv2.INTER_AREA)
    out = np.zeros((height, width, 3), dtype=np.uint8)
    top, left = (height - shape[1]) // 2, (width - shape[0]) // 2
    out[top : top + shape[1], left : left + shape[0]] = resized
    return out


def clip_frames(path: Path, size: tuple[int, int]) -> list[np.ndarray]:
    from rnnpb.perception import VideoFileSource

    with VideoFileSource(path) as video:
        return [letterboxed(frame, size) for frame in video]


def busy_core(stop) -> None:
    while not stop.is_set():
        sum(range(10_000))


def machine() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return f"{line.split(':', 1)[1].strip()}, {os.cpu_count()} cores"
    except OSError:
        pass
    return f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores"


def percentiles(values_ms: list[float]) -> dict[str, float]:
    array = np.asarray(values_ms)
    return {
        "median": float(np.median(array)),
        "p95": float(np.percentile(array, 95)),
        "p99": float(np.percentile(array, 99)),
        "max": float(array.max()),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--video", type=Path, default=CLIP, help=f"default {CLIP}")
    parser.add_argument("--steps", type=int, default=1000, help="steps per way (default 1000)")
    parser.add_argument("--dt", type=float, default=0.1, help="seconds per step (default 0.1)")
    parser.add_argument("--size", default="640x480", help="frame size (default 640x480)")
    parser.add_argument("--block", type=int, default=100, help="steps per block (default 100)")
    parser.add_argument("--ways", default=",".join(WAYS), help="direct,worker (default both)")
    parser.add_argument("--busy", type=int, default=0, help="processes keeping a core busy")
    parser.add_argument("--json", type=Path, help="also write the figures here")
    args = parser.parse_args()
    ways = [w for w in args.ways.split(",") if w]
    if not ways or any(w not in WAYS for w in ways):
        parser.error(f"--ways: a comma-separated list of {', '.join(WAYS)}")
    if args.steps < 2 or args.block < 1 or not args.dt > 0:
        parser.error("--steps >= 2, --block >= 1 and --dt > 0")
    width, height = (int(v) for v in args.size.split("x"))

    import rnnpb

    rnnpb.configure_xla()
    from rnnpb import _xla

    _xla.compilation_cache()
    from rnnpb.interaction import InteractionLoop, LoopConfig, SessionRecorder
    from rnnpb.model import MirrorSystem, OnlineConfig, TrainedModel
    from rnnpb.models import SHIPPED_MODEL
    from rnnpb.perception import FrameSource, PoseTracker, TrackedUserSource
    from rnnpb.robot import JOINT_LIMITS, KinematicRobot
    from rnnpb.safety import online_safety

    frames = clip_frames(args.video, (width, height))

    class LoopedClip(FrameSource):
        """The clip's frames, over and over."""

        description = f"{args.video.name} looped"

        def read(self) -> np.ndarray:
            self.frame_index += 1
            return frames[self.frame_index % len(frames)]

    class TimedPoseTracker(PoseTracker):
        """The pose tracker, keeping each frame's time (ms), wherever it runs."""

        def __init__(self) -> None:
            super().__init__()
            self.times_ms: list[float] = []

        def track(self, frame: np.ndarray):
            t0 = time.perf_counter()
            result = super().track(frame)
            self.times_ms.append((time.perf_counter() - t0) * 1e3)
            return result

    model = TrainedModel.load(SHIPPED_MODEL, joint_limits=JOINT_LIMITS)
    online = OnlineConfig.for_model(model).config
    spawn = multiprocessing.get_context("spawn")  # not forked: JAX's threads are running
    stop = spawn.Event()
    busy = [spawn.Process(target=busy_core, args=(stop,)) for _ in range(args.busy)]
    for process in busy:
        process.start()
    print(
        f"pose_paced: {args.video.name} ({len(frames)} frames) at {width}x{height}, "
        f"{args.steps} steps per way at dt {args.dt:g} s, blocks of {args.block}, "
        f"{args.busy} busy processes; {machine()}; load average {os.getloadavg()[0]:.2f}"
    )
    runs = {}
    try:
        with tempfile.TemporaryDirectory() as tmp, contextlib.ExitStack() as stack:
            for way in ways:
                safety = online_safety(SHIPPED_MODEL, model, online)
                tracker = TimedPoseTracker()
                source = stack.enter_context(
                    TrackedUserSource(LoopedClip(), tracker, in_worker=way == "worker")
                )
                robot = stack.enter_context(KinematicRobot())
                recorder = stack.enter_context(
                    SessionRecorder(Path(tmp) / f"{way}.csv", model.network.pb_size)
                )
                if safety.command_filter is not None:
                    safety.command_filter.reset(robot.read())
                loop = InteractionLoop(
                    MirrorSystem(model, safety.config, **safety.mirror_options),
                    source,
                    robot,
                    recorder,
                    LoopConfig(dt=args.dt, paced=True, max_steps=0),
                    command_filter=safety.command_filter,
                )
                runs[way] = {
                    "loop": loop,
                    "source": source,
                    "tracker": tracker,
                    "records": [],
                    "load": [],
                }
            while any(run["loop"].steps < args.steps for run in runs.values()):
                for run in runs.values():
                    loop = run["loop"]
                    if loop.steps >= args.steps:
                        continue
                    end = min(args.steps, loop.steps + args.block)
                    loop.config = replace(loop.config, max_steps=end)
                    run["load"].append(os.getloadavg()[0])
                    loop.run(on_step=run["records"].append)
                    time.sleep(3 * args.dt)  # a frame still in perception ends before the next
    finally:
        stop.set()
        for process in busy:
            process.join()
    figures: dict[str, dict] = {}
    for way, run in runs.items():
        records = run["records"][1:]
        loop, source, tracker = run["loop"], run["source"], run["tracker"]
        sections = {
            name: percentiles(
                [
                    1e3 * (sum(r.timings.values()) if name == "step" else r.timings[name])
                    for r in records
                ]
            )
            for name in SECTIONS
        }
        missed = [r for r in run["records"] if sum(r.timings.values()) > args.dt]
        causes = Counter(max(r.timings, key=lambda name: r.timings[name]) for r in missed)
        figures[way] = {
            "steps": loop.steps,
            "missed_deadlines": loop.missed_deadlines,
            "missed_by_longest_section": dict(causes),
            "missed_section_ms_median": {
                name: float(np.median([1e3 * r.timings[name] for r in missed])) if missed else 0.0
                for name in SECTIONS[:-1]
            },
            "load_average_per_block": run["load"],
            "reused_observations": loop.reused_observations,
            "late_frames": source.late_frames,
            "frames_perceived": source.n_frames,
            "pose_ms": percentiles(tracker.times_ms[1:]),
            "section_ms": sections,
        }
        pose = figures[way]["pose_ms"]
        print(
            f"{way}: {loop.steps} steps, missed deadlines {loop.missed_deadlines} ("
            + ", ".join(f"{n} {name}" for name, n in causes.most_common())
            + f" the longest), observations reused {loop.reused_observations}, frames perceived "
            f"late {source.late_frames} (of {source.n_frames}); load average per block "
            f"{min(run['load']):.1f}-{max(run['load']):.1f}"
        )
        if missed:
            print(
                "  the missed steps' sections, median ms: "
                + ", ".join(
                    f"{k} {v:.1f}" for k, v in figures[way]["missed_section_ms_median"].items()
                )
            )
        rows = {"pose tracker, per frame": pose} | {f"section {k}": v for k, v in sections.items()}
        for name, v in rows.items():
            print(
                f"  {name:<24} ms: median {v['median']:7.2f}  p95 {v['p95']:7.2f}  "
                f"p99 {v['p99']:7.2f}  max {v['max']:7.2f}"
            )
    print(f"load average at the end {os.getloadavg()[0]:.2f}")
    if args.json:
        args.json.write_text(
            json.dumps(
                {
                    "machine": machine(),
                    "video": args.video.name,
                    "size": [width, height],
                    "dt": args.dt,
                    "busy": args.busy,
                    **figures,
                },
                indent=2,
            )
        )


if __name__ == "__main__":
    main()
