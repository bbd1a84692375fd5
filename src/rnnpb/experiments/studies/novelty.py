"""``rnnpb study novelty``: does the robot know what it sees? (issue: recognition with
confidence, and a novelty detector that tells a new movement from noise; paper section 4.1.)

For each learning set (1–4, and the larger set), the mirror system meets generated streams of
the user: each learned pattern held; a learned pattern, then a novel structured movement (the
left-out pattern, every new shape of :data:`rnnpb.demonstrator.NEW_SHAPES`); unstructured
movement (:data:`rnnpb.demonstrator.UNSTRUCTURED`); the hands held still. Every step's novelty
state is compared with the truth. Measured: the confusion matrix of the four states, the delay
until a novel movement is called ``novel`` (steps and cycles), a ROC curve of the novelty
score (the best learned pattern's RMS error), the recognition accuracy on learned patterns
(with the nearest-learned-PB rule for comparison).

Models: ``DIR/models/set1.npz`` … ``set4.npz`` and ``full.npz`` when present (for example the
models ``rnnpb demo`` learned, copied there), else they are learned and saved there (the
paper's algorithm; ``--quick``: ``TrainConfig.fast()``, sets 1 and full only).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb.experiments.reporting import embed, fmt, table, versions, write_outputs
from rnnpb.experiments.studies import StudyOptions, StudyOutcome
from rnnpb.experiments.studies._pool import study_pool
from rnnpb.experiments.summary import Target

NAME = "novelty"
SUMMARY = "recognition with confidence and novelty detection over generated streams"

STATES = ("familiar", "novel", "unstructured", "still", "")
LEAD_STEPS = 36  # a learned pattern before each novel movement (three cycles)
# Steps at a movement's start that are not judged: the detector needs a cycle of evidence
# and the robot about LOCK_LIMIT steps to lock on (docs/model.md).
SETTLE_STEPS = 24
PERIOD = 12  # the demonstrator's period, steps (PatternConfig.period_steps)


@dataclass(frozen=True)
class StreamRun:
    """One stream through the mirror system: its kind, truth per step, what the step said."""

    model: str
    kind: str  # learned, novel, unstructured, still
    movement: str
    seed: int
    start: int  # first step of the judged movement
    novelty: tuple[str, ...]
    recognised: tuple[str | None, ...]
    nearest_pb: tuple[str, ...]
    score: np.ndarray  # (T,) novelty score: smallest RMS pattern error (NaN undecided)
    sensory: np.ndarray  # (T, S) what was observed
    pattern_errors: np.ndarray  # (T, K) the evidence, to replay the detector with other settings
    pb: np.ndarray  # (T, P)
    confidence: tuple[float, ...] = ()  # the step's confidence in what it said


def _streams(
    patterns: tuple[str, ...], novel: tuple[str, ...], seed: int, steps: int
) -> list[tuple[str, str, int, list[tuple[str, int]]]]:
    from rnnpb.demonstrator import PAUSE, UNSTRUCTURED

    out = [("learned", p, 0, [(p, steps)]) for p in patterns]
    for i, movement in enumerate(novel):
        lead = patterns[(seed + i) % len(patterns)]
        out.append(("novel", movement, LEAD_STEPS, [(lead, LEAD_STEPS), (movement, steps)]))
    out += [("unstructured", m, 0, [(m, steps)]) for m in UNSTRUCTURED]
    out.append(("still", PAUSE, 0, [(PAUSE, steps)]))
    return out


def run_stream(
    mirror: Any,
    model_name: str,
    kind: str,
    movement: str,
    seed: int,
    start: int,
    segments: list[tuple[str, int]],
) -> StreamRun:
    """Play one generated stream through ``mirror`` (reset first)."""
    from rnnpb.demonstrator import make_scenario

    scenario = make_scenario(segments, seed=seed)
    mirror.reset()
    novelty, recognised, nearest, score, evidence, pbs = [], [], [], [], [], []
    confidence = []
    for u in scenario.sensory:
        result = mirror.step(u)
        confidence.append(result.confidence)
        evidence.append(result.pattern_errors)
        pbs.append(result.pb)
        novelty.append(result.novelty)
        recognised.append(result.recognised)
        nearest.append(mirror.model.nearest_pattern(result.pb)[0])
        errors = result.pattern_errors
        score.append(float(np.sqrt(np.min(errors))) if np.all(np.isfinite(errors)) else np.nan)
    return StreamRun(
        model_name,
        kind,
        movement,
        seed,
        start,
        tuple(novelty),
        tuple(recognised),
        tuple(nearest),
        np.array(score),
        scenario.sensory.copy(),
        np.array(evidence),
        np.array(pbs),
        tuple(confidence),
    )


def replay(run: StreamRun, model: Any, config: Any, use_taught: bool = True) -> StreamRun:
    """The same stream's evidence through the detector with other settings (the regression
    does not depend on them): how the settings were chosen, and (``use_taught=False``) what
    the detector says without the hands as taught."""
    from dataclasses import replace

    from rnnpb.model.mirror import normalized_hands
    from rnnpb.model.recognition import initial_recognition_state, recognise, taught_stretches

    names = tuple(model.pattern_pb)
    learned = np.array([model.pattern_pb[n] for n in names])
    taught = taught_stretches(model.taught_hands or {}, names, config) if use_taught else None
    state = initial_recognition_state(run.sensory.shape[1], run.pb.shape[1], config)
    novelty, recognised, confidence = [], [], []
    for u, errors, pb in zip(run.sensory, run.pattern_errors, run.pb, strict=True):
        u, seen = normalized_hands(u, len(u))
        state, answer = recognise(state, u, seen, errors, pb, learned, names, config, taught)
        novelty.append(answer.novelty)
        recognised.append(answer.recognised)
        confidence.append(answer.confidence)
    return replace(
        run, novelty=tuple(novelty), recognised=tuple(recognised), confidence=tuple(confidence)
    )


#: The models the study measures: name -> (learning set, learned with the fast preset).
FULL_MODELS: dict[str, tuple[str, bool]] = {
    "1": ("1", False),
    "2": ("2", False),
    "3": ("3", False),
    "4": ("4", False),
    "full": ("full", False),
    "fast-1": ("1", True),
    "fast-full": ("full", True),
}
QUICK_MODELS: dict[str, tuple[str, bool]] = {"fast-1": ("1", True), "fast-full": ("full", True)}


def model_file(name: str) -> str:
    """The file name of the study's model ``name`` in ``DIR/models``."""
    set_name, fast = (FULL_MODELS | QUICK_MODELS)[name]
    stem = "full" if set_name == "full" else f"set{set_name}"
    return f"{'fast_' if fast else ''}{stem}.npz"


def _models(out: Path, quick: bool) -> dict[str, Path]:
    """The study's models by name: their files in ``out/models``, learned there if absent."""
    from rnnpb.demonstrator import learning_set
    from rnnpb.model import TrainConfig, train
    from rnnpb.robot import JOINT_LIMITS

    folder = out / "models"
    folder.mkdir(parents=True, exist_ok=True)
    paths = {}
    for name, (set_name, fast) in (QUICK_MODELS if quick else FULL_MODELS).items():
        path = folder / model_file(name)
        if not path.exists():
            config = TrainConfig.fast(seed=0) if fast else TrainConfig(seed=0)
            train(learning_set(set_name), JOINT_LIMITS, config=config).save(path)
        paths[name] = path
    return paths


def _model_job(
    name: str, path: str, seeds: list[int], steps: int, shapes: tuple[str, ...]
) -> tuple[str, dict[str, Any], list[StreamRun]]:
    """Every stream of one model: its on-line regression and recognition settings chosen as
    ``OnlineConfig.for_model`` chooses them for the model's learning (as the dashboard and
    ``rnnpb interact`` do)."""
    from dataclasses import replace

    from rnnpb.demonstrator import learning_set_patterns, novel_pattern
    from rnnpb.model import MirrorSystem, OnlineConfig, TrainedModel
    from rnnpb.robot import JOINT_LIMITS

    set_name = (FULL_MODELS | QUICK_MODELS)[name][0]
    model = TrainedModel.load(path, joint_limits=JOINT_LIMITS)
    choice = OnlineConfig.for_model(model)
    mirror = MirrorSystem(model, choice.config, recognition=choice.recognition)
    patterns = learning_set_patterns(set_name)
    novel = ((novel_pattern(set_name),) if set_name != "full" else ()) + tuple(shapes)
    runs = [
        run_stream(mirror, name, kind, movement, seed, start, segments)
        for seed in seeds
        for kind, movement, start, segments in _streams(patterns, novel, seed, steps)
    ]
    settings = {
        "online_preset": choice.name,
        "online": choice.config.to_dict(),
        "recognition": choice.recognition.to_dict(),
        "taught_hands": model.taught_sensory is not None,
    }
    # The same evidence without the hands as taught: what they add (the network's evidence,
    # the PB and the structure test alone, with the settings chosen for that, as a model that
    # kept no taught hands gets them).
    untaught = OnlineConfig.for_model(replace(model, taught_sensory=None)).recognition
    alone = [replay(r, model, untaught, use_taught=False) for r in runs]
    return name, settings, runs, alone


def _judged(run: StreamRun) -> range:
    return range(run.start + SETTLE_STEPS, len(run.novelty))


def _share(runs: list[StreamRun], test) -> float:
    hits = [test(run, t) for run in runs for t in _judged(run)]
    return float(np.mean(hits)) if hits else float("nan")


def _delay(run: StreamRun) -> int | None:
    for t in range(run.start, len(run.novelty)):
        if run.novelty[t] == "novel":
            return t - run.start
    return None


def measure(runs: list[StreamRun]) -> dict[str, Any]:
    """Every measure of the study from its runs."""
    by_kind = {
        k: [r for r in runs if r.kind == k] for k in ("learned", "novel", "unstructured", "still")
    }
    confusion = {
        kind: {
            state or "undecided": int(
                sum(run.novelty[t] == state for run in rs for t in _judged(run))
            )
            for state in STATES
        }
        for kind, rs in by_kind.items()
    }
    learned = by_kind["learned"]
    delays = [_delay(r) for r in by_kind["novel"]]
    after = [r for r in by_kind["novel"]]

    def novel_after(run: StreamRun) -> float:
        d = _delay(run)
        if d is None:
            return 0.0
        tail = run.novelty[run.start + d :]
        return float(np.mean([s == "novel" for s in tail]))

    positives = np.concatenate([r.score[list(_judged(r))] for r in by_kind["novel"]] or [[]])
    negatives = np.concatenate([r.score[list(_judged(r))] for r in learned] or [[]])
    positives, negatives = positives[np.isfinite(positives)], negatives[np.isfinite(negatives)]
    thresholds = np.unique(np.concatenate([positives, negatives, [np.inf]]))
    roc = [
        (
            float(np.mean(negatives >= t)) if len(negatives) else 0.0,
            float(np.mean(positives >= t)) if len(positives) else 0.0,
        )
        for t in thresholds
    ]
    auc = (
        float(np.mean([[float(p > n) + 0.5 * float(p == n) for n in negatives] for p in positives]))
        if len(positives) and len(negatives)
        else 0.0
    )
    right, wrong = [], []
    for r in learned:
        for t in _judged(r):
            if r.recognised[t] is not None and r.novelty[t] == "familiar":
                (right if r.recognised[t] == r.movement else wrong).append(r.confidence[t])
    return {
        "confusion": confusion,
        "confidence_right": float(np.mean(right)) if right else float("nan"),
        "confidence_wrong": float(np.mean(wrong)) if wrong else float("nan"),
        "wrong_steps": len(wrong),
        "learned_recognised": _share(learned, lambda r, t: r.recognised[t] == r.movement),
        "learned_nearest_pb": _share(learned, lambda r, t: r.nearest_pb[t] == r.movement),
        "learned_called_novel": _share(learned, lambda r, t: r.novelty[t] == "novel"),
        "novel_delay_steps": delays,
        "novel_within_3_cycles": float(np.mean([d is not None and d <= 3 * PERIOD for d in delays]))
        if delays
        else float("nan"),
        "novel_after_detection": float(np.mean([novel_after(r) for r in after]))
        if after
        else float("nan"),
        "novel_recognised_as_learned": _share(
            by_kind["novel"], lambda r, t: r.recognised[t] is not None
        ),
        "unstructured_called_novel": _share(
            by_kind["unstructured"], lambda r, t: r.novelty[t] == "novel"
        ),
        "still_called_still": _share(by_kind["still"], lambda r, t: r.novelty[t] == "still"),
        "roc": roc,
        "roc_auc": auc,
    }


TARGETS = {
    "learned_recognised": (">=", 0.98),
    "learned_called_novel": ("<=", 0.02),
    "novel_within_3_cycles": (">=", 0.95),
    "novel_after_detection": (">=", 0.80),
    "unstructured_called_novel": ("<=", 0.10),
    "still_called_still": (">=", 0.90),
}


def judge(measures: dict[str, Any]) -> dict[str, Target]:
    out = {}
    for key, (how, limit) in TARGETS.items():
        value = measures[key]
        met = bool(value >= limit) if how == ">=" else bool(value <= limit)
        out[key] = Target(met, f"{100 * value:.1f} % ({how} {100 * limit:.0f} %)")
    return out


def run(out: Path, options: StudyOptions) -> StudyOutcome:
    from rnnpb import _xla
    from rnnpb.analysis.figures import plot_confusion, plot_delays, plot_roc
    from rnnpb.demonstrator import NEW_SHAPES

    _xla.configure()
    started = time.perf_counter()
    out = Path(out)
    (out / "figures").mkdir(parents=True, exist_ok=True)
    models = _models(out, options.quick)
    draws = 1 if options.quick else 2
    steps = 72 if options.quick else 84
    shapes = tuple(NEW_SHAPES[:2] if options.quick else NEW_SHAPES)
    seeds = [options.seed + 1000 + i for i in range(draws)]  # not the draws tuned on (0, 1)
    runs: list[StreamRun] = []
    alone: list[StreamRun] = []
    settings: dict[str, dict[str, Any]] = {}
    with study_pool(min(options.workers, len(models))) as pool:
        jobs = [
            pool.submit(_model_job, name, str(path), seeds, steps, shapes)
            for name, path in models.items()
        ]
        for job in jobs:
            name, chosen, model_runs, model_alone = job.result()
            settings[name] = chosen
            runs += model_runs
            alone += model_alone
    per_set = {name: measure([r for r in runs if r.model == name]) for name in models}
    presets = {
        preset: [r for r in runs if settings[r.model]["online_preset"] == preset]
        for preset in dict.fromkeys(s["online_preset"] for s in settings.values())
    }
    per_preset = {preset: measure(rs) for preset, rs in presets.items()}
    overall = measure(runs)
    without_taught = {name: measure([r for r in alone if r.model == name]) for name in models}
    without_taught["all"] = measure(alone)
    targets = judge(overall)
    for preset, m in per_preset.items():
        if len(presets) > 1:
            targets |= {f"{preset}: {k}": t for k, t in judge(m).items()}
    plot_confusion(
        {n: m["confusion"] for n, m in per_set.items()}, out / "figures" / "confusion.png"
    )
    plot_delays(
        {n: [d for d in m["novel_delay_steps"]] for n, m in per_set.items()},
        out / "figures" / "delays.png",
        period=PERIOD,
    )
    plot_roc({n: m["roc"] for n, m in per_set.items()}, out / "figures" / "roc.png")
    report = _report(
        per_set, overall, targets, options, seeds, settings, per_preset, without_taught
    )
    results = {
        "study": NAME,
        "quick": options.quick,
        "seeds": seeds,
        "config": {
            "models": settings,
            "steps": steps,
            "settle_steps": SETTLE_STEPS,
            "lead_steps": LEAD_STEPS,
        },
        "models": {n: str(path) for n, path in models.items()},
        "per_set": per_set,
        "per_preset": per_preset,
        "overall": overall,
        "without_taught_hands": {
            name: {key: m[key] for key in TARGETS} for name, m in without_taught.items()
        },
        "targets": {k: t.to_json() for k, t in targets.items()},
        "versions": versions(),
    }
    write_outputs(out, report, results)
    return StudyOutcome(runtime_s=time.perf_counter() - started, targets=targets)


def _report(
    per_set: dict[str, dict[str, Any]],
    overall: dict[str, Any],
    targets: dict[str, Target],
    options: StudyOptions,
    seeds: list[int],
    settings: dict[str, dict[str, Any]],
    per_preset: dict[str, dict[str, Any]],
    without_taught: dict[str, dict[str, Any]],
) -> list[str]:
    lines = [
        "# Study: novelty — does the robot know what it sees?",
        "",
        f"{'Quick form' if options.quick else 'Full form'}; draws of the user (scenario "
        f"seeds) {seeds}, none of them the draws the detector's settings were chosen on. "
        f"Steps judged: from {SETTLE_STEPS} steps after a movement starts. Each model runs "
        "with the on-line regression and recognition settings chosen for its learning "
        "(`OnlineConfig.for_model`): "
        + ", ".join(f"{n}: {s['online_preset']}" for n, s in settings.items())
        + ". Targets over all models, then per regression preset.",
        "",
        "## Targets",
        "",
    ]
    lines += table(
        ["target", "met", "measured"],
        [[k, "yes" if t.met else "NO", t.detail] for k, t in targets.items()],
    )
    lines += ["", "## Per learning set", ""]
    rows = []
    for name, m in per_set.items():
        delays = [d for d in m["novel_delay_steps"] if d is not None]
        rows.append(
            [
                name,
                fmt(100 * m["learned_recognised"]),
                fmt(100 * m["learned_nearest_pb"]),
                fmt(100 * m["learned_called_novel"]),
                fmt(100 * m["novel_within_3_cycles"]),
                fmt(float(np.median(delays))) if delays else "never",
                fmt(100 * m["novel_after_detection"]),
                fmt(100 * m["unstructured_called_novel"]),
                fmt(100 * m["still_called_still"]),
                f"{m['roc_auc']:.3f}",
            ]
        )
    lines += table(
        [
            "set",
            "learned recognised %",
            "nearest PB right %",
            "learned novel %",
            "novel within 3 cycles %",
            "median delay (steps)",
            "novel after detection %",
            "unstructured novel %",
            "still %",
            "ROC AUC",
        ],
        rows,
    )
    lines += ["", "## What the hands as taught add", ""]
    lines += [
        "The same evidence replayed through the detector without the third term (the hands "
        'as taught; docs/model.md, "Recognition and novelty"): the network\'s evidence, the '
        "PB and the structure test alone, as before models kept their taught hands. A model "
        "without them (a file of format 1 or 2) runs this way; "
        + (
            "every model here kept them."
            if all(s["taught_hands"] for s in settings.values())
            else "here: " + ", ".join(n for n, s in settings.items() if not s["taught_hands"]) + "."
        ),
        "",
    ]
    lines += table(
        ["models", *TARGETS],
        [
            [
                f"{name}{suffix}",
                *[fmt(100 * m[key]) for key in TARGETS],
            ]
            for name in [*per_set, "all"]
            for suffix, m in (
                ("", overall if name == "all" else per_set[name]),
                (" without", without_taught[name]),
            )
        ],
    )
    lines += ["", "## Confidence", ""]
    lines += [
        "Mean confidence of the recognised pattern on learned patterns' judged steps, where "
        "it was right and where it was wrong (a meaningful confidence is lower when wrong):",
        "",
    ]
    lines += table(
        ["models", "when right", "when wrong", "wrong steps"],
        [
            [
                name,
                fmt(m["confidence_right"]),
                fmt(m["confidence_wrong"]),
                str(m["wrong_steps"]),
            ]
            for name, m in [*per_preset.items(), ("all", overall)]
        ],
    )
    lines += ["", "## Confusion of the four states (all sets)", ""]
    lines += table(
        ["truth \\ said", *[s or "undecided" for s in STATES]],
        [[kind, *row.values()] for kind, row in overall["confusion"].items()],
    )
    lines += [
        "",
        embed("confusion matrices", "confusion.png"),
        embed("detection delays", "delays.png"),
        embed("ROC", "roc.png"),
        "",
    ]
    return lines
