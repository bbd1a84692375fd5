"""The people study (docs/experiments.md): real motion capture of people through the robot's
learning phase, teaching and following.

For each movement, the learning performer's takes are recorded as ``rnnpb record bvh:`` does
(hands on the standard body, resampled to the step, joint angles by the safe retargeting) and
cut into training sequences; one network learns every movement (the fast preset). Then each
other performer's takes of every movement, one movement after another, are followed by the
robot with the command filter in the loop; the same streams go through teaching's episode
cutter. Measured: unsafe steps of every recording, the recognised share of settled steps and
the filtered share of commands while following, and the demonstrator's reach with the safe
retargeting against the paper's inverse kinematics. The scenarios and measures are
:mod:`rnnpb.experiments.scenarios.people`; the targets' definitions are the study's exam.

``--data DIR``: a folder of BVH takes named as the Bandai Namco dataset names them. The quick
form learns each movement in DIR from its first two takes and follows its third (the shared
development takes: any styles); the full form learns from the development performers
(:data:`~rnnpb.experiments.scenarios.people.DEVELOPMENT_LEARNER` and ``…_FOLLOWED``), the exam
from the exam's.
"""

from __future__ import annotations

import re
import time
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
SUMMARY = "real motion capture: safe recordings, and another performer's movements followed"
NEEDS_DATA = True  # the motion capture is not part of rnnpb: `--data DIR`

_TAKE = re.compile(r"^dataset-2_(?P<content>[a-z-]+)_(?P<style>[a-z]+)_(?P<id>\d+)\.bvh$")


def _plan(data: Path, options: StudyOptions, exam: Exam) -> dict[str, Any]:
    """Which takes are learned and which followed, per movement."""
    if options.quick:
        found: dict[tuple[str, str], list[Path]] = {}
        for path in sorted(data.glob("dataset-2_*.bvh")):
            match = _TAKE.match(path.name)
            if match:
                found.setdefault((match["content"], match["style"]), []).append(path)
        movements = {
            content: takes for (content, _), takes in sorted(found.items()) if len(takes) >= 3
        }
        if not movements:
            raise ConfigError(f"{data}: no movement with 3 takes named dataset-2_*_*_N.bvh")
        return {
            "movements": list(movements),
            "learn": {m: takes[:2] for m, takes in movements.items()},
            "follow": {"another take": {m: takes[2:3] for m, takes in movements.items()}},
        }
    count = int(exam.parameter("takes"))
    movements = list(exam.name_list("movements"))
    if options.exam is not None:
        (learner,) = exam.name_list("learn_styles")
        followed = exam.name_list("follow_styles")
    else:  # the development performers: never the exam's
        learner, followed = scenario.DEVELOPMENT_LEARNER, scenario.DEVELOPMENT_FOLLOWED
    return {
        "movements": movements,
        "learn": {m: scenario.takes_of(data, m, learner, count) for m in movements},
        "follow": {
            style: {m: scenario.takes_of(data, m, style, count) for m in movements}
            for style in followed
        },
    }


def run(out: Path, options: StudyOptions) -> StudyOutcome:
    from rnnpb.analysis.figures import plot_following
    from rnnpb.model import TrainConfig, train
    from rnnpb.robot import JOINT_LIMITS
    from rnnpb.safety import SafetyChecker, SafetyLimits

    start = time.perf_counter()
    if options.data is None:
        raise ConfigError("the people study reads motion capture: give --data DIR")
    data = Path(options.data)
    if not data.is_dir():
        raise ConfigError(f"--data {data}: no such directory")
    out = Path(out)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    exam = options.exam or load_exam(NAME)
    config = scenario.PeopleConfig(
        distance=exam.parameter("distance"), settle_steps=int(exam.parameter("settle_steps"))
    )
    seed = exam.seed_list("training")[0] if options.exam else options.seed
    plan = _plan(data, options, exam)
    checker = SafetyChecker(SafetyLimits(dt=config.dt))
    recordings: dict[str, dict[str, int]] = {}
    sequences, scales = [], {}
    for movement in plan["movements"]:
        files = plan["learn"][movement]
        scales[movement] = scenario.time_scale(files, config.dt)
        stream = scenario.stream_hands(files, config, scales[movement])
        demo = scenario.record(stream.hands, config, movement)
        recordings[f"learn {movement}"] = scenario.path_safety(demo.motor, config.dt, checker)
        sequences += scenario.length_sequences(demo, movement, config.sequence_length)
    model = train(sequences, JOINT_LIMITS, config=TrainConfig.fast(seed=seed))
    model.save(out / "people.npz")
    runs: dict[str, dict[str, Any]] = {}
    for performer, takes in plan["follow"].items():
        sensory, labels = [], []
        for movement in plan["movements"]:
            stream = scenario.stream_hands(takes[movement], config, scales[movement])
            demo = scenario.record(stream.hands, config, movement)
            recordings[f"{performer} {movement}"] = scenario.path_safety(
                demo.motor, config.dt, checker
            )
            for k, motor in enumerate(scenario.taught_motor(stream.hands, demo.sensory, config)):
                recordings[f"{performer} {movement} taught {k + 1}"] = scenario.path_safety(
                    motor, config.dt, checker
                )
            sensory.append(demo.sensory)  # NaN where a hand is out of the camera's view
            labels += [movement] * len(stream.hands)
        runs[performer] = scenario.follow(model, np.concatenate(sensory), labels)
    following = scenario.measure(list(runs.values()), config.settle_steps)
    reach = scenario.demonstrator_reach(seed)
    steps = sum(r["steps"] for r in recordings.values())
    colliding = sum(r["collision"] for r in recordings.values())
    beyond = sum(r["speed"] + r["outside_limits"] for r in recordings.values())
    measures = {
        "recorded_colliding_steps": colliding,
        "recorded_limits_held": 1.0 - beyond / steps if steps else float("nan"),
        "followed_recognised": following["recognised_share"],
        "filtered_commands": following["filtered_share"],
        "demonstrator_reach_ratio": reach["ratio"],
    }
    plot_following(runs, plan["movements"], out / "figures" / "following.png", config.settle_steps)
    results: dict[str, Any] = {
        "config": {**config.__dict__, "time_scales": scales, "training_seed": seed},
        "quick": options.quick,
        "versions": versions(),
        "takes": {
            "learn": {m: [p.name for p in f] for m, f in plan["learn"].items()},
            "follow": {
                s: {m: [p.name for p in f] for m, f in t.items()} for s, t in plan["follow"].items()
            },
        },
        "recordings": recordings,
        "following": {k: v for k, v in following.items()},
        "demonstrator_reach": reach,
        "measures": measures,
        "training": {"sequences": len(sequences), "seconds": model.meta["training"]["seconds"]},
    }
    if options.exam is not None:
        results["exam"] = exam.to_json()
    targets = judge(measures, exam)
    results["targets"] = {k: t.to_json() for k, t in targets.items()}
    results["runtime_s"] = time.perf_counter() - start
    write_outputs(out, _report(results, targets, exam, options), results)
    return StudyOutcome(results["runtime_s"], targets)


def judge(measures: dict[str, Any], exam: Exam | None = None) -> dict[str, Target]:
    """The targets by ``exam``'s definitions (default: the study's exam) from the measures:
    counts and ratios as numbers, shares as percentages."""

    def detail(target, value: float) -> str:
        if target.limit > 1 or target.name.endswith("steps"):
            return f"{value:.4g} ({target.compare} {target.limit:g})"
        return f"{value:.2%} ({target.compare} {target.limit:.0%})"

    return (exam or load_exam(NAME)).verdicts(measures, detail)


def judge_results(results: dict[str, Any], exam: Exam) -> dict[str, Target]:
    """The study's targets judged by ``exam``'s definitions from a finished results.json."""
    return judge(results["measures"], exam)


def _report(
    results: dict[str, Any], targets: dict[str, Target], exam: Exam, options: StudyOptions
) -> list[str]:
    following = results["following"]
    lines = [
        "# Study: people — real motion capture through the robot",
        "",
        f"{'Quick form' if options.quick else 'Full form'}; motion capture from `--data`; "
        f"the network's seed {results['config']['training_seed']}; dt "
        f"{results['config']['dt']} s; each movement slowed so that the learning performer's "
        f"shortest period is {scenario.PERIOD_STEPS} steps (time scales: "
        + ", ".join(f"{m} {s:.2f}" for m, s in results["config"]["time_scales"].items())
        + ").",
        "",
    ]
    if options.exam is not None:
        lines += [exam.describe(), ""]
    lines += ["## Targets", ""]
    lines += table(
        ["target", "met", "measured"],
        [(k, "yes" if t.met else "NO", t.detail) for k, t in targets.items()],
    )
    lines += ["", "## Recordings (learning phase and teaching)", ""]
    lines += table(
        ["recording", "steps", "colliding", "too fast", "outside limits"],
        [
            (k, r["steps"], r["collision"], r["speed"], r["outside_limits"])
            for k, r in results["recordings"].items()
        ],
    )
    lines += ["", "## Following another performer", ""]
    lines += table(
        ["movement", "recognised (settled steps)"],
        [(m, f"{100 * v:.1f} %") for m, v in following["per_movement"].items()],
    )
    lines += [
        "",
        f"Over {following['judged_steps']} judged steps: {fmt(100 * following['recognised_share'])}"
        f" % recognised; {fmt(100 * following['filtered_share'], 2)} % of "
        f"{following['commands']} commands filtered.",
        "",
        embed("following", "following.png"),
        "",
        "## The demonstrator's reach",
        "",
        f"Mean hand distance over the learning sets: safe retargeting "
        f"{results['demonstrator_reach']['safe_m']:.3g} m, the paper's inverse kinematics "
        f"{results['demonstrator_reach']['plain_m']:.3g} m (ratio "
        f"{results['demonstrator_reach']['ratio']:.3f}).",
    ]
    return lines
