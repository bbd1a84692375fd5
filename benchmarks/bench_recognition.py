"""What recognition and the novelty detector cost the on-line step.

Times, alternately on the same machine (pinned to one core where possible), the full
``MirrorSystem.step`` (the regression, each learned pattern's evidence and the detector with
the hands as taught), the same with a model that kept no taught hands, and the same compiled
step without the evidence and without the detector. Prints the medians and their ratios;
quote the ratios from one run (other processes change the absolute figures).

    .venv/bin/python benchmarks/bench_recognition.py [--steps N]
"""

from __future__ import annotations

import argparse
import os
import time
from dataclasses import replace


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=300)
    args = parser.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    from rnnpb import _xla

    _xla.configure()
    import jax
    import numpy as np

    from rnnpb.demonstrator import learning_set
    from rnnpb.model import MirrorSystem, NetworkConfig, TrainedModel
    from rnnpb.model.mirror import normalized_hands
    from rnnpb.model.network import init_params
    from rnnpb.model.online import initial_state, step_sessions
    from rnnpb.robot import JOINT_LIMITS

    network = NetworkConfig()
    sequences = learning_set("1", seed=0)
    rng = np.random.default_rng(0)
    lower = np.concatenate([np.zeros(network.sensory_size), JOINT_LIMITS[:, 0]])
    upper = np.concatenate([np.ones(network.sensory_size), JOINT_LIMITS[:, 1]])
    model = TrainedModel(
        network=network,
        params=init_params(network, jax.random.PRNGKey(0)),
        lower=lower,
        upper=upper,
        sequence_pb=rng.uniform(0.2, 0.8, (len(sequences), network.pb_size)),
        sequence_patterns=tuple(s.pattern for s in sequences),
        initial_context=np.full((len(sequences), network.context_size), 0.5),
        taught_sensory=np.array([s.sensory for s in sequences]),
    )
    mirror = MirrorSystem(model)
    untaught = MirrorSystem(replace(model, taught_sensory=None))
    state = initial_state(model, mirror.config)
    out = np.empty((1, mirror._layout.pattern_errors.stop), np.float32)

    def bare(u: np.ndarray) -> None:
        """The compiled step alone: no evidence asked for, no recognition on the host."""
        hands, seen = normalized_hands(u, network.sensory_size)
        step_sessions(
            mirror._net,
            mirror._meta,
            state,
            hands[None].astype(np.float32),
            seen[None],
            np.zeros(1, bool),
            mirror._candidates,
            mirror._phase_candidates,
            mirror._pattern_rho[:0],
            mirror._settings,
            out[:, : mirror._layout.context.stop],
            mirror._native,
        )

    stream = np.concatenate([s.sensory for s in sequences])
    for t in range(40):
        mirror.step(stream[t])
        untaught.step(stream[t])
        bare(stream[t])
    with_times, untaught_times, without_times = [], [], []
    for t in range(args.steps):
        u = stream[(40 + t) % len(stream)]
        t0 = time.perf_counter()
        mirror.step(u)
        t1 = time.perf_counter()
        untaught.step(u)
        t2 = time.perf_counter()
        bare(u)
        t3 = time.perf_counter()
        with_times.append((t1 - t0) * 1e3)
        untaught_times.append((t2 - t1) * 1e3)
        without_times.append((t3 - t2) * 1e3)
    with_ms, without_ms = float(np.median(with_times)), float(np.median(without_times))
    untaught_ms = float(np.median(untaught_times))
    print(f"on-line step with recognition and novelty:    {with_ms:7.3f} ms median")
    print(f"the same, a model without taught hands:       {untaught_ms:7.3f} ms median")
    print(f"the same step without evidence and detector:  {without_ms:7.3f} ms median")
    print(f"the detector costs {with_ms - without_ms:+.3f} ms ({with_ms / without_ms:.3f}x)")
    print(
        f"of which the taught hands {with_ms - untaught_ms:+.3f} ms ({with_ms / untaught_ms:.3f}x)"
    )


if __name__ == "__main__":
    main()
