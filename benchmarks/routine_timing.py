"""How well the routine level knows when the person will switch, on development draws.

Routines A and B of the routines study are learned over the shipped model from user draws
201-203 (each performed twice in a row); draws 101-110 then perform each routine. At each
switch, what the higher level said ``--before`` steps earlier (its predicted end of the
current movement, ``FollowStep.steps_left``) is set against the step the person switched on.
Prints the error's median, median size, spread and the share within one step: how far a
switch can be anticipated from the routine alone, before the new movement shows.

Usage: ``PYTHONPATH=src .venv/bin/python benchmarks/routine_timing.py [--draws 101,102]
[--before 6]``.
"""

from __future__ import annotations

import argparse

import numpy as np

from rnnpb import _xla
from rnnpb.demonstrator import routine_scenario
from rnnpb.experiments.scenarios.routines import ROUTINES, learn
from rnnpb.model import TrainedModel
from rnnpb.model.routines import TwoLevelMirror
from rnnpb.models import SHIPPED_MODEL


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--draws", default=",".join(str(d) for d in range(101, 111)))
    parser.add_argument("--before", type=int, default=6, help="steps before each switch")
    args = parser.parse_args()
    _xla.configure()
    lower = TrainedModel.load(SHIPPED_MODEL)
    routines = learn(lower, [201, 202, 203], repeats=2)
    errors, unknown = [], 0
    for seed in (int(d) for d in args.draws.split(",")):
        for parts in ROUTINES.values():
            scenario = routine_scenario(parts, seed=seed)
            two = TwoLevelMirror(lower, routines, use_prior=False)
            said = [two.step(u).higher for u in scenario.sensory]
            for switch in scenario.switch_steps:
                then = said[switch - args.before]
                if then.routine is None or not np.isfinite(then.steps_left):
                    unknown += 1
                    continue
                errors.append(switch - args.before + then.steps_left - switch)
    e = np.array(errors)
    within = np.mean(np.abs(e) <= 1)
    centred = np.mean(np.abs(e - np.median(e)) <= 1)
    print(f"switches: {len(e) + unknown} ({unknown} without a recognised routine then)")
    print(
        f"predicted minus true switch step: median {np.median(e):+.1f}, median size "
        f"{np.median(np.abs(e)):.1f}, sd {e.std():.1f}, within one step {within:.0%}; "
        f"with the median taken off: within one step {centred:.0%}"
    )


if __name__ == "__main__":
    main()
