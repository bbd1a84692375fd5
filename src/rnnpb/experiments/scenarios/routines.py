"""The routines study's runs and measures: routines learned from some draws of the user,
performed by others, with and without the higher level's prior on the same streams."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rnnpb.demonstrator import routine_scenario
from rnnpb.demonstrator._scenarios import Scenario
from rnnpb.model import TrainedModel
from rnnpb.model.routines import RoutineModel, TwoLevelMirror, learn_routines

ROUTINES: dict[str, list[tuple[str, int]]] = {
    "A": [("1", 3), ("3", 2), ("2", 4)],
    "B": [("2", 2), ("3", 3), ("1", 3)],
}
"""The routines learned (patterns of learning set 1 and their cycles)."""
UNLEARNED = [("3", 2), ("2", 2), ("1", 3), ("2", 2)]
"""An order of the same patterns neither routine has (3 then 2, 2 then 1, 1 then 2)."""
DEVIATIONS: dict[str, list[tuple[str, int]]] = {
    "A": [("1", 3), ("2", 3)],
    "B": [("2", 2), ("1", 3)],
}
"""Each routine's first part, then a pattern the routine does not predict next."""
FOLLOWED_STEPS = 3
"""A switch is followed once the lower PB's nearest pattern is the new one for this many
steps in a row."""


def learn(lower: TrainedModel, seeds: list[int], repeats: int = 2) -> RoutineModel:
    """Learn :data:`ROUTINES` over ``lower`` from one recording per seed of each (the
    routine performed ``repeats`` times in a row)."""
    recordings = {
        name: [routine_scenario(parts, seed=s, repeats=repeats).sensory for s in seeds]
        for name, parts in ROUTINES.items()
    }
    return learn_routines(lower, recordings)


@dataclass(frozen=True)
class RoutineRun:
    """One stream through the two levels: per step the lower PB, the higher PB, the
    routine said and the pattern the lower PB is nearest."""

    kind: str  # "learned", "deviation", "unlearned", "timing"
    routine: str
    seed: int
    prior: bool
    switches: tuple[int, ...]
    labels: tuple[str, ...]
    lower_pb: np.ndarray
    higher_pb: np.ndarray
    said: tuple[str | None, ...]
    nearest: tuple[str, ...]

    def lags(self) -> list[int | None]:
        """Steps from each switch until the new pattern is followed (None: never)."""
        out: list[int | None] = []
        bounds = [*self.switches, len(self.labels)]
        for i, switch in enumerate(self.switches):
            target = self.labels[switch]
            lag = None
            for t in range(switch, bounds[i + 1] - FOLLOWED_STEPS + 1):
                if all(self.nearest[t + k] == target for k in range(FOLLOWED_STEPS)):
                    lag = t - switch
                    break
            out.append(lag)
        return out


def perform(
    lower: TrainedModel,
    routines: RoutineModel,
    scenario: Scenario,
    kind: str,
    routine: str,
    seed: int,
    prior: bool,
) -> RoutineRun:
    """Run one scenario through the two levels (``prior``: the higher level's prediction
    goes down; without it the higher level only watches)."""
    mirror = TwoLevelMirror(lower, routines, use_prior=prior)
    steps = [mirror.step(u) for u in scenario.sensory]
    lower_pb = np.array([s.lower.pb for s in steps])
    return RoutineRun(
        kind=kind,
        routine=routine,
        seed=seed,
        prior=prior,
        switches=scenario.switch_steps,
        labels=scenario.labels,
        lower_pb=lower_pb,
        higher_pb=np.array([s.higher.pb for s in steps]),
        said=tuple(s.higher.routine for s in steps),
        nearest=tuple(lower.nearest_pattern(pb)[0] for pb in lower_pb),
    )


def runs_for_seed(
    lower: TrainedModel,
    routines: RoutineModel,
    seed: int,
    jitters: tuple[float, ...],
    names: tuple[str, ...] = tuple(ROUTINES),
) -> list[RoutineRun]:
    """Every stream of one user draw (of the routines ``names``), each with and without the
    prior."""
    streams: list[tuple[str, str, Scenario]] = []
    for name in names:
        parts = ROUTINES[name]
        streams.append(("learned", name, routine_scenario(parts, seed=seed)))
        streams.append(("deviation", name, routine_scenario(DEVIATIONS[name], seed=seed)))
        for jitter in jitters:
            scenario = routine_scenario(parts, seed=seed, timing_jitter=jitter)
            streams.append((f"timing {jitter:g}", name, scenario))
    streams.append(("unlearned", "-", routine_scenario(UNLEARNED, seed=seed)))
    out = []
    for kind, name, scenario in streams:
        for prior in (True, False):
            if kind == "unlearned" and not prior:
                continue
            out.append(perform(lower, routines, scenario, kind, name, seed, prior))
    return out


def _median(values: list[int]) -> float | None:
    return float(np.median(values)) if values else None


def measure(runs: list[RoutineRun], within: int, deviation_steps: int, judged_from: int):
    """The study's measures over ``runs`` (see the exam's definitions)."""
    out: dict[str, object] = {}
    for prior, key in ((True, "with"), (False, "without")):
        learned = [r for r in runs if r.kind == "learned" and r.prior == prior]
        lags = [lag for r in learned for lag in r.lags()]
        got = [lag for lag in lags if lag is not None]
        out[f"median_lag_{key}"] = _median(got)
        out[f"switches_within_{key}"] = (
            sum(lag is not None and lag <= within for lag in lags) / len(lags) if lags else None
        )
        out[f"switches_{key}"] = len(lags)
        deviations = [r for r in runs if r.kind == "deviation" and r.prior == prior]
        dev_lags = [r.lags()[0] for r in deviations if r.switches]
        out[f"deviation_followed_{key}"] = (
            sum(lag is not None and lag <= deviation_steps for lag in dev_lags) / len(dev_lags)
            if dev_lags
            else None
        )
        out[f"deviation_lags_{key}"] = dev_lags
        for kind in sorted({r.kind for r in runs if r.kind.startswith("timing")}):
            timed = [lag for r in runs if r.kind == kind and r.prior == prior for lag in r.lags()]
            out[f"{kind} median_lag_{key}"] = _median([t for t in timed if t is not None])
            out[f"{kind} within_{key}"] = (
                sum(t is not None and t <= within for t in timed) / len(timed) if timed else None
            )
    learned = [r for r in runs if r.kind == "learned" and r.prior]
    recognised = [
        r.switches and r.said[r.switches[0] - 1] == r.routine for r in learned if r.switches
    ]
    out["recognised_in_first_segment"] = (
        sum(bool(x) for x in recognised) / len(recognised) if recognised else None
    )
    unlearned = [r for r in runs if r.kind == "unlearned"]
    said = [s for r in unlearned for s in r.said[judged_from:]]
    out["unlearned_taken_for_learned"] = (
        sum(s is not None for s in said) / len(said) if said else None
    )
    return out


__all__ = [
    "DEVIATIONS",
    "FOLLOWED_STEPS",
    "ROUTINES",
    "UNLEARNED",
    "RoutineRun",
    "learn",
    "measure",
    "perform",
    "runs_for_seed",
]
