"""How the routine level's prior reaches the lower level, measured on development draws.

Routines A and B of the routines study are learned over the shipped model from user draws
201-203 (each performed twice in a row); draws 101-105 then perform each routine and each
deviation. Each variant runs every stream and prints the switch lags (steps until the lower
PB's nearest pattern is the new one for 3 steps), the share within 3 steps, the deviations'
lags, and the steps on which the robot already showed the next pattern before the user
switched (an early switch):

* ``off``: the higher level only watches (no prior);
* ``restart``: the default, the predicted PB as one more restart candidate from one step
  before the predicted switch;
* ``span:N``: the same with the restarts' span cut to N steps at those steps;
* ``impose:N:K``: at the predicted switch the lower PB's last N steps are set to the predicted
  one and restarts are paused for K steps (the evidence can only pull it back through the
  regression).

Usage: ``PYTHONPATH=src .venv/bin/python benchmarks/routine_prior.py [--draws 101,102]
[--variants off,restart,span:2,impose:3:3]``.
"""

from __future__ import annotations

import argparse

import jax.numpy as jnp
import numpy as np

from rnnpb import _xla
from rnnpb.demonstrator import routine_scenario
from rnnpb.experiments.scenarios.routines import DEVIATIONS, ROUTINES, RoutineRun, learn
from rnnpb.model import TrainedModel
from rnnpb.model.network import logit_numpy
from rnnpb.model.routines import TwoLevelMirror
from rnnpb.models import SHIPPED_MODEL


def run_variant(lower, routines, variant: str, draws: list[int]) -> str:
    kind, *numbers = variant.split(":")
    values = [int(n) for n in numbers]
    lags, deviations, early = [], [], 0
    for draw in draws:
        streams = [("learned", ROUTINES[n]) for n in ROUTINES]
        streams += [("deviation", DEVIATIONS[n]) for n in ROUTINES]
        for what, parts in streams:
            scenario = routine_scenario(parts, seed=draw)
            two = TwoLevelMirror(lower, routines, use_prior=kind in ("restart", "span"))
            mirror = two.mirror
            plain = mirror.config
            changed = plain
            if kind == "span":
                changed = plain.with_tuning(restart_span=values[0])
            if kind == "impose":
                changed = plain.with_tuning(restart_span=0, phase_restarts=0)
            paused, out = 0, []
            for u in scenario.sensory:
                due = two._last is not None and two._last.switch_due
                if kind == "impose" and due and paused == 0:
                    state = mirror._state
                    n = int(state.n)
                    rows = jnp.arange(state.rho.shape[0])
                    recent = (rows >= n - values[0]) & (rows < n)
                    prior = jnp.asarray(logit_numpy(two._last.predicted_pb), jnp.float32)
                    mirror._state = state._replace(
                        rho=jnp.where(recent[:, None], prior, state.rho),
                        rho_velocity=jnp.zeros_like(state.rho_velocity),
                    )
                    paused = values[1]
                if kind == "impose":
                    mirror.config = changed if paused > 0 else plain
                    paused = max(0, paused - 1)
                elif kind == "span":
                    mirror.config = changed if due else plain
                out.append(two.step(u))
            nearest = tuple(lower.nearest_pattern(o.lower.pb)[0] for o in out)
            run = RoutineRun(what, "", draw, True, scenario.switch_steps, scenario.labels,
                             np.zeros(0), np.zeros(0), (), nearest)  # fmt: skip
            for s in scenario.switch_steps:
                early += sum(nearest[t] == scenario.labels[s] for t in range(max(0, s - 6), s))
            if what == "learned":
                lags += run.lags()
            else:
                deviations += run.lags()[:1]
    got = [lag for lag in lags if lag is not None]
    within = np.mean([lag is not None and lag <= 3 for lag in lags])
    return (
        f"{variant}: median lag {np.median(got):g}, within 3 steps {100 * within:.0f} %, "
        f"lags {lags}, deviation lags {deviations}, early steps {early}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--draws", default="101,102,103,104,105")
    parser.add_argument("--variants", default="off,restart,span:2,span:1,impose:3:3")
    args = parser.parse_args()
    _xla.configure()
    lower = TrainedModel.load(SHIPPED_MODEL)
    routines = learn(lower, [201, 202, 203])
    draws = [int(d) for d in args.draws.split(",")]
    for variant in args.variants.split(","):
        print(run_variant(lower, routines, variant, draws), flush=True)


if __name__ == "__main__":
    main()
