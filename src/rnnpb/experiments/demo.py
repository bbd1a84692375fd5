"""Run every experiment of the paper's section 3 and write ``report.md`` and ``results.json``.

The jobs (:mod:`rnnpb.experiments.jobs`, one per trained model) run in ``workers`` processes;
every job is seeded, so a run repeats. Outputs under the chosen directory::

    data/            the learning sets as sequence CSVs (set1/ … set4/, full/)
    models/          every trained model (setK.npz, full_seedN.npz)
    figures/         the figures the report embeds
    report.md        measure | paper | ours, with the figures (:mod:`rnnpb.experiments.report`)
    results.json     every measure, the config, versions and which file is which
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Sequence
from pathlib import Path

from rnnpb import __version__
from rnnpb.analysis import metrics
from rnnpb.experiments.jobs import (
    ExperimentConfig,
    JobRunner,
    LearningSetResult,
    model_name,
    run_jobs,
    sequence_file_name,
)
from rnnpb.experiments.paper import Attractor, NovelResponse
from rnnpb.experiments.report import report_lines
from rnnpb.experiments.reporting import FIGURES_DIR, versions, write_outputs
from rnnpb.experiments.summary import (
    DemoResults,
    LearningSetFiles,
    OutputFiles,
    distributions,
    draws_summary,
    summarize,
    targets,
)


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
