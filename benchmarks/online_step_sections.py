"""Where the on-line step's time goes, by section.

Times, alternately on the same machine (pinned to one core, XLA single-threaded), with the
shipped model (learning set 1, the fast preset):

* the whole ``MirrorSystem.step`` under several regressions: the default, the paper's, the
  default without phase restarts, without restarts, with half and with no iterations (what is
  left with none is everything but the regression loop);
* the default step by section, as ``MirrorSystem.step`` runs it: the hands checked, the
  compiled call before the regression's loop (``online.prepare_sessions``), the native loop
  with its blocks filled and taken back (``online.fill_blocks``, ``native.run``,
  ``online.take_blocks``; with ``RNNPB_NATIVE=0``, or without llvmlite, the compiled loop
  ``online.regress_sessions``), the compiled call after it (``online.conclude_sessions``), the
  outputs unpacked, recognition on the host, the motor command;
* ``BatchedMirror``: B sessions in one call against one session's step;
* then the default step of one mirror system stepped alone, with nothing between its steps
  (in the alternating runs above, every step follows other systems' steps, which push its
  data out of the caches: the compiled calls take about twice as long there).

Prints medians and 99th percentiles and the ratios of medians to the default's; quote the
ratios from one run (other processes change the absolute figures).

    PYTHONPATH=src .venv/bin/python benchmarks/online_step_sections.py [--steps N] [--sessions B]
"""

from __future__ import annotations

import argparse
import os
import time


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--sessions", type=int, default=16)
    args = parser.parse_args()
    from rnnpb import _xla

    _xla.configure()
    _xla.single_threaded()
    _xla.compilation_cache()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    import numpy as np

    from rnnpb.demonstrator import learning_set
    from rnnpb.model import BatchedMirror, MirrorSystem, OnlineConfig, TrainedModel, online
    from rnnpb.model.mirror import motor_command, normalized_hands
    from rnnpb.model.online import OnlineState, StepOutputs
    from rnnpb.model.recognition import recognise
    from rnnpb.models import SHIPPED_MODEL

    model = TrainedModel.load(SHIPPED_MODEL)
    stream = np.concatenate([s.sensory for s in learning_set("1", seed=0)])
    default = OnlineConfig()
    variants = {
        "default": default,
        "paper": OnlineConfig.paper(),
        "no phase restarts": default.with_tuning(phase_restarts=0),
        "no restarts": default.with_tuning(restart_span=0),
        "half the iterations": OnlineConfig(iterations=default.iterations // 2),
        "no iterations": OnlineConfig(iterations=0),
    }
    systems = {name: MirrorSystem(model, config) for name, config in variants.items()}
    batched = BatchedMirror(model, args.sessions, default)
    offsets = np.arange(args.sessions) * 7

    def session_hands(t: int) -> np.ndarray:
        return stream[(t + offsets) % len(stream)]

    for t in range(40):
        for system in systems.values():
            system.step(stream[t])
        batched.step(session_hands(t))

    whole: dict[str, list[float]] = {name: [] for name in systems}
    whole[f"{args.sessions} sessions in one call"] = []
    native = systems["default"]._native
    calls = ("call before the loop", "native loop" if native else "compiled loop", "call after it")
    sections: dict[str, list[float]] = {
        name: [] for name in ("hands checked", *calls, "unpacked", "recognition", "motor command")
    }
    mirror = systems["default"]
    for t in range(args.steps):
        u_raw = stream[(40 + t) % len(stream)]
        for name, system in systems.items():
            t0 = time.perf_counter()
            system.step(u_raw)
            whole[name].append(time.perf_counter() - t0)
        hands = session_hands(40 + t)
        t0 = time.perf_counter()
        batched.step(hands)
        whole[f"{args.sessions} sessions in one call"].append(time.perf_counter() - t0)
        # The default's step by section, on a copy of its state (the mirror goes on as above).
        marks = [time.perf_counter()]
        u, seen = normalized_hands(u_raw, model.network.sensory_size)
        marks.append(time.perf_counter())
        state = OnlineState(*(np.array(part) for part in mirror._state))
        gates, kept = np.empty(1, np.float32), online.start_arrays(state)
        guarded = np.zeros(1, bool)
        settings = mirror._settings
        online.prepare_sessions(
            mirror._net,
            state,
            u[None].astype(np.float32),
            seen[None],
            mirror._candidates,
            mirror._phase_candidates,
            settings,
            gates,
            kept,
        )
        marks.append(time.perf_counter())
        if native is not None:
            layout, blocks = native.block_layout(), native.blocks(1)
            online.fill_blocks(mirror._net, state, gates, guarded, settings, layout, blocks)
            native.run(blocks)
            online.take_blocks(state, layout, blocks)
        else:
            online.regress_sessions(mirror._net, mirror._meta, state, gates, guarded, settings)
        marks.append(time.perf_counter())
        out = np.empty((1, mirror._layout.pattern_errors.stop), np.float32)
        online.conclude_sessions(
            mirror._net, mirror._meta, state, kept, guarded, mirror._pattern_rho, settings, out
        )
        packed = out[0].astype(np.float64)
        marks.append(time.perf_counter())
        outputs = StepOutputs(*(packed[part] for part in mirror._layout))
        marks.append(time.perf_counter())
        recognise(
            mirror._recognition,
            u,
            seen,
            outputs.pattern_errors,
            outputs.pb,
            mirror._learned_pb,
            mirror.patterns,
            mirror.recognition,
            mirror._taught,
        )
        marks.append(time.perf_counter())
        motor_command(model, outputs.motor)
        marks.append(time.perf_counter())
        for name, start, end in zip(sections, marks[:-1], marks[1:], strict=True):
            sections[name].append(end - start)

    base = float(np.median(whole["default"]))

    def line(name: str, times: list[float]) -> str:
        ms = np.asarray(times) * 1e3
        return (
            f"  {name + ':':<30}{np.median(ms):8.3f} ms median, {np.percentile(ms, 99):8.3f} "
            f"ms p99, {np.median(times) / base:5.2f}x the default step"
        )

    print(f"on-line step by regression ({args.steps} steps each, alternately):")
    for name, times in whole.items():
        print(line(name, times))
    print("the default step by section:")
    for name, times in sections.items():
        print(line(name, times))
    alone = MirrorSystem(model, default)
    for t in range(40):
        alone.step(stream[t])
    times = []
    for t in range(args.steps):
        t0 = time.perf_counter()
        alone.step(stream[(40 + t) % len(stream)])
        times.append(time.perf_counter() - t0)
    print("one mirror system stepped alone:")
    print(line("default", times))


if __name__ == "__main__":
    main()
