"""The novelty study's scenarios and measures (``rnnpb study novelty``): generated streams of
the user through the mirror system, and what its novelty states and recognition got right.

For each model the streams are: each learned pattern held; a learned pattern, then a novel
structured movement (the left-out pattern, new shapes of
:data:`rnnpb.demonstrator.NEW_SHAPES`); each new shape at half and at twice the usual speed
(``novel-slow``, ``novel-fast``: the user performs the whole stream at that speed, the learned
pattern before it too); unstructured movement (:data:`rnnpb.demonstrator.UNSTRUCTURED`, twice
as long: long enough for the detector to decide); the hands held still; the hands stopping
after a learned pattern, a new shape (also at half speed) and unstructured movement
(``stopped``). Every step's novelty state is compared with the truth: the confusion matrix of
the states, the delay until a novel movement is called ``novel``, a ROC curve of the novelty
score (the best learned pattern's RMS error), the recognition accuracy on learned patterns
(with the nearest-learned-PB rule for comparison).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb.experiments.scenarios import study_models as shared

STATES = ("familiar", "novel", "unstructured", "still", "")
LEAD_STEPS = 36  # a learned pattern before each novel movement (three cycles)
PERIOD = 12  # the demonstrator's period, steps (PatternConfig.period_steps)
SPEEDS = {"novel-slow": 0.5, "novel-fast": 2.0}  # the new shapes' other speeds, by stream kind
STOP_STEPS = 36  # the hands held still after a movement stops
STILL_GRACE_STEPS = 5  # the first steps of a stop not judged: the hands are still coming to rest


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
    speed: float = 1.0  # the user's speed, a multiple of the demonstrator's (period PERIOD / speed)


def streams(
    patterns: tuple[str, ...], novel: tuple[str, ...], seed: int, steps: int
) -> list[tuple[str, str, int, list[tuple[str, int]], float]]:
    """The streams of one draw, each ``(kind, movement, start, segments, speed)``: ``start``
    is the first step of the judged movement, ``segments`` what the user performs, at
    ``speed`` times the demonstrator's speed."""
    from rnnpb.demonstrator import NEW_SHAPES, PAUSE, UNSTRUCTURED

    out = [("learned", p, 0, [(p, steps)], 1.0) for p in patterns]
    for i, movement in enumerate(novel):
        lead = patterns[(seed + i) % len(patterns)]
        out.append(("novel", movement, LEAD_STEPS, [(lead, LEAD_STEPS), (movement, steps)], 1.0))
    for kind, speed in SPEEDS.items():
        # At half speed the stream is twice as long: the same number of the shape's cycles.
        length = round(steps * max(1.0, 1.0 / speed))
        for i, movement in enumerate(m for m in novel if m in NEW_SHAPES):
            lead = patterns[(seed + i) % len(patterns)]
            segments = [(lead, LEAD_STEPS), (movement, length)]
            out.append((kind, movement, LEAD_STEPS, segments, speed))
    # Unstructured movement twice as long: it is undecided until the longest period the
    # detector looks for could have repeated (80 steps), then unstructured.
    out += [("unstructured", m, 0, [(m, 2 * steps)], 1.0) for m in UNSTRUCTURED]
    out.append(("still", PAUSE, 0, [(PAUSE, steps)], 1.0))
    shapes = [m for m in novel if m in NEW_SHAPES] or list(novel)
    before = [patterns[seed % len(patterns)], *shapes[seed % len(shapes) :][:1], UNSTRUCTURED[0]]
    for movement in before:
        out.append(
            ("stopped", movement, LEAD_STEPS, [(movement, LEAD_STEPS), (PAUSE, STOP_STEPS)], 1.0)
        )
    # A slow new shape stops too, after three of its cycles: its turning points are not stops,
    # a stop still is.
    slow = 3 * round(PERIOD / SPEEDS["novel-slow"])
    shape = before[1]
    out.append(("stopped", shape, slow, [(shape, slow), (PAUSE, STOP_STEPS)], SPEEDS["novel-slow"]))
    return out


def run_streams_of(
    model: Any,
    config: Any,
    recognition: Any,
    model_name: str,
    cases: list[tuple[str, str, int, int, list[tuple[str, int]], float]],
) -> list[StreamRun]:
    """Every stream of ``cases`` (``(kind, movement, seed, start, segments, speed)``) from a
    fresh start of ``model``'s mirror system, in order, stepped by
    :func:`rnnpb.experiments.paper.step_streams` (together in one batched call when they hold
    enough steps to pay for it)."""
    from rnnpb.experiments.paper import step_streams

    scenarios = [_scenario(segments, seed, speed) for _, _, seed, _, segments, speed in cases]
    results = step_streams(model, [s.sensory for s in scenarios], config, recognition=recognition)
    return [
        _stream_run(model, model_name, (kind, movement, seed, start, speed), scenario, steps)
        for (kind, movement, seed, start, _, speed), scenario, steps in zip(
            cases, scenarios, results, strict=True
        )
    ]


def _scenario(segments: list[tuple[str, int]], seed: int, speed: float):
    from rnnpb.demonstrator import PatternConfig, make_scenario

    return make_scenario(segments, seed=seed, config=PatternConfig(period_steps=PERIOD / speed))


def _stream_run(
    model: Any,
    model_name: str,
    case: tuple[str, str, int, int, float],
    scenario: Any,
    results: list[Any],
) -> StreamRun:
    kind, movement, seed, start, speed = case
    score = []
    for result in results:
        errors = result.pattern_errors
        score.append(float(np.sqrt(np.min(errors))) if np.all(np.isfinite(errors)) else np.nan)
    return StreamRun(
        model_name,
        kind,
        movement,
        seed,
        start,
        tuple(r.novelty for r in results),
        tuple(r.recognised for r in results),
        tuple(model.nearest_pattern(r.pb)[0] for r in results),
        np.array(score),
        scenario.sensory.copy(),
        np.array([r.pattern_errors for r in results]),
        np.array([r.pb for r in results]),
        tuple(r.confidence for r in results),
        speed,
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


def study_models(
    out: Path,
    directory: str | None,
    quick: bool,
    seed: int = 0,
    learning_sets: tuple[str, ...] = (),
) -> dict[str, tuple[str, Path]]:
    """The study's models by name, each (its learning set, its file).

    ``directory``: the models of learning sets 1-4 and the larger set (the quick form: 1 and
    the larger set) as ``rnnpb demo`` writes them (``setK.npz``, ``full.npz`` or
    ``full_seed0.npz``), named by their learning set; a missing one is a clear error. None: the
    study's own (:data:`FULL_MODELS`, quick :data:`QUICK_MODELS`), their files in
    ``out/models``, learned there if absent (demonstrations and weights of ``seed``).
    ``learning_sets``: only those (empty: all).
    """
    from rnnpb.model import TrainConfig

    wanted = QUICK_MODELS if quick else FULL_MODELS
    if learning_sets:
        wanted = {n: v for n, v in wanted.items() if v[0] in learning_sets}

    def learning(name: str) -> TrainConfig:
        return TrainConfig.fast(seed=seed) if wanted[name][1] else TrainConfig(seed=seed)

    folder = out / "models"
    if directory is not None:
        sets = tuple(dict.fromkeys(set_name for set_name, _ in wanted.values()))
        found = shared.study_models(sets, directory, folder, learning)
        return {set_name: (set_name, Path(path)) for set_name, path in found.items()}
    models = {name: set_name for name, (set_name, _) in wanted.items()}
    learned = shared.study_models(
        models, None, folder, learning, seed, file_name=model_file, reuse=True
    )
    return {name: (models[name], Path(path)) for name, path in learned.items()}


def model_job(
    name: str, set_name: str, path: str, seeds: list[int], steps: int, shapes: tuple[str, ...]
) -> tuple[str, dict[str, Any], list[StreamRun], list[StreamRun]]:
    """Every stream of one model: its on-line regression and recognition settings chosen as
    ``OnlineConfig.for_model`` chooses them for the model's learning (as the dashboard and
    ``rnnpb interact`` do)."""
    from dataclasses import replace

    from rnnpb.demonstrator import learning_set_patterns, novel_pattern
    from rnnpb.model import OnlineConfig, TrainedModel
    from rnnpb.robot import JOINT_LIMITS

    model = TrainedModel.load(path, joint_limits=JOINT_LIMITS)
    choice = OnlineConfig.for_model(model)
    patterns = learning_set_patterns(set_name)
    novel = ((novel_pattern(set_name),) if set_name != "full" else ()) + tuple(shapes)
    cases = [
        (kind, movement, seed, start, segments, speed)
        for seed in seeds
        for kind, movement, start, segments, speed in streams(patterns, novel, seed, steps)
    ]
    runs = run_streams_of(model, choice.config, choice.recognition, name, cases)
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


def _judged(run: StreamRun, settle_steps: int, grace_steps: int = STILL_GRACE_STEPS) -> range:
    """The steps judged: of a stop, after its first ``grace_steps``; of a movement, from
    ``settle_steps`` after it starts — at a slower speed, as many more as the same cycles
    take."""
    if run.kind == "stopped":
        return range(run.start + grace_steps, len(run.novelty))
    return range(run.start + round(settle_steps * max(1.0, 1.0 / run.speed)), len(run.novelty))


def _share(
    runs: list[StreamRun], test, settle_steps: int, grace_steps: int = STILL_GRACE_STEPS
) -> float:
    hits = [test(run, t) for run in runs for t in _judged(run, settle_steps, grace_steps)]
    return float(np.mean(hits)) if hits else float("nan")


def _delay(run: StreamRun) -> int | None:
    for t in range(run.start, len(run.novelty)):
        if run.novelty[t] == "novel":
            return t - run.start
    return None


def measure(
    runs: list[StreamRun],
    settle_steps: int,
    novel_steps: int,
    grace_steps: int = STILL_GRACE_STEPS,
) -> dict[str, Any]:
    """Every measure of the study from its runs: steps are judged from ``settle_steps`` after
    a movement starts (:func:`_judged`), and from ``grace_steps`` after the hands stop; a
    novel movement counts as detected in time when called novel within ``novel_steps`` of its
    start."""
    kinds = ("learned", "novel", *SPEEDS, "unstructured", "still", "stopped")
    by_kind = {k: [r for r in runs if r.kind == k] for k in kinds}
    confusion = {
        kind: {
            state or "undecided": int(
                sum(
                    run.novelty[t] == state
                    for run in rs
                    for t in _judged(run, settle_steps, grace_steps)
                )
            )
            for state in STATES
        }
        for kind, rs in by_kind.items()
        if rs or kind in ("learned", "novel", "unstructured", "still")
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

    positives = np.concatenate(
        [r.score[list(_judged(r, settle_steps))] for r in by_kind["novel"]] or [[]]
    )
    negatives = np.concatenate([r.score[list(_judged(r, settle_steps))] for r in learned] or [[]])
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
        for t in _judged(r, settle_steps):
            if r.recognised[t] is not None and r.novelty[t] == "familiar":
                (right if r.recognised[t] == r.movement else wrong).append(r.confidence[t])
    return {
        "confusion": confusion,
        "confidence_right": float(np.mean(right)) if right else float("nan"),
        "confidence_wrong": float(np.mean(wrong)) if wrong else float("nan"),
        "wrong_steps": len(wrong),
        "learned_recognised": _share(
            learned, lambda r, t: r.recognised[t] == r.movement, settle_steps
        ),
        "learned_nearest_pb": _share(
            learned, lambda r, t: r.nearest_pb[t] == r.movement, settle_steps
        ),
        "learned_called_novel": _share(learned, lambda r, t: r.novelty[t] == "novel", settle_steps),
        "novel_delay_steps": delays,
        "novel_within_3_cycles": float(
            np.mean([d is not None and d <= novel_steps for d in delays])
        )
        if delays
        else float("nan"),
        "novel_after_detection": float(np.mean([novel_after(r) for r in after]))
        if after
        else float("nan"),
        "novel_recognised_as_learned": _share(
            by_kind["novel"], lambda r, t: r.recognised[t] is not None, settle_steps
        ),
        "unstructured_called_novel": _share(
            by_kind["unstructured"], lambda r, t: r.novelty[t] == "novel", settle_steps
        ),
        "still_called_still": _share(
            by_kind["still"], lambda r, t: r.novelty[t] == "still", settle_steps
        ),
        "novel_slow_called_novel": _share(
            by_kind["novel-slow"], lambda r, t: r.novelty[t] == "novel", settle_steps
        ),
        "novel_fast_called_novel": _share(
            by_kind["novel-fast"], lambda r, t: r.novelty[t] == "novel", settle_steps
        ),
        "stopped_called_still": _share(
            by_kind["stopped"], lambda r, t: r.novelty[t] == "still", settle_steps, grace_steps
        ),
        "roc": roc,
        "roc_auc": auc,
    }
