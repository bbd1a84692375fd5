"""Could any PB have made the unguarded robot's colliding commands safe?

The meta-level (docs/safety.md) can only move the PB. This script bounds what that can do: an
adversarial user of `rnnpb study safety` drives the unguarded mirror system; at every step
whose command collides, the window's forward pass after that step's regression is run again
with the PB held at each of 500 random points of PB space (and at every learned PB), and each
resulting command is checked for a self-collision on the way from the previous command. It
prints, per user, how many colliding steps some PB would have made collision-free (the most
any PB-space guard could remove, an oracle's share) and how many a PB within 0.2 of the
regressed one would have.

    .venv/bin/python benchmarks/safety_pb_oracle.py MODEL
        [--users random_walk,jerky_targets,fast_scribbles,full_swing] [--steps 300]
        [--samples 500]

It reads the mirror system's compiled state between steps (``MirrorSystem._state``), which
only a diagnostic may do.
"""

from __future__ import annotations

import argparse
import json


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("model")
    parser.add_argument("--users", default="random_walk,jerky_targets,full_swing")
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--samples", type=int, default=500)
    parser.add_argument("--seed", type=int, default=0, help="the study's seed (users: +1000+k)")
    args = parser.parse_args()
    from rnnpb import _xla

    _xla.configure()
    import numpy as np

    from rnnpb.experiments.scenarios.safety import USERS, adversarial_stream
    from rnnpb.model import MirrorSystem, OnlineConfig, TrainedModel, online
    from rnnpb.model.mirror import motor_command
    from rnnpb.model.network import logit_numpy
    from rnnpb.safety import SafetyChecker

    model = TrainedModel.load(args.model)
    mirror = MirrorSystem(model, OnlineConfig.for_model(model).config)
    checker = SafetyChecker()
    rng = np.random.default_rng(0)
    pbs = np.concatenate(
        [
            rng.uniform(0.01, 0.99, (args.samples, model.network.pb_size)),
            np.array(list(model.pattern_pb.values())),
        ]
    )
    s = model.network.sensory_size

    rho_of = logit_numpy(pbs).astype(np.float32)

    def commands_with() -> np.ndarray:
        """The command the window gives this step with each PB of ``pbs`` in place of the
        regressed profile, from the regressed onset (normalized)."""
        state, count = mirror._state, len(pbs)
        n = int(state.n[0])
        fixed, mask, _, _ = online._windows(
            mirror._net,
            state.sensory[0],
            state.seen[0],
            state.motor_sent[0],
            n,
            mirror._settings.recorded,
            count,
        )
        rho = np.ascontiguousarray(np.broadcast_to(rho_of[:, None], (count, *state.rho.shape[1:])))
        _, outputs = online._run(
            mirror._net,
            fixed,
            mask,
            rho,
            np.repeat(state.onset_context, count, axis=0),
            np.repeat(state.onset_motor, count, axis=0),
            n,
        )
        return outputs[max(n - 2, 0), :, s : s + model.network.motor_size]

    def collides(previous, command) -> bool:
        return any(r.startswith("collision") for r in checker.command_reasons(previous, command))

    for user in args.users.split(","):
        seed = args.seed + 1000 + USERS.index(user)
        sensory = adversarial_stream(user, args.steps, seed, model.patterns[0])
        mirror.reset()
        previous, colliding, some, near = None, 0, 0, 0
        for t in range(args.steps):
            result = mirror.step(sensory[t])
            # After the window has filled (the first steps have no regression to speak of).
            if t >= mirror.config.window and collides(previous, result.motor):
                colliding += 1
                others = np.asarray(commands_with(), np.float64)
                safe = np.array([not collides(previous, motor_command(model, o)) for o in others])
                distance = np.linalg.norm(pbs - result.pb, axis=1)
                some += bool(safe.any())
                near += bool((safe & (distance < 0.2)).any())
            previous = result.motor
        print(
            json.dumps(
                {
                    "user": user,
                    "seed": seed,
                    "steps": args.steps,
                    "colliding": colliding,
                    "some_pb_safe": some,
                    "safe_pb_within_0.2": near,
                }
            ),
            flush=True,
        )


if __name__ == "__main__":
    main()
