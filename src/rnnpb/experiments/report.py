"""Run every experiment of the paper's section 3 and write ``report.md`` and ``results.json``.

The jobs (one per trained model) run in ``workers`` processes; every job is seeded, so a run
repeats. Outputs under the chosen directory::

    data/            the learning sets as sequence CSVs (set1/ … set4/, full/)
    models/          every trained model (setK.npz, full_seedN.npz)
    figures/         the figures the report embeds
    report.md        measure | paper | ours, with the figures
    results.json     every measure, the config, versions and which file is which
"""

from __future__ import annotations

import multiprocessing
import os
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from rnnpb import __version__
from rnnpb.analysis import metrics
from rnnpb.experiments.paper import (
    PAUSE_STEPS,
    SWITCH_STEPS_EACH,
    Attractor,
    ExperimentConfig,
    LargerSetRun,
    LearningSetResult,
    NovelResponse,
    larger_set_job,
    learning_set_job,
    sequence_file_name,
)
from rnnpb.experiments.reporting import (
    FIGURES_DIR,
    embed,
    fmt,
    median_and_worst,
    row,
    sci,
    table,
    versions,
    write_lines,
    write_outputs,
)
from rnnpb.experiments.summary import (
    STEP_TARGETS,
    DemoResults,
    Distribution,
    LearningSetFiles,
    OutputFiles,
    Summary,
    Target,
    distributions,
    draws_summary,
    flat,
    summarize,
    targets,
    within,
)
from rnnpb.model import OnlineConfig, TrainConfig

LEARNING_SETS = ("1", "2", "3", "4")


def _worker_init() -> None:
    # Each worker keeps to one core; the pool provides the parallelism.
    from rnnpb import _xla

    _xla.configure()  # the on-line step's loop setting, unless the caller chose otherwise
    _xla.single_threaded()


# A job of the demo: (key, function, arguments); a runner runs jobs and yields (key, result)
# as each ends. The command line runs them on Ray (rnnpb.sweeps.ray_runner); this default
# runs them in a local process pool.
Job = tuple[Any, Callable[..., Any], tuple[Any, ...]]
JobRunner = Callable[[Sequence[Job]], Iterator[tuple[Any, Any]]]


def process_pool_runner(workers: int) -> JobRunner:
    """Jobs in ``workers`` local processes, each keeping JAX to one core."""

    def run(jobs: Sequence[Job]) -> Iterator[tuple[Any, Any]]:
        context = multiprocessing.get_context("spawn")
        with ProcessPoolExecutor(
            max_workers=workers, mp_context=context, initializer=_worker_init
        ) as pool:
            futures = {pool.submit(function, *args): key for key, function, args in jobs}
            for future in as_completed(futures):
                yield futures[future], future.result()

    return run


@dataclass(frozen=True)
class DemoJobs:
    """What the demo's jobs returned: per training seed, every learning set's results with
    the default on-line regression (with the compared one inside); the larger-set runs."""

    by_seed: dict[int, dict[str, LearningSetResult]]
    larger: list[LargerSetRun]

    @property
    def default(self) -> dict[str, LearningSetResult]:
        """The first seed's: the networks the figures show."""
        return next(iter(self.by_seed.values()))

    @property
    def paper(self) -> dict[str, LearningSetResult]:
        return {k: r.compared("paper") for k, r in self.default.items() if r.compare is not None}


def model_name(set_name: str, seed: int, first: int) -> str:
    """``setK`` for the first training seed (the figures' networks), ``setK_seedS`` else."""
    return f"set{set_name}" if seed == first else f"set{set_name}_seed{seed}"


def run_jobs(
    out: Path, config: ExperimentConfig, log: Callable[[str], None], runner: JobRunner | None = None
) -> DemoJobs:
    """Every job of the demo: per learning set and training seed, the default's results and
    (with ``config.compare_paper``, for the first ``config.compare_seeds`` training seeds) the
    paper's regression's; the larger-set runs by seed."""
    models, data = out / "models", out / "data"
    models.mkdir(parents=True, exist_ok=True)
    runner = runner or process_pool_runner(config.workers)
    compare = config.paper_online if config.compare_paper else None
    first = config.training_seeds[0]
    compared_seeds = set(config.training_seeds[: config.compare_seeds])
    jobs: list[Job] = []
    for seed in config.training_seeds:
        for name in LEARNING_SETS:
            data_dir = None
            if seed == first:
                data_dir = data / f"set{name}"
                data_dir.mkdir(parents=True, exist_ok=True)
            train = replace(config.train, seed=seed)
            jobs.append(
                (
                    ("default", name, seed),
                    learning_set_job,
                    (
                        name,
                        train,
                        config.online,
                        config,
                        str(models / f"{model_name(name, seed, first)}.npz"),
                        None if data_dir is None else str(data_dir),
                        "default",
                        True,
                        compare if seed in compared_seeds else None,
                        seed != first,
                    ),
                )
            )
    # The larger set's seeds learn together, in as many groups as there are workers
    # (rnnpb.model.train_seeds), and start first: they are the longest jobs.
    seeds = tuple(range(config.larger_set_seeds))
    groups = [g for g in (seeds[i :: config.workers] for i in range(config.workers)) if g]
    larger_jobs: list[Job] = [
        (
            ("larger", group, None),
            larger_set_job,
            (
                group,
                config.larger_train,
                config.online,
                config,
                [str(models / f"full_seed{seed}.npz") for seed in group],
            ),
        )
        for group in groups
    ]
    jobs = larger_jobs + jobs
    by_seed: dict[int, dict[str, LearningSetResult]] = {s: {} for s in config.training_seeds}
    larger: list[LargerSetRun] = []
    for done, ((kind, key, seed), result) in enumerate(runner(jobs), start=1):
        if kind == "default":
            by_seed[seed][key] = result
            what = f"set {key}, training seed {seed}"
        else:
            larger.extend(result)
            what = f"larger set, seed{'s' if len(key) > 1 else ''} {', '.join(map(str, key))}"
        log(f"  [{done}/{len(jobs)}] {what} done")
    larger.sort(key=lambda r: r.seed)
    return DemoJobs({s: {k: v[k] for k in sorted(v)} for s, v in by_seed.items()}, larger)


# --- running the demo --------------------------------------------------------------------


def _shown_novel(
    novel_runs: Sequence[tuple[NovelResponse, dict[str, Attractor]]],
) -> list[tuple[NovelResponse, dict[str, Attractor]]]:
    """One example of each response case, as the paper shows, then others up to three."""
    shown: list[tuple[NovelResponse, dict[str, Attractor]]] = []
    for case in metrics.RESPONSE_CASES:
        for run, attractors in novel_runs:
            if run.case == case:
                shown.append((run, attractors))
                break
    for run, attractors in novel_runs:
        if len(shown) >= 3:
            break
        if all(run is not s for s, _ in shown):
            shown.append((run, attractors))
    return shown


def _draw_figures(
    figure_dir: Path, full: list, default: dict[str, LearningSetResult], config: ExperimentConfig
) -> None:
    from rnnpb.analysis import figures
    from rnnpb.robot import JOINT_LIMITS

    figures.plot_patterns(full, figure_dir / "figure4_patterns.png")
    set1 = default["1"]
    sync = set1.synchronization[0]
    figures.plot_session(
        sync.run.session(),
        figure_dir / "figure5_synchronization.png",
        title=f"Learning set 1: the user performs pattern {sync.pattern}, "
        f"pauses (shaded) and goes on",
        joint_limits=JOINT_LIMITS,
        marks=[(sync.steps_to_lock or 0, "locked")],
        pattern_pb=set1.pattern_pb,
    )
    sequence = set1.sequence
    session = sequence.run.session()
    switches = sequence.run.switch_steps
    figures.plot_session(
        session,
        figure_dir / "figure6_switching.png",
        title="Learning set 1: the user switches among the learned patterns",
        joint_limits=JOINT_LIMITS,
        marks=[(s, "switch") for s in switches],
        pattern_pb=set1.pattern_pb,
    )
    figures.plot_switch_zoom(
        session,
        [(s - 10, s + 30) for s in switches],
        figure_dir / "figure7_switching_zoom.png",
        JOINT_LIMITS,
        switches,
    )
    figures.plot_switch_matrix(
        {k: default[k].switching.pairs for k in sorted(default)},
        figure_dir / "switching_matrix.png",
        metrics.SWITCH_LIMIT,
    )
    novel_runs = [(run, default[k].attractors) for k in sorted(default) for run in default[k].novel]
    shown = _shown_novel(novel_runs)
    figures.plot_novel_responses(
        [r for r, _ in shown], figure_dir / "figure8_novel.png", JOINT_LIMITS
    )
    figures.plot_attractors(
        shown, figure_dir / "figure9_attractors.png", config.attractor_transient
    )
    histories = {f"set {k}": default[k].train_history for k in sorted(default)}
    figures.plot_training(histories, figure_dir / "training.png", metrics.TRAIN_ERROR_TARGET)


def run_demo(
    out_dir: str | os.PathLike[str],
    config: ExperimentConfig,
    log: Callable[[str], None] = print,
    runner: JobRunner | None = None,
) -> DemoResults:
    """Run everything (the jobs with ``runner``, default a local process pool); write the
    report, the results and the figures; return the results."""
    from rnnpb.demonstrator import learning_set
    from rnnpb.sequences import write_sequence

    start = time.perf_counter()
    out = Path(out_dir)
    figure_dir = out / FIGURES_DIR
    figure_dir.mkdir(parents=True, exist_ok=True)
    full_dir = out / "data" / "full"
    full = learning_set(
        "full", seed=config.data_seed, samples_per_pattern=config.samples_per_pattern
    )
    for seq in full:
        write_sequence(full_dir / sequence_file_name(seq), seq)
    log(
        f"training and running the experiments ({'quick' if config.quick else 'full'} run, "
        f"{config.workers} workers) …"
    )
    jobs = run_jobs(out, config, log, runner)
    default, larger, paper = jobs.default, jobs.larger, jobs.paper
    log("drawing the figures …")
    _draw_figures(figure_dir, full, default, config)

    ordered = {k: default[k] for k in sorted(default)}
    summary = summarize(default)
    novel = [run for r in ordered.values() for run in r.novel]
    paper_summary = summarize(paper) if paper else None
    scenario_seeds = (config.scenario_seed, *config.extra_scenario_seeds)
    first = config.training_seeds[0]
    files = OutputFiles(
        models={
            **{
                model_name(k, s, first): f"models/{model_name(k, s, first)}.npz"
                for s in config.training_seeds
                for k in ordered
            },
            **{f"full_seed{r.seed}": f"models/full_seed{r.seed}.npz" for r in larger},
        },
        learning_sets={
            **{
                f"set{k}": LearningSetFiles(r.patterns, f"data/set{k}/") for k, r in ordered.items()
            },
            "full": LearningSetFiles(["1", "2", "3", "4"], "data/full/"),
        },
        figures=sorted(p.name for p in figure_dir.glob("*.png")),
    )
    results = DemoResults(
        rnnpb_version=__version__,
        versions=versions(),
        config=config,
        default=summary,
        novel=novel,
        closed_loop_periods={
            k: {p: a.period for p, a in r.attractors.items()} for k, r in ordered.items()
        },
        switch_sequence_steps_to_follow=ordered["1"].sequence.steps_to_follow,
        larger=larger,
        targets=targets(summary, larger, [r.case for r in novel]),
        draws=draws_summary(
            {k: r.draws_by_seed() for k, r in ordered.items()},
            [r.draws_by_seed() for r in larger],
            (config.scenario_seed, *config.extra_scenario_seeds),
        ),
        files=files,
        paper=paper_summary,
        paper_targets=targets(paper_summary, [], []) if paper_summary else None,
        distributions=distributions(jobs.by_seed, larger, scenario_seeds),
        novel_all=[
            n.without_arrays()
            for results in jobs.by_seed.values()
            for r in results.values()
            for n in r.novel
        ],
        paper_distributions=(
            distributions(
                {
                    s: {k: r.compared("paper") for k, r in results.items()}
                    for s, results in jobs.by_seed.items()
                    if all(r.compare is not None for r in results.values())
                },
                [],
                scenario_seeds,
            )
            if config.compare_paper
            else None
        ),
        runtime_s=time.perf_counter() - start,
    )
    write_outputs(out, report_lines(results), results.to_json())
    return results


# --- the report: one function per section --------------------------------------------------


def missing_cases_explanation(
    novel: Sequence[NovelResponse], closed_loop_periods: dict[str, dict[str, float | None]]
) -> list[str]:
    """Why a response case did not occur, from the attractor analysis's own numbers."""
    seen = {r.case for r in novel}
    missing = [c for c in metrics.RESPONSE_CASES if c not in seen]
    if not missing or not novel:
        return []
    periods = sorted({f"{r.period:.1f}" for r in novel if r.period is not None}, key=float)
    worst_return = max(r.return_error for r in novel)
    closed = [p for periods_ in closed_loop_periods.values() for p in periods_.values()]
    learned = sorted({f"{p:.1f}" for p in closed if p is not None}, key=float)
    cycles = sum(p is not None for p in closed)
    if cycles == len(closed):
        autonomous = (
            f"The closed-loop attractors of the learned patterns are limit cycles too "
            f"(periods {', '.join(learned)}), and with on-line regression "
            "the network entrains to the period it is shown."
        )
    else:
        autonomous = (
            f"Of the learned patterns' closed-loop attractors, {cycles} of "
            f"{len(closed)} are limit cycles (periods "
            f"{', '.join(learned) or '–'}) and the others do not repeat "
            f"within {metrics.MAX_PERIOD} steps; yet driven by a repeated input and "
            "with on-line regression, the network entrains to the period it is shown."
        )
    lines = ["", f"**Why case {' and '.join(map(str, missing))} did not occur here.**"]
    if 3 in missing:
        lines.append(
            f"Every response settled on a limit cycle: the largest return error over all "
            f"{len(novel)} runs is {worst_return:.3f} (a response counts as unsteady above "
            f"{metrics.PERIODIC_TOLERANCE:g}), at period(s) {', '.join(periods)} — "
            "the period of the input cycle or a multiple of it. "
            f"{autonomous} "
            + (
                "Even demonstrated by hand, with imperfect cycles, the novel pattern is close "
                "enough to a cycle that the PB, regressed every step, keeps the response on "
                "its period."
                if any(r.user_draw is not None for r in novel)
                else "The input here is one exactly repeated cycle (the paper's user demonstrated "
                "the novel patterns by hand), and the PB, regressed every step, keeps the "
                "response on that period."
            )
        )
    if 2 in missing:
        lines.append(
            f"Every periodic response lay within {metrics.SIMILAR_CYCLE:g} of a "
            "learned pattern's cycle: the novel patterns were drawn into the learned "
            "attractors."
        )
    if 1 in missing:
        lines.append(
            f"No periodic response lay within {metrics.SIMILAR_CYCLE:g} of a learned "
            "pattern's cycle."
        )
    return lines


def _describe_learning(train: TrainConfig) -> str:
    if train.optimizer == "momentum":
        how = "the paper's algorithm, gradient descent with momentum"
    else:
        how = "Adam with noise on the teacher-forced inputs (the fast preset)"
    return f"{how}, {train.iterations:,} iterations"


def describe_configuration(config: ExperimentConfig) -> str:
    """What **default** and **paper's regression** mean in this run, from its config."""

    def onset(online: OnlineConfig) -> str:
        return "optimised with the PB" if online.optimize_onset else "carried over"

    online = config.online
    phase = (
        f", phase restarts from the learned cycles (scored on the last "
        f"{online.phase_restarts} steps)"
        if online.phase_restarts
        else ""
    )
    gate = (
        f", the surprise gate at {online.surprise_gate} RMS (power {online.gate_power:g})"
        if online.surprise_gate > 0
        else ", no surprise gate"
    )
    text = (
        f"**default** is this run's configuration. Learning: "
        f"{_describe_learning(config.train)} (the larger set: "
        f"{config.larger_train.iterations:,} iterations). On-line: "
        f"L = {online.window}, {online.iterations} iterations, integration length "
        f"{online.pb.integration_length}, onset state {onset(online)}"
        f"{', restarts at the learned PBs' if online.restart_span else ''}"
        f"{phase}{gate}."
    )
    if config.compare_paper:
        paper = config.paper_online
        text += (
            f" **paper's regression** runs the same models with the paper's on-line "
            f"regression (L = {paper.window}, l = {paper.pb.integration_length}, "
            f"{paper.iterations} iterations, onset state {onset(paper)})."
        )
    return text


def _header(results: DemoResults) -> list[str]:
    config = results.config
    return [
        "# rnnpb — the experiments of Ito & Tani (2004), reproduced",
        "",
        f"rnnpb {results.rnnpb_version}, {'quick' if config.quick else 'full'} run, "
        f"{results.runtime_s:.0f} s on {results.versions['cpus']} CPU(s) "
        f"(jax {results.versions['jax']}, mujoco {results.versions['mujoco']}). "
        "Every number below is in `results.json`; the definitions of the measures are in "
        "`rnnpb.analysis.metrics` and docs/experiments.md.",
        "",
        describe_configuration(config),
        "",
        f"Every learning set holds {config.samples_per_pattern} demonstrations of each of its "
        f"patterns (the paper: 2), from the synthetic demonstrator with data seed "
        f"{config.data_seed}.",
    ]


def _summary_section(results: DemoResults) -> list[str]:
    ours, theirs = results.default, results.paper
    absent = "not run (quick)" if results.config.quick else "–"

    def spread(measure: str, per_pattern: bool = True) -> tuple[str, str]:
        def cell(summary: Summary | None) -> str:
            if summary is None:
                return absent
            value = getattr(summary, measure)
            return median_and_worst(flat(value) if per_pattern else list(value.values()))

        return cell(ours), cell(theirs)

    def worst(measure: str, prefix: str, none: str) -> tuple[str, str]:
        def cell(summary: Summary | None) -> str:
            if summary is None:
                return none
            return f"{prefix}{max(getattr(summary, measure).values()):.2e}"

        return cell(ours), cell(theirs)

    def recognised(summary: Summary | None) -> str:
        return f"{summary.recognized_correctly}/{summary.recognition_runs}" if summary else "–"

    target = sci(metrics.TRAIN_ERROR_TARGET)
    cases = [r.case for r in results.novel]
    rows = [
        (
            "final training error (MSE per output, worst of sets 1–4)",
            f"< {target} (RMS, read as MSE)",
            *worst("train_mse", "max ", absent),
        ),
        ("final training error as RMS (worst)", f"< {target}", *worst("train_rms", "", "–")),
        (
            "steps until locked on a learned pattern",
            f"about {metrics.LOCK_LIMIT}",
            *spread("sync_steps_to_lock"),
        ),
        ("steps until the PB settles", f"about {metrics.SETTLE_LIMIT}", *spread("pb_settle_steps")),
        (
            "phase lag once locked (steps; + = robot behind)",
            "mostly synchronous",
            *spread("phase_lag_steps"),
        ),
        (
            f"robot motion during a {PAUSE_STEPS}-step pause (relative to before)",
            "keeps moving",
            *spread("pause_relative_motion"),
        ),
        ("steps to re-lock after the pause", "a few", *spread("pause_steps_to_relock")),
        (
            "steps until the robot follows a switch (every ordered pair, sets 1–4)",
            "several",
            *spread("switch_steps"),
        ),
        (
            "learned pattern recognised (nearest learned PB)",
            "all",
            recognised(ours),
            recognised(theirs),
        ),
        (
            "novel-pattern responses (case 1 / 2 / 3)",
            "all three occur",
            " / ".join(str(cases.count(c)) for c in metrics.RESPONSE_CASES),
            "–",
        ),
        (
            "larger set: runs that follow every pattern",
            f"{metrics.LARGER_SET_FOLLOWS} of {metrics.LARGER_SET_RUNS}",
            f"{results.larger_set_success} of {len(results.larger)}",
            "–",
        ),
    ]
    return [
        "",
        "## Summary",
        "",
        *table(("measure", "paper", "ours (default)", "ours (paper's regression)"), rows),
    ]


def _verdict(target: Target | None) -> str:
    if target is None:
        return "–"
    return f"{'met' if target.met else 'NOT met'} ({target.detail})"


def _targets_section(results: DemoResults) -> list[str]:
    seeds = results.draws.scenario_seeds
    pooled, theirs = results.draws.targets, results.paper_targets
    rows = [
        (
            key,
            _verdict(value),
            _verdict(pooled.get(key)),
            _verdict(theirs.get(key) if theirs else None),
        )
        for key, value in results.targets.items()
    ]
    return [
        "",
        "### Targets",
        "",
        f"For the report's draw of the user's imperfection (scenario seed {seeds[0]}) and "
        f"over all {len(seeds)} draws ({', '.join(map(str, seeds))}; see "
        '"Other draws of the user\'s imperfection" below):',
        "",
        *table(("target", "default", "default, all draws", "paper's regression"), rows),
    ]


def _patterns_section(results: DemoResults) -> list[str]:
    return [
        "",
        "## The four movement patterns (Figure 4)",
        "",
        embed("patterns", "figure4_patterns.png"),
    ]


def _learning_section(results: DemoResults) -> list[str]:
    ours = results.default
    rows = [
        (k, f"{ours.train_mse[k]:.2e}", f"{ours.train_rms[k]:.2e}", f"{ours.train_seconds[k]:.0f}")
        for k in sorted(ours.train_mse)
    ]
    return [
        "",
        "## Learning",
        "",
        *table(("learning set", "MSE (worst output)", "RMS", "seconds"), rows),
        "",
        embed("training", "training.png"),
    ]


def _synchronization_section(results: DemoResults) -> list[str]:
    ours = results.default
    rows = [
        (
            k,
            p,
            fmt(ours.sync_steps_to_lock[k][p]),
            fmt(ours.pb_settle_steps[k][p]),
            fmt(ours.phase_lag_steps[k][p], 2),
            ours.recognized_pattern[k][p],
            fmt(ours.pause_relative_motion[k][p], 2),
            fmt(ours.pause_steps_to_relock[k][p]),
        )
        for k in sorted(ours.sync_steps_to_lock)
        for p in ours.sync_steps_to_lock[k]
    ]
    return [
        "",
        "## 3.1 Synchronization and pause (Figure 5)",
        "",
        *table(
            (
                "set",
                "pattern",
                "steps to lock",
                "PB settles",
                "phase lag",
                "recognised",
                "motion in pause",
                "re-lock",
            ),
            rows,
        ),
        "",
        embed("synchronization", "figure5_synchronization.png"),
    ]


def _switching_section(results: DemoResults) -> list[str]:
    return [
        "",
        "## 3.2 Switching (Figures 6 and 7)",
        "",
        "Steps from the user's switch until the robot follows the new pattern, for "
        "every ordered pair of learned patterns in every learning set (the user performs "
        f"{SWITCH_STEPS_EACH} steps of the first pattern, then the second):",
        "",
        embed("switching matrix", "switching_matrix.png"),
        "",
        embed("switching", "figure6_switching.png"),
        "",
        embed("switching zoom", "figure7_switching_zoom.png"),
    ]


def _novel_section(results: DemoResults) -> list[str]:
    rows = [
        (r.learning_set, r.novel_pattern, f"x{r.amplitude:g}", r.description) for r in results.novel
    ]
    periods = "; ".join(
        f"set {k}: " + ", ".join(f"{p}→{fmt(v)}" for p, v in found.items())
        for k, found in results.closed_loop_periods.items()
    )
    return [
        "",
        "## 3.3 Novel patterns and attractors (Figures 8 and 9)",
        "",
        "One cycle of the pattern a learning set left out is repeated while the PB is "
        "regressed on-line; the robot's response after the transient is classified "
        "(case 1: a limit cycle like a learned one; 2: a new limit cycle; 3: unsteady).",
        "",
        *table(("set", "novel pattern", "size", "response"), rows),
        *missing_cases_explanation(results.novel_all or results.novel, results.closed_loop_periods),
        "",
        embed("novel", "figure8_novel.png"),
        "",
        embed("attractors", "figure9_attractors.png"),
        "",
        "Closed-loop periods of the learned patterns (steps; none = not periodic): " + periods,
        "",
        "Whether the robot itself tells a novel movement from a learned one, or from noise "
        "(section 4.1): `rnnpb study novelty --out DIR` (docs/experiments.md).",
    ]


def _larger_set_section(results: DemoResults) -> list[str]:
    rows = [
        (
            r.seed,
            f"{r.train_mse_max:.2e}",
            " / ".join(fmt(v) for v in r.steps_to_follow.values()),
            "yes" if r.follows_all else "no",
        )
        for r in results.larger
    ]
    return [
        "",
        "## 3.4 The larger set",
        "",
        *table(("seed", "training MSE", "steps to follow 1 / 2 / 3 / 4", "follows all"), rows),
    ]


DISTRIBUTION_NAMES = {
    "steps_to_lock": ("steps until locked on a learned pattern", f"about {metrics.LOCK_LIMIT}"),
    "pb_settle_steps": ("steps until the PB settles", f"about {metrics.SETTLE_LIMIT}"),
    "phase_lag_steps": ("phase lag once locked (steps)", "mostly synchronous"),
    "pause_relative_motion": ("robot motion during the pause (relative)", "keeps moving"),
    "pause_steps_to_relock": (
        "steps to re-lock after the pause",
        f"a few (≤ {metrics.RELOCK_LIMIT})",
    ),
    "switch_steps": (
        "steps until the robot follows a switch",
        f"several (≤ {metrics.SWITCH_LIMIT})",
    ),
    "steps_to_follow": (
        "larger set: steps until the robot follows each pattern",
        f"≤ {metrics.SWITCH_LIMIT}",
    ),
}


def _share(interval) -> str:
    if interval is None or interval.n == 0:
        return "–"
    return f"{interval.value:.0%} [{interval.low:.0%}, {interval.high:.0%}]"


def _distribution_cells(found: Distribution | None) -> tuple[str, str]:
    if found is None:
        return "–", "–"
    digits = 2 if found.measure in ("phase_lag_steps", "pause_relative_motion") else 1
    never = f", never {found.never}/{found.n}" if found.never else ""
    return f"{found.median.describe(digits)}{never}", _share(found.within)


def _distributions_section(results: DemoResults) -> list[str]:
    ours, theirs = results.distributions, results.paper_distributions
    if ours is None:
        return []
    rows = []
    for measure, (name, paper) in DISTRIBUTION_NAMES.items():
        if measure not in ours.measures:
            continue
        compared = theirs.measures.get(measure) if theirs else None
        rows.append(
            (
                name,
                paper,
                *_distribution_cells(ours.measures[measure]),
                *_distribution_cells(compared),
            )
        )
    rows.append(
        (
            "learned pattern recognised (nearest learned PB)",
            "all",
            "–",
            _share(ours.recognised),
            "–",
            _share(theirs.recognised) if theirs else "–",
        )
    )
    rows.append(
        (
            f"networks whose final error is below {sci(metrics.TRAIN_ERROR_TARGET)}",
            "all",
            "–",
            _share(ours.train_below_target),
            "–",
            "–",
        )
    )
    if ours.larger_set_follows is not None:
        rows.append(
            (
                "larger set: (seed, draw) runs that follow every pattern",
                f"{metrics.LARGER_SET_FOLLOWS} of {metrics.LARGER_SET_RUNS}",
                "–",
                _share(ours.larger_set_follows),
                "–",
                "–",
            )
        )
    cases = []
    for label, found in (("default", ours), ("paper's regression", theirs)):
        if found is None:
            continue
        for kind, counts in found.novel_cases.items():
            if sum(counts.values()):
                cases.append((label, kind, *(counts[c] for c in metrics.RESPONSE_CASES)))
    periodic, total = ours.closed_loop_periodic
    return [
        "",
        "## Over every network and draw of the user",
        "",
        f"Every measure of section 3 over {len(ours.training_seeds)} networks per learning "
        f"set (training seeds {', '.join(map(str, ours.training_seeds))}) and "
        f"{len(ours.scenario_seeds)} draws of the user's imperfection (scenario seeds "
        f"{', '.join(map(str, ours.scenario_seeds))}), every pattern and ordered pair pooled; "
        f"the larger set over its {len(results.larger)} seeds and the same draws. Medians "
        "are over the runs where the event happened (never: how many it did not); the "
        "share counts values within the paper's limit (never counts as outside). "
        "Brackets: 95 % percentile bootstrap intervals (`rnnpb.analysis.statistics`). The "
        "sections above show the first seed's networks."
        + (
            f" The paper's regression ran on the networks of training seed(s) "
            f"{', '.join(map(str, theirs.training_seeds))} only (`compare_seeds`)."
            if theirs is not None and len(theirs.training_seeds) < len(ours.training_seeds)
            else ""
        ),
        "",
        *table(
            (
                "measure",
                "paper",
                "default: median [95 % CI]",
                "default: within",
                "paper's regression: median",
                "paper's regression: within",
            ),
            rows,
        ),
        "",
        "Novel-pattern responses over every network and draw (the repeated cycle is "
        "one exact cycle at each size; by hand, the user demonstrates the novel pattern "
        "with imperfect cycles, one demonstration per draw, as in the paper's interaction "
        f"experiment). Learned attractors that are limit cycles: {periodic} of {total} "
        "(the period may be fractional, `metrics.periodicity`).",
        "",
        *table(("regression", "input", "case 1", "case 2", "case 3"), cases),
    ]


def _draws_section(results: DemoResults) -> list[str]:
    draws = results.draws
    first = draws.scenario_seeds[0]
    lines = [
        "",
        "## Other draws of the user's imperfection",
        "",
        "The user's imperfection (period, size and shape from cycle to cycle, drift, "
        "sensor noise) is drawn at random; the figures above use one draw. The same "
        "models, driven by other draws, give (counts within the target; median and worst "
        "steps):",
        "",
    ]
    names = {
        "sync_steps_to_lock": "lock on",
        "pb_settle_steps": "PB settles",
        "pause_steps_to_relock": "re-lock",
        "switch_steps": "switch",
    }
    header = (
        "scenario seed",
        *(f"{names[t.measure]} ≤ {t.limit}" for t in STEP_TARGETS),
        "larger set",
    )
    lines += table(header, [])
    for seed, draw in draws.by_seed.items():
        cells: list[str] = [f"{seed}{' (above)' if int(seed) == first else ''}"]
        for target in STEP_TARGETS:
            values = flat(getattr(draw, target.measure))
            cells.append(
                f"{within(values, target.limit)}/{len(values)} ({median_and_worst(values)})"
            )
        n_larger = len(draw.larger_set_steps_to_follow)
        cells.append(f"{draw.larger_set_success}/{n_larger}" if n_larger else "–")
        lines.append(row(cells))
    return lines


def _files_section(results: DemoResults) -> list[str]:
    return [
        "",
        "## Files",
        "",
        "Models (reuse them with `rnnpb interact --model …`): "
        + ", ".join(f"`{v}`" for v in results.files.models.values())
        + ".",
        "Learning sets as sequence CSVs: `data/set1/` … `data/set4/`, `data/full/`.",
        "",
    ]


SECTIONS = (
    _header,
    _summary_section,
    _targets_section,
    _distributions_section,
    _patterns_section,
    _learning_section,
    _synchronization_section,
    _switching_section,
    _novel_section,
    _larger_set_section,
    _draws_section,
    _files_section,
)


def report_lines(results: DemoResults) -> list[str]:
    """``report.md``, section after section, as lines."""
    return [line for section in SECTIONS for line in section(results)]


def write_report(path: str | os.PathLike[str], results: DemoResults) -> None:
    """Write the report of ``results`` to ``path`` (``run_demo`` writes it with the
    results)."""
    write_lines(path, report_lines(results))
