"""The people study (docs/experiments.md): real people, at their own speed, through the
robot's learning phase and then followed in other people, at the paper's step and at 0.1 s.

For each step time and kind of source — motion capture (``dataset-2_*.bvh`` takes) and video
through the pose model (when ``rnnpb[hands]`` is installed) — each movement of the learning
performer goes through the learning phase as ``rnnpb record`` runs it with its defaults, one
network learns them all (the paper's algorithm, as `rnnpb train` learns by default), and
the other performers' movements, one after
another, are followed with the command filter in the loop. Measured: sources recorded or
learned with a refusal, learned steps the independent judges (MuJoCo's contacts, the servo's
step) refuse, the recognised share, the share of segments followed in step and the share of
steps the PB jumps on (all over settled steps), the filtered commands, the pose model's time
per frame, and the missed deadlines of a video paced in real time at 0.1 s. The scenarios and
measures are :mod:`rnnpb.experiments.scenarios.people`; the targets' definitions the exam's.

``--data DIR``: the takes (named as the Bandai Namco dataset names them) and the videos (named
as the exam names them). The quick form learns each movement in DIR with three takes from its
first two and follows its third, at dt 0.1; the full form learns from the development
performers (:data:`~rnnpb.experiments.scenarios.people.DEVELOPMENT_LEARNER` and ``…_FOLLOWED``,
and the development videos), the exam from the exam's.
"""

from __future__ import annotations

import os
import platform
import re
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.experiments.exams import Exam, load_exam
from rnnpb.experiments.reporting import embed, fmt, table, versions, write_outputs
from rnnpb.experiments.scenarios import people as scenario
from rnnpb.experiments.studies import StudyOptions, StudyOutcome
from rnnpb.experiments.summary import Target

NAME = "people"
SUMMARY = "real people at their own speed: learned from one, followed in others, at 0.4 and 0.1 s"
NEEDS_DATA = True  # the motion capture and videos are not part of rnnpb: `--data DIR`

_TAKE = re.compile(r"^dataset-2_(?P<content>[a-z-]+)_(?P<style>[a-z]+)_(?P<id>\d+)\.bvh$")


def _plan(data: Path, options: StudyOptions, exam: Exam) -> dict[str, Any]:
    """Which takes and videos are learned and which followed, and at which step times."""
    if options.quick:
        found: dict[str, list[Path]] = {}
        for path in sorted(data.glob("dataset-2_*.bvh")):
            match = _TAKE.match(path.name)
            if match:
                found.setdefault(match["content"], []).append(path)
        movements = {content: takes for content, takes in sorted(found.items()) if len(takes) >= 3}
        if not movements:
            raise ConfigError(f"{data}: no movement with 3 takes named dataset-2_*_*_N.bvh")
        return {
            "step_times": [0.1],
            "learn": {m: takes[:2] for m, takes in movements.items()},
            "follow": {"another take": {m: takes[2:3] for m, takes in movements.items()}},
            "videos": {"learn": [], "follow": []},
        }
    first, count = int(exam.parameter("first_take")), int(exam.parameter("takes"))
    movements = exam.name_list("movements")
    if options.exam is not None:
        (learner,) = exam.name_list("learn_styles")
        followed = exam.name_list("follow_styles")
        videos = {"learn": exam.name_list("video_learn"), "follow": exam.name_list("video_follow")}
    else:  # the development performers: never the exam's
        learner, followed = scenario.DEVELOPMENT_LEARNER, scenario.DEVELOPMENT_FOLLOWED
        videos = {k: list(v) for k, v in scenario.DEVELOPMENT_VIDEOS.items()}
    return {
        "step_times": [float(dt) for dt in exam.name_list("step_times")],
        "learn": {m: scenario.takes_of(data, m, learner, first, count) for m in movements},
        "follow": {
            style: {m: scenario.takes_of(data, m, style, first, count) for m in movements}
            for style in followed
        },
        "videos": videos,
    }


def _videos(data: Path, plan: dict[str, Any]) -> dict[str, Any]:
    """Every planned video through the pose model once (shared by both step times); empty
    when the pose model is not installed."""
    from rnnpb.perception import pose_available

    names = [*plan["videos"]["learn"], *plan["videos"]["follow"]]
    if not names or not pose_available():
        return {}
    return {name: scenario.video_performance(scenario.video_path(data, name)) for name in names}


def _kind(
    kind: str,
    learn: dict[str, Any],
    follow: dict[str, list[tuple[str, Any]]],
    dt: float,
    seed: int,
    out: Path,
) -> dict[str, Any]:
    """One kind of source at one step time: learned (the learning phase, then one network) and
    followed by every other performer."""
    from rnnpb.model import TrainConfig, train
    from rnnpb.robot import JOINT_LIMITS

    sources, sequences, framings = {}, [], set()
    for movement, performance in learn.items():
        recording = scenario.learn(performance, movement, dt)
        if isinstance(recording, str):
            sources[movement] = {"refused": recording}
            continue
        refusal = scenario.train_refusal(recording.sequences, dt)
        sources[movement] = {
            "refused": refusal,
            "sequences": len(recording.sequences),
            "judged": scenario.judged(recording.sequences, dt),
            **recording.to_json(),
        }
        if not refusal:
            sequences += recording.sequences
            framings.add(recording.framing.distance)
    result: dict[str, Any] = {"sources": sources, "runs": {}}
    if not sequences or len(framings) != 1:
        return result
    # As `rnnpb train` learns with its defaults: the paper's algorithm.
    model = train(sequences, JOINT_LIMITS, config=replace(TrainConfig.paper(), seed=seed))
    framing = framings.pop()
    model = replace(model, meta={**model.meta, "dt": dt, "framing_m": framing})
    model.save(out / f"{kind}-dt{dt:g}.npz")
    result["model"] = str(out / f"{kind}-dt{dt:g}.npz")
    for performer, performances in follow.items():
        run = scenario.follow(model, scenario.seen(performances, dt, framing), dt)
        result["runs"][performer] = run
    return result


def run(out: Path, options: StudyOptions) -> StudyOutcome:
    from rnnpb.analysis.figures import plot_following

    start = time.perf_counter()
    if options.data is None:
        raise ConfigError("the people study reads motion capture and videos: give --data DIR")
    data = Path(options.data)
    if not data.is_dir():
        raise ConfigError(f"--data {data}: no such directory")
    out = Path(out)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    exam = options.exam or load_exam(NAME)
    seed = exam.seed_list("training")[0] if options.exam else options.seed
    plan = _plan(data, options, exam)
    capture = {m: scenario.capture_performance(f) for m, f in plan["learn"].items()}
    followed = {
        style: [(m, scenario.capture_performance(f)) for m, f in takes.items()]
        for style, takes in plan["follow"].items()
    }
    videos = _videos(data, plan)
    learn_videos = {
        scenario.video_movement(n): videos[n].performance for n in plan["videos"]["learn"]
    }
    follow_videos = {
        n: [(scenario.video_movement(n), videos[n].performance)] for n in plan["videos"]["follow"]
    }
    kinds: dict[str, dict[str, Any]] = {}
    measures: dict[str, Any] = {}
    for dt in plan["step_times"]:
        config = scenario.PeopleConfig(
            dt=dt,
            settle_seconds=float(exam.parameter("settle_seconds")),
            segment_seconds=float(exam.parameter("segment_seconds")),
            seed=seed,
        )
        kinds[f"capture dt {dt:g}"] = _kind("capture", capture, followed, dt, seed, out)
        if videos:
            kinds[f"video dt {dt:g}"] = _kind("video", learn_videos, follow_videos, dt, seed, out)
        runs = [r for k, v in kinds.items() if k.endswith(f"dt {dt:g}") for r in v["runs"].values()]
        following = scenario.measure(runs, config)
        measures[f"dt{dt:g}"] = following
        plot_following(
            {
                f"{k} · {p}": r
                for k, v in kinds.items()
                if k.endswith(f"dt {dt:g}")
                for p, r in v["runs"].items()
            },
            sorted({m for r in runs for m in r["labels"]}),
            out / "figures" / f"following_dt{dt:g}.png",
            config.settle_steps,
            dt=dt,
        )
    paced = {}
    if videos and not options.quick:
        name = (exam.name_list("video_paced") if options.exam else plan["videos"]["follow"])[0]
        model_path = kinds.get("video dt 0.1", {}).get("model")
        if model_path:
            from rnnpb.model import TrainedModel

            paced = scenario.paced_run(
                TrainedModel.load(model_path),
                scenario.video_path(data, name),
                int(exam.parameter("paced_steps")),
                0.1,
            )
    frame_ms = [ms for v in videos.values() for ms in v.frame_ms]
    values = _values(kinds, measures, frame_ms, paced)
    results: dict[str, Any] = {
        "config": {"training_seed": seed, "step_times": plan["step_times"]},
        "quick": options.quick,
        "versions": versions(),
        "machine": {
            "processor": platform.processor() or platform.machine(),
            "cores": os.cpu_count(),
        },
        "plan": {
            "learn": {m: [p.name for p in f] for m, f in plan["learn"].items()},
            "follow": {
                s: {m: [p.name for p in f] for m, f in t.items()} for s, t in plan["follow"].items()
            },
            "videos": plan["videos"],
        },
        "sources": {k: v["sources"] for k, v in kinds.items()},
        "following": measures,
        "paced": paced,
        "pose_frames": len(frame_ms),
        "measures": values,
    }
    if options.exam is not None:
        results["exam"] = exam.to_json()
    targets = judge(values, exam)
    results["targets"] = {k: t.to_json() for k, t in targets.items()}
    results["runtime_s"] = time.perf_counter() - start
    write_outputs(out, _report(results, targets, exam, options), results)
    return StudyOutcome(results["runtime_s"], targets)


def _values(kinds, measures, frame_ms, paced) -> dict[str, Any]:
    """The measure of every target, by name."""
    refused = sum(bool(s.get("refused")) for k in kinds.values() for s in k["sources"].values())
    unsafe = sum(
        s["judged"]["colliding"] + s["judged"]["too_fast"]
        for k in kinds.values()
        for s in k["sources"].values()
        if "judged" in s
    )
    filtered = sum(m["filtered"] for m in measures.values())
    commands = sum(m["commands"] for m in measures.values())
    values: dict[str, Any] = {
        "recorded_then_refused": refused,
        "learned_unsafe_steps": unsafe,
        "filtered_commands": filtered / commands if commands else float("nan"),
        "pose_frame_ms": float(np.median(frame_ms)) if frame_ms else float("nan"),
        "paced_missed_deadlines": paced.get("missed", float("nan")),
    }
    for dt in ("0.4", "0.1"):
        m = measures.get(f"dt{dt}", {})
        values[f"followed_recognised_dt{dt}"] = m.get("recognised_share", float("nan"))
        values[f"followed_in_step_dt{dt}"] = m.get("in_step_share", float("nan"))
        values[f"pb_jumps_dt{dt}"] = m.get("pb_jump_share", float("nan"))
    return values


def judge(measures: dict[str, Any], exam: Exam | None = None) -> dict[str, Target]:
    """The targets by ``exam``'s definitions (default: the study's exam): counts and times as
    numbers, shares as percentages."""

    def detail(target, value: float) -> str:
        if target.limit > 1 or target.limit == 0:
            return f"{value:.4g} ({target.compare} {target.limit:g})"
        return f"{value:.2%} ({target.compare} {target.limit:.0%})"

    return (exam or load_exam(NAME)).verdicts(measures, detail)


def judge_results(results: dict[str, Any], exam: Exam) -> dict[str, Target]:
    """The study's targets judged by ``exam``'s definitions from a finished results.json."""
    return judge(results["measures"], exam)


def _report(
    results: dict[str, Any], targets: dict[str, Target], exam: Exam, options: StudyOptions
) -> list[str]:
    lines = [
        "# Study: people — real people at their own speed",
        "",
        f"{'Quick form' if options.quick else 'Full form'}; motion capture and videos from "
        f"`--data`; the network's seed {results['config']['training_seed']}; step times "
        + ", ".join(f"{dt:g} s" for dt in results["config"]["step_times"])
        + f"; {results['machine']['processor']}, {results['machine']['cores']} cores.",
        "",
    ]
    if options.exam is not None:
        lines += [exam.describe(), ""]
    lines += ["## Targets", ""]
    lines += table(
        ["target", "met", "measured"],
        [(k, "yes" if t.met else "NO", t.detail) for k, t in targets.items()],
    )
    lines += ["", "## The learning phase", ""]
    rows = []
    for kind, sources in results["sources"].items():
        for movement, s in sources.items():
            if "framing" not in s:
                rows.append((kind, movement, "—", "—", "—", "—", s["refused"]))
                continue
            rows.append(
                (
                    kind,
                    movement,
                    f"{s['framing']['distance_m']} m" if s["framing"]["distance_m"] else "camera",
                    "yes" if s["time"]["retimed"] else "no",
                    f"{s['servos']['reduced_steps']} "
                    f"({s['servos']['median_reduced_amplitude']:.0%})",
                    f"{s['cycles']['count']} × {fmt(s['cycles']['median_steps'])} steps",
                    s["refused"] or "learned",
                )
            )
    lines += table(
        [
            "source",
            "movement",
            "framing",
            "retimed",
            "steps made smaller (median amplitude)",
            "whole cycles",
            "train",
        ],
        rows,
    )
    lines += ["", "## Following another performer", ""]
    for key, m in results["following"].items():
        lines += [
            f"**{key}**: recognised {fmt(100 * m['recognised_share'])} % of "
            f"{m['judged_steps']} settled steps ("
            + ", ".join(f"{k} {100 * v:.1f} %" for k, v in m["per_movement"].items())
            + f"); in step in {fmt(100 * m['in_step_share'])} % of {m['segments']} segments; "
            f"PB jumps on {fmt(100 * m['pb_jump_share'], 2)} %; "
            f"{m['filtered']} of {m['commands']} commands filtered.",
            "",
            embed(f"following {key}", f"following_{key}.png"),
            "",
        ]
    if results["paced"]:
        p = results["paced"]
        lines += [
            "## Bare hands in real time",
            "",
            f"{p['steps']} steps at 0.1 s of a video through the pose model: {p['missed']} "
            f"missed deadlines; median pose time per frame "
            f"{fmt(results['measures']['pose_frame_ms'])} ms over {results['pose_frames']} frames.",
        ]
    return lines
