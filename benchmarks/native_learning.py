"""The learning's iterations, native (rnnpb.model.native_learning) beside JAX, on one core.

Three shapes of learning, each from the same start, timed alternately in chunks of 200
iterations (the chunk `rnnpb bench` times):

- the paper's learning of learning set 1 (6 sequences × 50 steps, momentum, no noise);
- the paper's learning of the larger set (8 × 50);
- a teaching consolidation's learning of the larger set: its 8 sequences and two new
  performances of 37 steps, input noise 0.03, the old network as the rehearsed sequences'
  teacher (the policy's, rnnpb.model.consolidation).

Prints each one's median per iteration both ways, their ratio, and the largest difference of
the weights after one chunk::

    PYTHONPATH=src .venv/bin/python benchmarks/native_learning.py [--repeats 9]

Pin it to one core (`taskset -c 0`) for figures to compare.
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def main() -> None:
    parser = argparse.ArgumentParser(description=str(__doc__).splitlines()[0])
    parser.add_argument("--repeats", type=int, default=9, help="timed chunks of each")
    args = parser.parse_args()
    from rnnpb import _xla

    _xla.single_threaded()
    _xla.configure()
    import jax
    import jax.numpy as jnp

    from rnnpb.demonstrator import learning_set
    from rnnpb.model import NetworkConfig
    from rnnpb.model.learning import Teacher, TrainConfig, chunk_runner, init_state, prepare_data
    from rnnpb.model.native import enabled
    from rnnpb.robot import JOINT_LIMITS

    if not enabled():
        raise SystemExit("native_learning: native code is off (llvmlite missing or RNNPB_NATIVE=0)")
    network = NetworkConfig()
    chunk = 200
    cases = []
    for name, data_set, noise, taught in (
        ("set 1, the paper's (6 x 50)", "1", 0.0, 0),
        ("larger set, the paper's (8 x 50)", "full", 0.0, 0),
        ("a consolidation of the larger set (10 sequences)", "full", 0.03, 8),
    ):
        sequences = list(learning_set(data_set, seed=0))
        if taught:  # two new performances: the first pattern's first 37 steps, mirrored
            for k in range(2):
                first = sequences[k]
                sequences.append(
                    type(first)(
                        first.sensory[:37, ::-1].copy(), first.motor[:37], "new-1", f"new {k}"
                    )
                )
        data = prepare_data(sequences, JOINT_LIMITS)
        config = TrainConfig.paper(input_noise=noise)
        state = init_state(data, network, config)
        n_seq = data.valid.shape[0]
        teacher = None
        if taught:
            teacher = Teacher(
                state.params,
                jax.nn.sigmoid(state.initial_context_logit),
                jnp.full((n_seq, network.pb_size), 0.5),
                jnp.arange(n_seq) < taught,
            )
        arguments = (
            jnp.asarray(data.inputs, jnp.float32),
            jnp.asarray(data.valid),
            chunk,
            jnp.ones(n_seq, bool),
            teacher,
        )
        runners = {"native": chunk_runner(config), "jax": chunk_runner(config, native=False)}
        ends = {
            name: jax.block_until_ready(run(state, *arguments)) for name, run in runners.items()
        }
        times: dict[str, list[float]] = {name: [] for name in runners}
        for _ in range(args.repeats):
            for runner, run in runners.items():
                start = time.perf_counter()
                jax.block_until_ready(run(state, *arguments))
                times[runner].append((time.perf_counter() - start) / chunk * 1e3)
        difference = max(
            float(np.max(np.abs(np.asarray(a) - np.asarray(b))))
            for a, b in zip(ends["native"].params, ends["jax"].params, strict=True)
        )
        cases.append((name, times, difference))
    print(
        f"the learning's iterations, ms per iteration, medians of {args.repeats} chunks of {chunk}:"
    )
    for name, times, difference in cases:
        native, reference = np.median(times["native"]), np.median(times["jax"])
        print(
            f"  {name:50s} native {native:.4f}  JAX {reference:.4f}  "
            f"({reference / native:.2f}x; weights within {difference:.1e})"
        )


if __name__ == "__main__":
    main()
