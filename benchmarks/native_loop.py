"""The on-line regression's loop alone, native (rnnpb.model.native) beside the same loop
compiled from the model's equations by numba (rnnpb.model.online), on one core.

A real window: the model's mirror system after 40 steps of the demonstrator's first pattern,
then the next observation; the default regression (100 iterations of the window's forward and
backward pass, the PB update and the onset's step) from the state the step's restarts leave.
Prints the two loops' medians, timed alternately, their ratio, and their largest difference::

    PYTHONPATH=src .venv/bin/python benchmarks/native_loop.py [--model MODEL] [--repeats 50]

``RNNPB_NATIVE_CPU=haswell`` and ``NUMBA_CPU_NAME=haswell NUMBA_CPU_FEATURES=`` time the code
built for an AVX2 processor.
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
    from rnnpb.demonstrator import held_scenario
    from rnnpb.model import MirrorSystem, OnlineConfig, TrainedModel, online
    from rnnpb.model.mirror import normalized_hands
    from rnnpb.model.native import NativeRegression, enabled
    from rnnpb.model.online import OnlineState
    from rnnpb.models import SHIPPED_MODEL

    if not enabled():
        raise SystemExit("native_loop: the native loop is off (llvmlite missing or RNNPB_NATIVE=0)")
    model = TrainedModel.load(args.model or SHIPPED_MODEL)
    config = OnlineConfig.for_model(model).config
    mirror = MirrorSystem(model, config, native=False)
    hands = held_scenario(model.patterns[0], n_steps=41, seed=3).sensory
    for u in hands[:-1]:
        mirror.step(u)
    u, seen = normalized_hands(hands[-1], model.network.sensory_size)
    start = OnlineState(*(np.array(part) for part in mirror._state))
    gates = np.empty(1, np.float32)
    saved = online.start_arrays(start)
    online.prepare_sessions(
        mirror._net,
        start,
        u[None].astype(np.float32),
        seen[None],
        mirror._candidates,
        mirror._phase_candidates,
        mirror._settings,
        gates,
        saved,
    )
    kernel = NativeRegression(model.params, model.network, config)
    layout, guarded = kernel.block_layout(), np.zeros(1, bool)

    def copy() -> OnlineState:
        return OnlineState(*(np.array(part) for part in start))

    def native() -> OnlineState:
        state, blocks = copy(), kernel.blocks(1)
        online.fill_blocks(mirror._net, state, gates, guarded, mirror._settings, layout, blocks)
        kernel.run(blocks)
        online.take_blocks(state, layout, blocks)
        return state

    def compiled() -> OnlineState:
        state = copy()
        online.regress_sessions(mirror._net, mirror._meta, state, gates, guarded, mirror._settings)
        return state

    expected, got = compiled(), native()
    times: dict[str, list[float]] = {"native": [], "numba": []}
    for _ in range(args.repeats):  # alternately, so that both see the same machine
        for name, call in (("native", native), ("numba", compiled)):
            t0 = time.perf_counter()
            call()
            times[name].append(time.perf_counter() - t0)
    ms = {name: float(np.median(values)) * 1e3 for name, values in times.items()}
    difference = max(
        float(np.max(np.abs(getattr(expected, name) - getattr(got, name))))
        for name in ("rho", "rho_velocity", "onset_context", "onset_motor")
    )
    print(
        f"the default regression ({config.iterations} iterations, L = {config.window}), one core:"
    )
    print(f"  native loop: {ms['native']:.3f} ms median")
    print(
        f"  numba loop:  {ms['numba']:.3f} ms median ({ms['numba'] / ms['native']:.2f}x the native)"
    )
    print(f"  largest difference (rho, momentum, onset): {difference:.1e}")


if __name__ == "__main__":
    main()
