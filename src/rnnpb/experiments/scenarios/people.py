"""The people study's scenarios and measures: real people through the learning phase, then
followed in other people.

A *movement* is a person's performance of it: BVH takes of one content by one performer (a
style of the Bandai Namco dataset's naming, ``dataset-2_{content}_{style}_{id}.bvh``) played
as one stream, ``raise-up-hands-in-turn`` alternating the ``raise-up-left-hand`` and
``raise-up-right-hand`` takes; or a video of a person through the pose model. Everything is
at the people's own speed, at the step time of the run: the learning phase
(:func:`rnnpb.learning_phase.learning_phase`, as ``rnnpb record`` runs it with its defaults)
records the learning performer; another performer's movements, one after another, are seen
as the robot's camera would see them at the model's framing and followed with the command
filter in the loop.
"""

from __future__ import annotations

import math
import re
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb.errors import ConfigError, RnnpbError

IN_TURN = "raise-up-hands-in-turn"
DEVELOPMENT_LEARNER = "feminine"
DEVELOPMENT_FOLLOWED = ("exhausted",)
"""The performers (styles) of the full form without ``--exam``: the shared development takes'
styles, which the exam excludes."""
DEVELOPMENT_VIDEOS = {"learn": ("jj_a", "circ_a"), "follow": ("jj_e", "jj_g", "circ_b")}
"""The development videos (named as the exam names its own: the prefix is the movement)."""
VIDEO_MOVEMENTS = {"jj": "jumping-jacks", "circ": "arm-circles"}
PB_JUMP = 0.15
"""A PB unit moving by more than this in one step jumps (the people exam's definition)."""
_NAME = re.compile(r"^dataset-2_(?P<content>[a-z-]+)_(?P<style>[a-z]+)_(?P<id>\d+)\.bvh$")


@dataclass(frozen=True)
class PeopleConfig:
    """``dt``: seconds per step; ``settle_seconds``: seconds after a movement begins that are
    not judged; ``segment_seconds``: the length of the segments judged for synchrony;
    ``seed``: the network's."""

    dt: float = 0.4
    settle_seconds: float = 4.8
    segment_seconds: float = 4.8
    seed: int = 0

    @property
    def settle_steps(self) -> int:
        return math.ceil(self.settle_seconds / self.dt - 1e-9)

    @property
    def segment_steps(self) -> int:
        return max(4, round(self.segment_seconds / self.dt))


def takes_of(root: Path, content: str, style: str, first: int, count: int) -> list[Path]:
    """Takes ``first`` … ``first + count - 1`` (1 = the lowest id) of ``content`` by ``style``
    under ``root``; the raises in turn alternate left and right takes."""
    if content == IN_TURN:
        left = takes_of(root, "raise-up-left-hand", style, first, count)
        right = takes_of(root, "raise-up-right-hand", style, first, count)
        return [take for pair in zip(left, right, strict=True) for take in pair]
    found = []
    for path in root.glob(f"dataset-2_{content}_{style}_*.bvh"):
        match = _NAME.match(path.name)
        if match and match["content"] == content and match["style"] == style:
            found.append((int(match["id"]), path))
    found.sort()
    chosen = found[first - 1 : first - 1 + count]
    if len(chosen) < count:
        raise ConfigError(
            f"{root}: {len(found)} takes of {content!r} by {style!r}; the study needs takes "
            f"{first} to {first + count - 1}"
        )
    return [path for _, path in chosen]


def video_path(root: Path, name: str) -> Path:
    """The video ``name`` under ``root`` (any of the usual extensions)."""
    for extension in (".mp4", ".avi", ".mov", ".webm"):
        path = root / f"{name}{extension}"
        if path.is_file():
            return path
    raise ConfigError(f"{root}: no video named {name} (.mp4, .avi, .mov or .webm)")


def video_movement(name: str) -> str:
    """The movement a video's name says (its prefix)."""
    prefix = name.split("_")[0]
    if prefix not in VIDEO_MOVEMENTS:
        raise ConfigError(f"video {name!r}: its name does not say its movement")
    return VIDEO_MOVEMENTS[prefix]


def capture_performance(files: list[Path]):
    """Motion capture as the learning phase reads it."""
    from rnnpb.learning_phase import from_capture

    return from_capture([str(f) for f in files])


@dataclass
class VideoPerformance:
    """A video through the pose model, every frame, and the pose model's time per frame."""

    performance: Any
    frame_ms: list[float] = field(default_factory=list)


def video_performance(path: Path) -> VideoPerformance:
    """A video through the pose model at its own frame rate (as ``rnnpb record video:PATH
    --perception pose`` reads it at the 0.1 s step, every frame)."""
    from rnnpb.learning_phase import from_source
    from rnnpb.perception import open_camera_source, video_fps

    fps = video_fps(path)
    if not fps:
        raise RnnpbError(f"{path}: no frame rate")
    source = open_camera_source("video", str(path), perception="pose")
    frame_ms: list[float] = []
    track = source.tracker.track

    def timed(frame):
        start = time.perf_counter()
        result = track(frame)
        frame_ms.append((time.perf_counter() - start) * 1000)
        return result

    source.tracker.track = timed  # the pose model's time per frame, as the source reads it
    with source:
        performance = from_source(source, frame_time=1.0 / fps)
    return VideoPerformance(performance, frame_ms)


def learn(performance, name: str, dt: float):
    """The learning phase with ``rnnpb record``'s defaults: the recording, or the one-line
    reason it recorded nothing."""
    from rnnpb.learning_phase import PhaseOptions, learning_phase

    try:
        return learning_phase(performance, name, PhaseOptions(dt=dt))
    except RnnpbError as error:
        return str(error)


def train_refusal(sequences, dt: float) -> str:
    """What ``rnnpb train`` with its defaults says of the data ("" when it learns them): the
    one check, and the learning's own range check."""
    from rnnpb.model.learning import prepare_data
    from rnnpb.robot import JOINT_LIMITS
    from rnnpb.safety import check_data

    safety = check_data(sequences, dt=dt)
    if safety.unsafe:
        return safety.first
    try:
        prepare_data(sequences, JOINT_LIMITS)
    except RnnpbError as error:
        return str(error)
    return ""


def judged(sequences, dt: float) -> dict[str, int]:
    """Steps of learned data the independent judges refuse: MuJoCo's contacts (posture and
    way from the step before) and the servo's step."""
    from rnnpb.analysis.judges import CollisionJudge, judge_speed

    judge = CollisionJudge()
    steps = colliding = fast = 0
    for sequence in sequences:
        steps += sequence.n_steps
        colliding += judge.judge(sequence.motor).count
        fast += judge_speed(sequence.motor, dt).count
    return {"steps": steps, "colliding": colliding, "too_fast": fast}


@dataclass
class Followed:
    """Another performer's movements one after another, as the robot's camera sees them at a
    framing: sensory (n, 4), the joints the learning phase gives for their hands (n, 8: the
    robot's nearest movement at their tempo), the movement of each step."""

    sensory: np.ndarray
    target: np.ndarray
    labels: list[str]


def seen(performances: list[tuple[str, Any]], dt: float, framing: float) -> Followed:
    """The performances (movement, performance) as a stream at ``dt``, framed at ``framing``
    (a hand outside the view not seen), with each step's target joints."""
    from rnnpb.demonstrator import MirrorMapping, UserBody
    from rnnpb.learning_phase import fit_to_servos, resampled, sensory_at, whole_cycles
    from rnnpb.robot.camera import RobotCamera

    camera = RobotCamera()
    sensory, target, labels = [], [], []
    for movement, performance in performances:
        steps = resampled(performance, dt)
        values = sensory_at(steps, performance, framing, camera)
        with np.errstate(invalid="ignore"):
            outside = ((values < 0) | (values > 1)).reshape(-1, 2, 2).any(axis=2)
        values.reshape(-1, 2, 2)[outside] = np.nan
        period = whole_cycles(values).period
        window = int(round(period)) if period else max(2, round(1.0 / dt))
        fit = fit_to_servos(steps.hands, MirrorMapping(UserBody(), dt=dt), window)
        sensory.append(values)
        target.append(fit.motor)
        labels += [movement] * len(values)
    return Followed(np.concatenate(sensory), np.concatenate(target), labels)


def follow(model, stream: Followed, dt: float) -> dict[str, Any]:
    """The stream through the robot (the on-line settings that suit the model, the command
    filter in the loop): what it recognised, its PB, its commands and which were filtered."""
    from rnnpb.interaction import InteractionLoop, LoopConfig
    from rnnpb.model import MirrorSystem, OnlineConfig
    from rnnpb.robot import ELBOW_AT_ZERO_PITCH
    from rnnpb.safety import CommandFilter, SafetyChecker, SafetyLimits
    from rnnpb.sources import ArraySensorySource

    rest = np.array([0.0, 0.0, 0.0, ELBOW_AT_ZERO_PITCH] * 2)
    records = []
    with ArraySensorySource(stream.sensory) as source:
        choice = OnlineConfig.for_model(model)  # as `rnnpb interact` chooses
        mirror = MirrorSystem(model, choice.config, recognition=choice.recognition)
        checker = SafetyChecker(SafetyLimits(dt=dt))
        InteractionLoop(
            mirror,
            source,
            config=LoopConfig(dt=dt),
            command_filter=CommandFilter(checker, initial=rest),
        ).run(on_step=records.append)
    return {
        "labels": list(stream.labels),
        "recognised": [r.recognised for r in records],
        "novelty": [r.novelty for r in records],
        "filtered": [bool(r.filtered) for r in records],
        "pb": np.array([r.pb for r in records]),
        "motor": np.array([r.motor for r in records]),
        "target": stream.target,
    }


def settled_steps(labels: list[str], settle: int) -> np.ndarray:
    """(T,) bool: steps at least ``settle`` after their movement began."""
    judged = np.ones(len(labels), bool)
    for t in range(len(labels)):
        if t == 0 or labels[t] != labels[t - 1]:
            judged[t : t + settle] = False
    return judged


def _in_step(run: dict[str, Any], settled: np.ndarray, segment: int) -> tuple[int, int]:
    """(segments in step, segments) of a run's settled steps: each movement's settled steps
    in consecutive segments of ``segment`` steps whose lag is at most one step."""
    from rnnpb.analysis.metrics import phase_lag
    from rnnpb.learning_phase import whole_cycles

    motor, target, labels = run["motor"], run["target"], run["labels"]
    good = total = 0
    t = 0
    while t < len(labels):
        end = t
        while end < len(labels) and labels[end] == labels[t]:
            end += 1
        steps = np.flatnonzero(settled[t:end]) + t
        finite = np.isfinite(target[t:end]).all(axis=1)
        period = whole_cycles(target[t:end][finite]).period if finite.sum() > 8 else None
        reach = max(1, math.ceil((period or 8) / 2))
        for a in range(0, len(steps) - segment + 1, segment):
            chunk = steps[a : a + segment]
            if not np.isfinite(target[chunk]).all():
                continue
            lag = phase_lag(motor[chunk], target[chunk], min(reach, (segment - 3) // 2))
            total += 1
            good += int(abs(lag) <= 1.0)
        t = end
    return good, total


def measure(runs: list[dict[str, Any]], config: PeopleConfig) -> dict[str, Any]:
    """Over the runs' settled steps: the recognised share (overall and per movement), the
    share of segments in step, the share of steps a PB unit jumps on; the filtered share of
    all commands."""
    right = judged = jumps = filtered = commands = good = segments = 0
    per: dict[str, list[int]] = {}
    for run in runs:
        settled = settled_steps(run["labels"], config.settle_steps)
        moved = np.zeros(len(settled), bool)
        moved[1:] = np.abs(np.diff(run["pb"], axis=0)).max(axis=1) > PB_JUMP
        for t in np.flatnonzero(settled):
            ok = run["recognised"][t] == run["labels"][t]
            per.setdefault(run["labels"][t], [0, 0])
            per[run["labels"][t]][0] += int(ok)
            per[run["labels"][t]][1] += 1
            right += int(ok)
            judged += 1
        jumps += int(moved[settled].sum())
        filtered += sum(run["filtered"])
        commands += len(run["filtered"])
        g, n = _in_step(run, settled, config.segment_steps)
        good, segments = good + g, segments + n

    def share(a: float, b: float) -> float:
        return a / b if b else float("nan")

    return {
        "recognised_share": share(right, judged),
        "judged_steps": judged,
        "per_movement": {k: v[0] / v[1] for k, v in per.items()},
        "in_step_share": share(good, segments),
        "segments": segments,
        "pb_jump_share": share(jumps, judged),
        "filtered": filtered,
        "commands": commands,
    }


def looped_video(path: Path, dt: float, framing: float):
    """The video at ``path`` through the pose model at ``dt``, framed at ``framing``, played
    over and over: at its end the file is opened again, the pose tracker kept (one tracker for
    the whole run, as a camera's)."""
    from rnnpb.interaction import open_source
    from rnnpb.perception import VideoFileSource

    class Looped(VideoFileSource):
        def read(self):
            frame = super().read()
            if frame is None:
                self.close()
                self.connect()
                frame = super().read()
            return frame

    source = open_source(f"video:{path}", dt=dt, perception="pose", framing=framing)
    tracked = getattr(source, "inner", source)  # a video sampled every N-th frame: inside
    tracked.frames = Looped(tracked.frames.path)
    return source


def paced_run(model, path: Path, steps: int, dt: float) -> dict[str, Any]:
    """A video (looped) through the pose model and ``model`` in real time at ``dt``, as
    ``rnnpb interact --source video:PATH --perception pose --paced`` runs it: missed
    deadlines and the step's sections."""
    from rnnpb.interaction import InteractionLoop, LoopConfig
    from rnnpb.model import MirrorSystem, OnlineConfig

    source = looped_video(path, dt, model.framing)
    choice = OnlineConfig.for_model(model)
    mirror = MirrorSystem(model, choice.config, recognition=choice.recognition)
    # Compiled before the run, as `rnnpb interact` does before its first paced step.
    mirror.step(np.full(4, 0.5))
    mirror.reset()
    with source:
        loop = InteractionLoop(
            mirror, source, config=LoopConfig(dt=dt, paced=True, max_steps=steps)
        )
        loop.run()
    summary = loop.summary()
    return {
        "steps": summary.steps,
        "missed": summary.missed_deadlines,
        "section_ms": summary.section_ms,
    }
