"""The on-line regression's loop alone, native (rnnpb.model.native) beside JAX, on one core.

A real window: the model's mirror system after 40 steps of the demonstrator's first pattern,
then the next observation; the default regression (100 iterations of the window's forward and
backward pass, the PB update and the onset's step) from the state the step's restarts leave.
Prints the two loops' medians, timed alternately, their ratio, and their largest difference::

    PYTHONPATH=src .venv/bin/python benchmarks/native_loop.py [--model MODEL] [--repeats 50]
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def main() -> None:
    parser = argparse.ArgumentParser(description=str(__doc__).splitlines()[0])
    parser.add_argument("--model", help="a learned model (default: the shipped one)")
    parser.add_argument("--repeats", type=int, default=50, help="timed regressions of each")
    args = parser.parse_args()
    from rnnpb import _xla

    _xla.single_threaded()
    _xla.configure()
    import jax

    from rnnpb.demonstrator import held_scenario
    from rnnpb.model import MirrorSystem, OnlineConfig, TrainedModel
    from rnnpb.model.native import NativeRegression, enabled, prepare_block
    from rnnpb.model.online import regression
    from rnnpb.models import SHIPPED_MODEL

    if not enabled():
        raise SystemExit("native_loop: the native loop is off (llvmlite missing or RNNPB_NATIVE=0)")
    model = TrainedModel.load(args.model or SHIPPED_MODEL)
    config = OnlineConfig.for_model(model).config
    mirror = MirrorSystem(model, config, native=False)
    hands = held_scenario(model.patterns[0], n_steps=41, seed=3).sensory
    for u in hands[:-1]:
        mirror.step(u)
    u = hands[-1].astype(np.float32)
    start, block = prepare_block(
        mirror._params,
        mirror._state,
        u,
        np.isfinite(u),
        config,
        mirror._candidates,
        mirror._phase_candidates,
    )
    kernel = NativeRegression(mirror._params, model.network, config)
    jax_loop = jax.jit(regression, static_argnames=("config",))
    gate = None  # the default regression is not gated

    def in_jax():
        return jax.block_until_ready(jax_loop(mirror._params, start, gate, config))

    expected, got = in_jax(), kernel(block)
    times: dict[str, list[float]] = {"native": [], "jax": []}
    for _ in range(args.repeats):  # alternately, so that both see the same machine
        for name, call in (("native", lambda: kernel(block)), ("jax", in_jax)):
            t0 = time.perf_counter()
            call()
            times[name].append(time.perf_counter() - t0)
    ms = {name: float(np.median(values)) * 1e3 for name, values in times.items()}
    difference = max(
        float(np.max(np.abs(np.asarray(a) - b))) for a, b in zip(expected, got, strict=True)
    )
    print(
        f"the default regression ({config.iterations} iterations, L = {config.window}), one core:"
    )
    print(f"  native loop: {ms['native']:.3f} ms median")
    print(f"  JAX loop:    {ms['jax']:.3f} ms median ({ms['jax'] / ms['native']:.2f}x the native)")
    print(f"  largest difference (rho, momentum, onset): {difference:.1e}")


if __name__ == "__main__":
    main()
