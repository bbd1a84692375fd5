"""A random search of the recognition settings over recorded evidence, on development draws.

The mirror system runs the novelty study's generated streams of the user
(:func:`rnnpb.experiments.scenarios.novelty.model_job`: each learned pattern held, a learned
pattern then a novel movement, unstructured movement, the hands held still) once per model and
draw, recording every step's evidence. The detector is then replayed over that evidence
(:func:`~rnnpb.experiments.scenarios.novelty.replay`; the regression does not depend on the
detector's settings) with the preset's current values and with ``--trials`` random candidates,
each a ``RecognitionConfig.with_tuning(...)`` of the values the preset's evidence names as
searched (the keys whose source is the section's search: ``recognition-search``, with
``-untaught`` and ``-fast`` as the preset files name it).

Objective: the novelty study's measures (:func:`~rnnpb.experiments.scenarios.novelty.measure`)
over every run, judged by the novelty exam's target definitions (the definitions only, never
its draws). A candidate's score is the number of the exam's targets met (learned patterns
recognised, learned not called novel, novel called novel within three cycles and after, new
shapes at half and twice the speed called novel, unstructured not called novel, still called
still, a stop called still) plus the mean of those shares, each
turned so that higher is better (a share below 1 breaks ties between candidates meeting the
same targets). The values picked (``--pick best``: the best-scored trial; ``median``: each
value's median over the trials meeting every target) are printed against the current values.

Draws: ``--draws`` are user draws (scenario seeds) for development; one that is any study's
exam draw is refused. Models: ``--models DIR``, else the novelty study's own, learned with
seed 0 into ``OUT/models`` (the fast preset's in a minute or two; the paper preset's with the
paper's algorithm, slow: 50,000 iterations a model).

Writes ``OUT/search.json`` (every trial's values and measures, the current values' score, the
draws, the preset and the command line) and ``OUT/preset_fragment.toml`` (the values picked as
the preset's section and an evidence ``[sources.<id>]`` entry, to paste into a preset file; no
preset file is changed)::

    python tools/search_recognition.py --preset fast --draws 0,1 --trials 40 --out results/search
"""

from __future__ import annotations

import argparse
import json
import math
import shlex
import sys
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

SECTIONS = ("recognition", "recognition_untaught")
DEFAULT_DRAWS = (0, 1)  # the novelty exam's excluded development draws (settings chosen there)
DEFAULT_TRIALS = 30  # a few minutes on one core with the fast preset's models
#: Whether a larger measure is better, by the target's comparison with its limit.
HIGHER_IS_BETTER = {">=": True, "<=": False}


class SearchError(Exception):
    """A problem with the command's input, reported as one line."""


def exam_draws() -> dict[int, str]:
    """Every draw any study's exam runs on, with the study it belongs to."""
    from rnnpb.experiments.exams import exam_names, load_exam

    draws: dict[int, str] = {}
    for name in exam_names():
        for draw in load_exam(name).draws():
            draws.setdefault(draw, name)
    return draws


def check_draws(draws: Sequence[int]) -> None:
    """Refuse a draw that is an exam's: settings are chosen on development draws only."""
    exams = exam_draws()
    taken = [d for d in draws if d in exams]
    if taken:
        which = ", ".join(f"{d} ({exams[d]})" for d in taken)
        raise SearchError(
            f"draw(s) {which} belong to a study's exam; choose on development draws only"
        )
    if not draws or min(draws) < 0:
        raise SearchError("--draws must list one or more seeds >= 0")


def find_models(
    preset: str, directory: str | None, out: Path, sets: Sequence[str]
) -> dict[str, tuple[str, Path]]:
    """The novelty study's models of ``preset``: name -> (learning set, file).

    ``directory``: the paper preset's as ``rnnpb demo`` writes them, the fast preset's as the
    novelty study keeps them (``fast_set1.npz``, ``fast_full.npz``); None: the study's own,
    learned into ``out/models`` if absent."""
    from rnnpb.experiments.scenarios.novelty import (
        FULL_MODELS,
        QUICK_MODELS,
        model_file,
        study_models,
    )

    fast = preset == "fast"
    if directory is not None and fast:
        wanted = {n: s for n, (s, _) in QUICK_MODELS.items() if not sets or s in sets}
        models = {n: (s, Path(directory) / model_file(n)) for n, s in wanted.items()}
        missing = [str(p) for _, p in models.values() if not p.is_file()]
        if missing:
            raise SearchError(
                f"--models has no {', '.join(missing)} (the novelty study's fast models)"
            )
        return models
    models = study_models(out, directory, fast, learning_sets=tuple(sets))
    if directory is None:  # the study's own: those learned with this preset
        models = {n: v for n, v in models.items() if FULL_MODELS[n][1] == fast}
    if not models:
        raise SearchError(f"no {preset} model of learning sets {', '.join(sets)}")
    return models


def record(
    models: Mapping[str, tuple[str, Path]],
    preset: str,
    draws: Sequence[int],
    steps: int,
    shapes: Sequence[str],
) -> list[tuple[Any, list[Any]]]:
    """Each model with its recorded stream runs on ``draws``."""
    from rnnpb.experiments.scenarios.novelty import model_job
    from rnnpb.model import OnlineConfig, TrainedModel
    from rnnpb.robot import JOINT_LIMITS

    recorded = []
    for name, (set_name, path) in models.items():
        model = TrainedModel.load(path, joint_limits=JOINT_LIMITS)
        learned = OnlineConfig.for_model(model).recognition.tuning.preset
        if learned != preset:
            raise SearchError(f"model {path} was learned with preset {learned!r}, not {preset!r}")
        _, _, runs, _ = model_job(name, set_name, str(path), list(draws), steps, tuple(shapes))
        recorded.append((model, runs))
        print(f"recorded {name}: {len(runs)} streams", file=sys.stderr, flush=True)
    return recorded


def source_id(preset: str, section: str) -> str:
    """The preset's source for the values a search chose in ``section``, as the preset files
    name it (``recognition-search``, ``-untaught`` for the untaught section, ``-fast`` for the
    fast preset)."""
    untaught = "-untaught" if section == "recognition_untaught" else ""
    return f"recognition-search{untaught}{'-fast' if preset == 'fast' else ''}"


def searched_keys(preset: str, section: str) -> tuple[str, ...]:
    """The section's values the preset's evidence names as chosen by this section's search."""
    from rnnpb.presets import load_preset

    loaded = load_preset(preset)
    wanted = source_id(preset, section)
    keys = tuple(k for k in loaded.section(section) if loaded.evidence(section, k).id == wanted)
    if not keys:
        raise SearchError(f"preset {preset}'s [{section}] names no value chosen by {wanted}")
    return keys


def candidate(rng: np.random.Generator, current: Mapping[str, Any], keys: Sequence[str]) -> dict:
    """Random values of ``keys`` around ``current``: a scale or level log-uniformly within a
    factor of 2, a confidence level uniformly in [0.3, 0.9], a count of steps uniformly from
    half to twice the current count (at least the current count ± 3)."""
    values: dict[str, Any] = {}
    for key in keys:
        value = current[key]
        if key == "confidence_level":
            values[key] = round(float(rng.uniform(0.3, 0.9)), 3)
        elif isinstance(value, bool) or not isinstance(value, int | float):
            continue
        elif isinstance(value, int):
            low, high = max(1, min(value // 2, value - 3)), max(2 * value, value + 3)
            values[key] = int(rng.integers(low, high + 1))
        else:
            values[key] = float(f"{value * 2 ** rng.uniform(-1, 1):.3g}")
    return values


def score(
    recorded: Sequence[tuple[Any, list[Any]]], config: Any, use_taught: bool
) -> dict[str, Any]:
    """The detector with ``config`` replayed over every recorded run: the measures of the
    novelty study's targets, which are met, and the score (see the module)."""
    from rnnpb.experiments.exams import load_exam
    from rnnpb.experiments.scenarios.novelty import measure, replay

    exam = load_exam("novelty")
    settle = int(exam.parameter("settle_steps"))
    within = int(exam.target("novel_within_3_cycles").parameter("steps"))
    runs = [replay(r, model, config, use_taught=use_taught) for model, rs in recorded for r in rs]
    measured = measure(runs, settle, within)
    values = {key: measured[key] for key in exam.targets}
    met = exam.judge(values)
    turned = [v if HIGHER_IS_BETTER[exam.targets[k].compare] else 1 - v for k, v in values.items()]
    mean = float(np.mean([v if math.isfinite(v) else 0.0 for v in turned]))
    return {
        "score": sum(met.values()) + mean,
        "met": sum(met.values()),
        "of": len(met),
        "measures": values,
    }


def search(
    recorded: Sequence[tuple[Any, list[Any]]],
    preset: str,
    section: str,
    trials: int,
    seed: int,
) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The current values' result and each trial's (values, measures, score): each trial
    draws every searched value at once (:func:`candidate`), seeded by ``seed``."""
    from rnnpb.model.recognition import RecognitionConfig

    use_taught = section == "recognition"
    base = RecognitionConfig.from_preset(preset, section)
    keys = searched_keys(preset, section)
    current = {key: base.tuning[key] for key in keys}
    baseline = {"values": current, **score(recorded, base, use_taught)}
    rng = np.random.default_rng(seed)
    results = []
    for trial in range(trials):
        values = candidate(rng, base.tuning, keys)
        result = score(recorded, base.with_tuning(**values), use_taught)
        results.append({"trial": trial, "values": values, **result})
        if (trial + 1) % 10 == 0 or trial + 1 == trials:
            print(f"trial {trial + 1} of {trials}", file=sys.stderr, flush=True)
    return baseline, results


def median_of_passing(
    recorded: Sequence[tuple[Any, list[Any]]],
    preset: str,
    section: str,
    trials: Sequence[Mapping[str, Any]],
) -> dict[str, Any] | None:
    """Each searched value's median over the trials that met every target (a count of steps
    rounded), scored like a trial; None when no trial met every target."""
    from rnnpb.model.recognition import RecognitionConfig

    passing = [t for t in trials if t["met"] == t["of"]]
    if not passing:
        return None
    values: dict[str, Any] = {}
    for key, first in passing[0]["values"].items():
        middle = float(np.median([t["values"][key] for t in passing]))
        values[key] = int(round(middle)) if isinstance(first, int) else float(f"{middle:.3g}")
    config = RecognitionConfig.from_preset(preset, section).with_tuning(**values)
    result = score(recorded, config, section == "recognition")
    return {"trial": "median", "passing": len(passing), "values": values, **result}


def fragment(
    section: str,
    values: Mapping[str, Any],
    source: str,
    command: str,
    draws: Sequence[int],
    result: Mapping[str, Any],
    trials: int,
    about: str = "",
) -> str:
    """The chosen values as the preset's section and their evidence, in the preset files'
    form."""
    lines = [f"[{section}]", *(f"{k} = {_toml(v)}" for k, v in values.items()), ""]
    met = f"met {result['met']} of {result['of']} novelty targets on the chosen draws"
    if "passing" in result:
        figure = (
            f"{result['passing']} of {trials} random settings met every novelty target; each "
            f"value is the median over them, which {met} (score {result['score']:.4f})"
        )
    else:
        figure = f"the best of {trials} random settings {met} (score {result['score']:.4f})"
    note = (
        "random search over recorded evidence replayed by "
        "rnnpb.experiments.scenarios.novelty.replay (tools/search_recognition.py)"
        + (f", {about}" if about else "")
    )
    lines += [
        f"[sources.{source}]",
        # A seeded search repeats its trials: the command reproduces the figure.
        'kind = "measured"',
        f"command = {_toml(command)}",
        f"draws = {_toml(list(draws))}",
        f"figure = {_toml(figure)}",
        f"note = {_toml(note)}",
        "",
    ]
    return "\n".join(lines)


def _toml(value: Any) -> str:
    if isinstance(value, str):
        return json.dumps(value)  # a TOML basic string is JSON's
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return repr(value)


def _draws(text: str) -> tuple[int, ...]:
    try:
        return tuple(int(d) for d in text.split(",") if d.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a list of whole numbers: {text!r}") from None


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        description="Random search of the recognition settings over recorded evidence, "
        "scored by the novelty study's targets, on development draws."
    )
    p.add_argument("--preset", choices=("paper", "fast"), default="fast")
    p.add_argument(
        "--section",
        choices=SECTIONS,
        default="recognition",
        help="the settings for models with the hands as taught, or without (untaught)",
    )
    p.add_argument("--models", help="models folder (default: learn the study's into OUT/models)")
    p.add_argument("--draws", type=_draws, default=DEFAULT_DRAWS, help="user draws, e.g. 0,1")
    p.add_argument("--sets", default="", help="learning sets, e.g. 1,full (default: all)")
    p.add_argument("--trials", type=int, default=DEFAULT_TRIALS)
    p.add_argument("--seed", type=int, default=0, help="the search's random seed")
    p.add_argument(
        "--pick",
        choices=("best", "median"),
        default="best",
        help="the values written: the best-scored trial, or each value's median over the "
        "trials meeting every target (the best trial if none does)",
    )
    p.add_argument("--steps", type=int, default=72, help="steps of each stream (the quick study's)")
    p.add_argument(
        "--shapes", type=int, default=2, help="new shapes as novel movements (the quick study's 2)"
    )
    p.add_argument("--out", required=True, help="folder for search.json and preset_fragment.toml")
    return p


def main(argv: Sequence[str] | None = None) -> int:
    args = parser().parse_args(argv)
    command = shlex.join(
        ["python", "tools/search_recognition.py", *(sys.argv[1:] if argv is None else argv)]
    )
    from rnnpb.errors import ConfigError

    try:
        return _run(args, command)
    except (SearchError, ConfigError) as error:
        print(f"search_recognition: {error}", file=sys.stderr)
        return 2


def _run(args: argparse.Namespace, command: str) -> int:
    from rnnpb import _xla
    from rnnpb.demonstrator import NEW_SHAPES
    from rnnpb.presets import load_preset

    check_draws(args.draws)
    if args.trials < 1:
        raise SearchError("--trials must be >= 1")
    _xla.configure()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    sets = tuple(s.strip() for s in args.sets.split(",") if s.strip())
    models = find_models(args.preset, args.models, out, sets)
    shapes = tuple(NEW_SHAPES[: args.shapes])
    recorded = record(models, args.preset, args.draws, args.steps, shapes)
    recorded_s = time.perf_counter() - started
    baseline, trials = search(recorded, args.preset, args.section, args.trials, args.seed)
    best = max(trials, key=lambda t: t["score"])  # the first of equal scores
    chosen = best
    if args.pick == "median":
        chosen = median_of_passing(recorded, args.preset, args.section, trials) or best
    preset = load_preset(args.preset)
    source = source_id(args.preset, args.section)
    results = {
        "command": command,
        "preset": {"name": preset.name, "version": preset.version},
        "section": args.section,
        "draws": list(args.draws),
        "models": {name: str(path) for name, (_, path) in models.items()},
        "steps": args.steps,
        "shapes": list(shapes),
        "seed": args.seed,
        "objective": "targets met + mean of the exam's target shares turned higher-is-better",
        "current": baseline,
        "pick": args.pick,
        "best": best,
        "chosen": chosen,
        "trials": trials,
        "runtime_s": {"record": recorded_s, "total": time.perf_counter() - started},
    }
    (out / "search.json").write_text(json.dumps(results, indent=1) + "\n", encoding="utf-8")
    about = f"preset {preset.name} version {preset.version}, models {', '.join(models)}"
    if args.pick == "median" and chosen is best:
        print("no trial met every target: the best trial is written", file=sys.stderr)
    text = fragment(
        args.section, chosen["values"], source, command, args.draws, chosen, args.trials, about
    )
    (out / "preset_fragment.toml").write_text(text, encoding="utf-8")
    print(report(baseline, chosen, args, preset.version, len(trials)))
    print(f"wrote {out / 'search.json'} and {out / 'preset_fragment.toml'}")
    return 0


def report(baseline: Mapping, best: Mapping, args: argparse.Namespace, version: int, n: int) -> str:
    """The chosen candidate (``best``: the best trial or the median) against the current
    values, one line each, and every value."""
    keys = list(baseline["measures"])
    width = max(len(k) for k in keys)
    lines = [
        f"preset {args.preset} v{version} [{args.section}], draws {list(args.draws)}, "
        f"{n} trials (seed {args.seed})",
        f"{'':{width}}  {'current':>9}  {args.pick:>9}",
        *(f"{k:{width}}  {baseline['measures'][k]:9.4f}  {best['measures'][k]:9.4f}" for k in keys),
        f"{'targets met':{width}}  {baseline['met']:>9}  {best['met']:>9}",
        f"{'score':{width}}  {baseline['score']:9.4f}  {best['score']:9.4f}",
        "the search "
        + ("beats" if best["score"] > baseline["score"] else "does not beat")
        + " the current values on these draws",
        f"values (current -> {args.pick}): "
        + ", ".join(f"{k} {baseline['values'][k]} -> {v}" for k, v in best["values"].items()),
    ]
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
