"""A sweep's report: per setting, every measure's median and share within the paper's limit,
each with its 95 % bootstrap interval, over learning sets, seeds, draws and patterns; the
novel-pattern cases; the figure that compares the settings; per study, how often each of its
targets was met over the seeds."""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from rnnpb.analysis import metrics
from rnnpb.analysis.statistics import (
    Interval,
    bootstrap_interval,
    median_interval,
    share_within,
)
from rnnpb.experiments.reporting import (
    FIGURES_DIR,
    embed,
    sci,
    table,
    versions,
    write_outputs,
)
from rnnpb.sweeps._runs import MEASURES
from rnnpb.sweeps._spec import SweepSpec

# A measure's limit from the paper (steps, or the training error): the report gives the share
# of values at most this.
LIMITS: dict[str, float] = {
    "train_mse_max": metrics.TRAIN_ERROR_TARGET,
    "steps_to_lock": metrics.LOCK_LIMIT,
    "pb_settle_steps": metrics.SETTLE_LIMIT,
    "pause_steps_to_relock": metrics.RELOCK_LIMIT,
    "switch_steps": metrics.SWITCH_LIMIT,
    "steps_to_follow": metrics.SWITCH_LIMIT,
}
FIGURE_MEASURES = (
    "steps_to_lock",
    "pb_settle_steps",
    "pause_steps_to_relock",
    "switch_steps",
    "steps_to_follow",
    "train_mse_max",
)
FIGURE_FILE = "settings.png"


@dataclass(frozen=True)
class MeasureSummary:
    """One measure of one setting over all its runs (and patterns, pairs …)."""

    measure: str
    setting: str
    values: list[float | None]
    median: Interval
    within: Interval | None  # share at most LIMITS[measure]; None without a limit

    def to_json(self) -> dict[str, Any]:
        return {
            "measure": self.measure,
            "setting": self.setting,
            "n": len(self.values),
            "never": sum(v is None for v in self.values),
            "median": asdict(self.median),
            "within_limit": asdict(self.within) if self.within else None,
            "limit": LIMITS.get(self.measure),
        }


def setting_name(row: dict[str, Any]) -> str:
    return f"{row['training']} / {row['online']}"


def summaries(rows: Sequence[dict[str, Any]]) -> list[MeasureSummary]:
    """Every (measure, setting) of the table's ``ok`` rows."""
    values: dict[tuple[str, str], list[float | None]] = {}
    for row in rows:
        if row["status"] == "ok" and not row["study"] and row["measure"] != "novel_case":
            values.setdefault((row["measure"], setting_name(row)), []).append(row["value"])
    order = list(MEASURES)
    out = []
    for (measure, setting), sample in sorted(
        values.items(), key=lambda kv: (order.index(kv[0][0]), kv[0][1])
    ):
        limit = LIMITS.get(measure)
        out.append(
            MeasureSummary(
                measure,
                setting,
                sample,
                median_interval(sample),
                share_within(sample, limit) if limit is not None else None,
            )
        )
    return out


def novel_cases(rows: Sequence[dict[str, Any]]) -> dict[tuple[str, str], Counter]:
    """(setting, input) → how often each response case occurred."""
    out: dict[tuple[str, str], Counter] = {}
    for row in rows:
        if row["status"] == "ok" and row["measure"] == "novel_case" and not row["study"]:
            kind = "by hand" if row["key"] == "by hand" else "repeated cycle"
            out.setdefault((setting_name(row), kind), Counter())[int(row["value"])] += 1
    return out


def _cell(summary: MeasureSummary) -> tuple[str, ...]:
    digits = 2 if summary.measure in ("phase_lag_steps", "pause_relative_motion") else 1
    if summary.measure.startswith("train_"):
        median = summary.median
        text = (
            f"{sci_like(median.value)} [{sci_like(median.low)}, {sci_like(median.high)}]"
            if median.n
            else "–"
        )
    else:
        text = summary.median.describe(digits)
    within = summary.within
    share = "–" if within is None else (f"{within.value:.0%} [{within.low:.0%}, {within.high:.0%}]")
    never = sum(v is None for v in summary.values)
    return (
        MEASURES[summary.measure],
        summary.setting,
        str(len(summary.values)),
        text,
        str(never),
        share,
    )


def sci_like(value: float) -> str:
    return "–" if math.isnan(value) else f"{value:.2e}"


@dataclass(frozen=True)
class StudyTargetSummary:
    """One target of one study over the seeds it ran with: the share of seeds that met it."""

    study: str
    target: str
    seeds: list[int]
    met: list[bool]
    share: Interval

    def to_json(self) -> dict[str, Any]:
        return {
            "study": self.study,
            "target": self.target,
            "seeds": self.seeds,
            "met": self.met,
            "share_met": asdict(self.share),
        }


def study_summaries(rows: Sequence[dict[str, Any]]) -> list[StudyTargetSummary]:
    """Per (study, target): which seeds met it, and the share with its bootstrap interval."""
    import numpy as np

    found: dict[tuple[str, str], dict[int, bool]] = {}
    for row in rows:
        if row["status"] == "ok" and row["study"] and row["measure"] == "study_target_met":
            found.setdefault((row["study"], row["key"]), {})[row["seed"]] = row["value"] == 1
    return [
        StudyTargetSummary(
            study,
            target,
            sorted(by_seed),
            [by_seed[s] for s in sorted(by_seed)],
            bootstrap_interval([float(v) for v in by_seed.values()], np.mean),
        )
        for (study, target), by_seed in found.items()
    ]


def _studies_section(found: Sequence[StudyTargetSummary], rows) -> list[str]:
    if not found:
        return []
    folders = {
        (r["study"], r["seed"]): r["model"] for r in rows if r["study"] and r["status"] == "ok"
    }
    return [
        "",
        "## Studies",
        "",
        "Each study ran once per seed (`StudyOptions.seed`), its own report in the folder "
        "named below; a target counts as met in a seed when that study's run met it.",
        "",
        *table(
            ("study", "target", "met in", "share [95 % CI]", "seeds that missed it"),
            [
                (
                    s.study,
                    s.target,
                    f"{sum(s.met)} of {len(s.met)}",
                    f"{s.share.value:.0%} [{s.share.low:.0%}, {s.share.high:.0%}]",
                    ", ".join(str(seed) for seed, m in zip(s.seeds, s.met, strict=True) if not m)
                    or "–",
                )
                for s in found
            ],
        ),
        "",
        *(
            f"- {study}, seed {seed}: `{folder}/report.md`"
            for (study, seed), folder in sorted(folders.items())
        ),
    ]


def _follows_by_seed(rows: Sequence[dict[str, Any]]) -> list[str]:
    """Larger set: per setting, how many seeds follow all four patterns in every draw."""
    seeds: dict[str, dict[int, list[bool]]] = {}
    errors: dict[str, dict[int, float]] = {}
    for row in rows:
        if row["status"] != "ok" or row["learning_set"] != "full":
            continue
        setting = setting_name(row)
        if row["measure"] == "follows_all":
            seeds.setdefault(setting, {}).setdefault(row["seed"], []).append(row["value"] == 1)
        if row["measure"] == "train_mse_max":
            errors.setdefault(setting, {})[row["seed"]] = row["value"]
    lines = []
    for setting, by_seed in seeds.items():
        every = sum(all(v) for v in by_seed.values())
        below = sum(
            e is not None and e < metrics.TRAIN_ERROR_TARGET
            for e in errors.get(setting, {}).values()
        )
        lines.append(
            f"- {setting}: {every} of {len(by_seed)} seeds follow all four patterns "
            f"in every draw (the paper: {metrics.LARGER_SET_FOLLOWS} of "
            f"{metrics.LARGER_SET_RUNS}); {below} of {len(errors.get(setting, {}))} "
            f"reach the paper's final error (MSE < "
            f"{sci(metrics.TRAIN_ERROR_TARGET)})."
        )
    return lines


def write_report(
    out: Path, spec: SweepSpec, rows: Sequence[dict[str, Any]], runtime_s: float
) -> None:
    """``out/report.md``, ``out/results.json`` (the summaries, spec and versions) and
    ``out/figures/settings.png``."""
    from rnnpb.analysis import figures

    found = summaries(rows)
    runs = {r["run"]: r for r in rows}
    failed = [r for r in runs.values() if r["status"] != "ok"]
    panels: dict[str, dict[str, tuple[list[float], Interval]]] = {}
    for s in found:
        if s.measure in FIGURE_MEASURES:
            panels.setdefault(s.measure, {})[s.setting] = (
                [v for v in s.values if v is not None],
                s.median,
            )
    figure_dir = out / FIGURES_DIR
    figure_dir.mkdir(parents=True, exist_ok=True)
    if panels:
        figures.plot_distributions(
            panels,
            figure_dir / FIGURE_FILE,
            {m: v for m, v in LIMITS.items() if m != "train_mse_max"},
        )
    cases = novel_cases(rows)
    studies = study_summaries(rows)
    grid = []
    if spec.learning_sets:
        grid.append(
            f"learning sets {', '.join(spec.learning_sets)}, user draws "
            f"{', '.join(map(str, spec.user_draws))}, settings (training / on-line): "
            f"{', '.join(sorted({setting_name(r) for r in rows if not r['study']}))}"
        )
    if spec.studies:
        grid.append(f"studies {', '.join(spec.studies)}{' (quick)' if spec.quick else ''}")
    lines = [
        f"# Sweep {spec.name}",
        "",
        f"{len(runs)} runs ({len(runs) - len(failed)} ok, {len(failed)} failed) over "
        f"seeds {', '.join(map(str, spec.seeds))}; {'; '.join(grid)}. This command's part "
        f"took {runtime_s:.0f} s. Every row is in `results.parquet`.",
    ]
    if found:
        lines += [
            "",
            'Medians are over the runs where the event happened ("never" counts those '
            "where it did not); the share counts values within the paper's limit, never "
            "counting as outside. Brackets: 95 % percentile bootstrap intervals.",
            "",
            *table(
                (
                    "measure",
                    "setting",
                    "n",
                    "median [95 % CI]",
                    "never",
                    "within the paper's limit [95 % CI]",
                ),
                [_cell(s) for s in found],
            ),
        ]
    if panels:
        lines += ["", embed("settings", FIGURE_FILE)]
    lines += _studies_section(studies, rows)
    if cases:
        lines += [
            "",
            "## Novel-pattern responses",
            "",
            *table(
                ("setting", "input", "case 1", "case 2", "case 3"),
                [
                    (setting, kind, counts[1], counts[2], counts[3])
                    for (setting, kind), counts in sorted(cases.items())
                ],
            ),
        ]
    follows = _follows_by_seed(rows)
    if follows:
        lines += ["", "## The larger set", "", *follows]
    if failed:
        lines += [
            "",
            "## Failed runs",
            "",
            *table(("run", "error"), [(r["run"], r["error"]) for r in failed]),
        ]
    write_outputs(
        out,
        lines,
        {
            "spec": asdict(spec),
            "versions": versions(),
            "summaries": [s.to_json() for s in found],
            "studies": [s.to_json() for s in studies],
            "novel_cases": [
                {"setting": k[0], "input": k[1], "counts": dict(v)} for k, v in cases.items()
            ],
            "failed": [{"run": r["run"], "error": r["error"]} for r in failed],
            "runtime_s": runtime_s,
        },
    )
