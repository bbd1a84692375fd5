"""rnnpb bench: how fast learning, the on-line step and tracking run on this machine."""

from __future__ import annotations

import argparse
import os
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import numpy as np

    from rnnpb.model.routines import FollowStep, TwoLevelMirror

NAME = "bench"
HELP = "time learning, the on-line step and tracking (single-threaded)"
DESCRIPTION = """\
Print the speed of the parts that must keep up with real time, at the paper's sizes
(12 inputs/outputs, 4 PB, 40 hidden, 30 context units), pinned to one CPU core and
single-threaded, after warm-up:

  - one learning iteration on 6 sequences x 50 steps (BPTT + weight and PB updates), and
    the same with its iterations in JAX rather than native code (rnnpb.model.native_learning),
    timed alternately with it;
  - one on-line step (PB regression over a window of L = 30 steps, 100 iterations,
    then the motor command): median and 99th percentile, and the median of the same step
    without phase restarts, timed alternately with it (what they cost), and the step with
    the safety guard on (the default guard, the meta-level's barrier on the newest PB step
    in the regression, then the command filter's check before sending: docs/safety.md), and
    each guard's step alone (the barrier on the newest step, on 3 steps, on the whole
    window, the projection, and the meta-level as an on-line run has it: the barrier only
    where the PB drives the motion, the regime and the inhibition check every step);
  - side by side in the same run, each as median, 99th percentile and ratio to the first:
    the step with the paper's regression, with the default one, the default one with its
    regression loop compiled from the model's equations by numba (rnnpb.model.online) rather
    than in native code (rnnpb.model.native), with the default one
    and its detectors and the safety guard (barrier and command filter), the step per session
    of 16 sessions stepped in one call (rnnpb.model.BatchedMirror), with the ratio of the
    16 sessions' call to one default step, and the two-level step (docs/routines.md: the
    shipped model's own step with the prior from the routine level above it, then the
    routine level's observe, on a routine performed by the synthetic user), with
    the routine level's part of it, the share of steps the prior went down on, and the
    budget it must stay within, the step period dt;
  - the same on-line step in float64 (the reference the tests hold the float32 one to),
    and the ratio;
  - colour-ball tracking of 640x480 frames;
  - bare-hand pose tracking of 640x480 frames of a photographed person, following the body
    and finding it afresh, median and 95th percentile (with the `rnnpb[hands]` extra; without
    it, one line says so);
  - two coupled agents (docs/dyad.md): one step of both against one agent's step, one after
    the other and side by side, in a process of their own on up to two cores.

--json FILE writes the same figures (keys train_iteration_ms_median,
online_step_ms_median, online_step_ms_p99, online_step_two_level_ms_median, ...) with the
machine and versions.
"""


BATCHED_SESSIONS = 16
"""Sessions of the batched figure: a study's draws of one model, or a room of users."""

SAFETY_GUARD_TIMED = "barrier"
"""The guard of the "safety on" figure: the one a map switches on by default
(``OnlineConfig.safety_guard``)."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--json", metavar="FILE", help="also write the figures as JSON")
    parser.add_argument("--steps", type=int, default=300, help="timed on-line steps (default 300)")
    parser.add_argument(
        "--reference-steps", type=int, default=5, help="timed float64 reference steps (default 5)"
    )
    parser.add_argument("--no-tracking", action="store_true", help="skip the tracking bench")
    parser.add_argument(
        "--no-progress",
        action="store_true",
        help="no progress bar (there is none when stderr is not a terminal)",
    )


_CORES: list[int] = []  # the cores the process could use before _single_core pinned it


def _single_core() -> str:
    """Pin this process to one core and make XLA single-threaded (before JAX starts)."""
    import sys

    from rnnpb import _xla

    _xla.single_threaded()
    note = "single core"
    if hasattr(os, "sched_setaffinity"):
        cores = sorted(os.sched_getaffinity(0))
        _CORES[:] = cores  # the dyad's side-by-side figure uses two of them
        os.sched_setaffinity(0, {cores[0]})
        note = f"pinned to core {cores[0]}"
    if "jax" in sys.modules:
        note += " (JAX was already loaded: XLA may use more threads)"
    note += ", loops compiled whole" if _xla.active() else ", XLA's default loop compilation"
    return note


def run(args: argparse.Namespace) -> int:
    from rnnpb.commands._checks import step_count

    # Before the half-minute of timing: a median of no steps is no figure.
    step_count("--steps", args.steps, high=1_000_000)
    step_count("--reference-steps", args.reference_steps, high=10_000)
    note = _single_core()
    import json
    import platform
    import time
    from dataclasses import replace

    import jax
    import numpy as np

    from rnnpb import __version__
    from rnnpb._atomic import atomic_write
    from rnnpb.commands.progress import progress_bar
    from rnnpb.demonstrator import learning_set
    from rnnpb.model import (
        MIRROR_SYSTEMS,
        BatchedMirror,
        MirrorSystem,
        NetworkConfig,
        OnlineConfig,
        learning,
    )
    from rnnpb.robot import JOINT_LIMITS

    parts = ["learning", "routine level", "on-line step", "float64 reference"] + (
        [] if args.no_tracking else ["tracking"]
    )
    bar = progress_bar(
        total=len(parts),
        unit="part",
        desc="bench",
        disable=args.no_progress,
        bar_format="{desc}: {n}/{total} parts [{elapsed}]{postfix}",
    )

    def next_part(done: bool = True) -> None:
        if done:
            bar.update(1)
        if bar.n < len(parts):
            bar.set_postfix_str(parts[bar.n])

    next_part(done=False)
    network = NetworkConfig()
    sequences = learning_set("1", seed=0)
    data = learning.prepare_data(sequences, JOINT_LIMITS)
    chunk_times = learning_chunk_times(data, network)
    train_ms = float(np.median(chunk_times["native"]))
    train_jax_ms = float(np.median(chunk_times["JAX"]))
    next_part()

    # The two-level step needs a lower model that knows the patterns (the shipped one) and
    # routines learned over it.
    routine_level = _routine_level()
    next_part()

    # The network's arithmetic costs the same for any weights: time it with a fresh network.
    # It recognises no pattern, so recognition's structure test runs on every step: the step
    # timed is the one of a movement the robot does not know (following a learned pattern
    # skips that test).
    model = bench_model(network, sequences, data)
    online = OnlineConfig()
    # The default step and the same step without phase restarts, timed alternately so that
    # both see the same machine: the difference is what phase restarts cost.
    compiled = MIRROR_SYSTEMS["compiled"]
    mirror = compiled(model, online)
    plain = compiled(model, online.with_tuning(phase_restarts=0))
    # The default step with its regression loop compiled from the equations by numba (what
    # rnnpb.model.native's loop is held to), side by side with the native loop.
    numba_loop = MirrorSystem(model, online, native=False)
    # The safety-on steps: a risk network of the stored size (its weights do not change the
    # cost) guarding the regression — the barrier on the newest steps (the default span), the
    # barrier on the whole window, the projection — and the command filter before sending.
    from rnnpb.safety import CommandFilter, MetaConfig, init_meta

    meta = init_meta(network.pb_size, MetaConfig().hidden, 0)
    guards = {
        "barrier": replace(online, safety_guard="barrier"),
        "barrier_3_steps": replace(online, safety_guard="barrier").with_tuning(barrier_span=3),
        "barrier_window": replace(online, safety_guard="barrier").with_tuning(barrier_span=0),
        "projection": replace(online, safety_guard="projection"),
    }
    guarded = {name: compiled(model, cfg, meta=meta) for name, cfg in guards.items()}
    # The meta-level as an on-line run has it (rnnpb.safety.online_safety): the barrier only
    # where the PB drives the motion, the regime and the inhibition check on every step.
    guarded["meta_level"] = compiled(
        model, guards["barrier"], meta=meta, steering="pb_driven", inhibition=True
    )
    command_filter = CommandFilter()
    # The paper's regression, and many sessions of the default in one call, each session at
    # its own place in the stream (its own phase).
    paper = compiled(model, OnlineConfig.paper())
    batched = BatchedMirror(model, BATCHED_SESSIONS, online)
    stream = np.concatenate([s.sensory for s in sequences])
    offsets = np.arange(BATCHED_SESSIONS) * 7

    def session_hands(t: int) -> np.ndarray:
        return stream[(t + offsets) % len(stream)]

    two_level, routine_stream, follower_times, step_period = routine_level
    due = False  # the higher level said a switch is due: the prior goes down next step
    for t in range(40):
        due = two_level.step(routine_stream[t % len(routine_stream)]).higher.switch_due
        mirror.step(stream[t])
        plain.step(stream[t])
        numba_loop.step(stream[t])
        paper.step(stream[t])
        batched.step(session_hands(t))
        for system in guarded.values():
            command_filter(system.step(stream[t]).motor)
    step_times, plain_times, paper_times, batched_times = [], [], [], []
    numba_times: list[float] = []
    two_level_times: list[float] = []
    follower_times.clear()
    prior_steps = 0
    # Also the processor time of each step: on a shared machine the wall-clock time includes
    # waiting for a core, the processor time does not (the ratios are measured in one run).
    cpu_times: dict[str, list[float]] = {name: [] for name in ("off", *guarded)}
    guarded_times: dict[str, list[float]] = {name: [] for name in guarded}
    filter_times: dict[str, list[float]] = {name: [] for name in guarded}
    for t in range(args.steps):
        u = stream[(40 + t) % len(stream)]
        for system, times in (
            (mirror, step_times),
            (plain, plain_times),
            (numba_loop, numba_times),
            (paper, paper_times),
        ):
            t0, c0 = time.perf_counter(), time.process_time()
            system.step(u)
            times.append((time.perf_counter() - t0) * 1e3)
            if system is mirror:
                cpu_times["off"].append((time.process_time() - c0) * 1e3)
        for name, system in guarded.items():
            t0, c0 = time.perf_counter(), time.process_time()
            command = system.step(u).motor
            cpu_times[name].append((time.process_time() - c0) * 1e3)
            t1 = time.perf_counter()
            command_filter(command)
            t2 = time.perf_counter()
            guarded_times[name].append((t1 - t0) * 1e3)
            filter_times[name].append((t2 - t1) * 1e3)
        hands = session_hands(40 + t)
        t0 = time.perf_counter()
        batched.step(hands)
        batched_times.append((time.perf_counter() - t0) * 1e3)
        prior_steps += due
        t0 = time.perf_counter()
        said = two_level.step(routine_stream[(40 + t) % len(routine_stream)])
        two_level_times.append((time.perf_counter() - t0) * 1e3)
        due = said.higher.switch_due
    step_times = np.asarray(step_times)
    next_part()

    # The same step, same model and config, in float64: the reference.
    reference = MIRROR_SYSTEMS["reference"](model, online)
    for t in range(online.window - 1):
        reference.step(stream[t])
    reference_times = []
    for t in range(args.reference_steps):
        t0 = time.perf_counter()
        reference.step(stream[online.window + t])
        reference_times.append((time.perf_counter() - t0) * 1e3)
    reference_ms = float(np.median(reference_times))
    next_part()

    # Two coupled agents (rnnpb.interaction.dyad), in a process of their own that may use two
    # cores (this one is pinned to one, and XLA sizes its threads when it starts).
    dyad_figures = _dyad_figures(model, online, args.steps)

    # Side by side: each as a median, a 99th percentile and a ratio to the paper's step.
    guarded_with_filter = np.add(
        guarded_times[SAFETY_GUARD_TIMED], filter_times[SAFETY_GUARD_TIMED]
    )
    side_by_side = {
        "paper": np.asarray(paper_times),
        "default": step_times,
        "default_numba": np.asarray(numba_times),
        "default_guarded": guarded_with_filter,
        "batched_per_session": np.asarray(batched_times) / BATCHED_SESSIONS,
        "two_level": np.asarray(two_level_times),
    }
    paper_median = float(np.median(paper_times))
    compared: dict[str, float] = {}
    for name, times in side_by_side.items():
        compared[f"step_{name}_ms_median"] = float(np.median(times))
        compared[f"step_{name}_ms_p99"] = float(np.percentile(times, 99))
        compared[f"step_{name}_vs_paper"] = float(np.median(times)) / paper_median
    compared["batched_sessions"] = float(BATCHED_SESSIONS)
    compared["batched_step_ms_median"] = float(np.median(batched_times))
    compared["batched_step_vs_default"] = float(np.median(batched_times)) / float(
        np.median(step_times)
    )
    # The routine level's own part of the two-level step, the steps the prior went down on,
    # and the budget: the step period, by which the next hands arrive.
    compared["step_two_level_follower_ms_median"] = float(np.median(follower_times))
    compared["step_two_level_follower_ms_p99"] = float(np.percentile(follower_times, 99))
    compared["step_two_level_follower_share"] = float(np.median(follower_times)) / float(
        np.median(two_level_times)
    )
    compared["step_two_level_prior_share"] = prior_steps / args.steps
    compared["step_budget_ms"] = step_period * 1e3

    figures = {
        "train_iteration_ms_median": train_ms,
        "train_50k_iterations_s_estimate": train_ms * 50.0,
        "train_iteration_jax_ms_median": train_jax_ms,
        "online_step_ms_median": float(np.median(step_times)),
        "online_step_ms_p99": float(np.percentile(step_times, 99)),
        "online_step_without_phase_restarts_ms_median": float(np.median(plain_times)),
        # The step with the guard the default uses when a map exists (the barrier on the
        # newest steps), plus the filter; then each guard's step alone.
        "online_step_safety_on_ms_median": float(
            np.median(np.add(guarded_times[SAFETY_GUARD_TIMED], filter_times[SAFETY_GUARD_TIMED]))
        ),
        **{
            f"online_step_{name}_ms_median": float(np.median(times))
            for name, times in guarded_times.items()
        },
        "command_filter_ms_median": float(np.median(filter_times[SAFETY_GUARD_TIMED])),
        **{
            f"online_step_{name}_cpu_ms_median": float(np.median(times))
            for name, times in cpu_times.items()
        },
        "online_step_reference_ms_median": reference_ms,
        "online_speedup_vs_reference": reference_ms / float(np.median(step_times)),
        **{f"online_{key}": value for key, value in compared.items()},
        **dyad_figures,
    }
    if not args.no_tracking:
        from rnnpb.perception import tracking_benchmark

        tracking = tracking_benchmark()
        figures["tracking_frames_per_s"] = float(tracking["fps"])
        figures["tracking_ms_median"] = float(tracking["median_ms"])
        figures["tracking_clean_error_px"] = float(tracking["clean_error_px"])
        figures["tracking_noisy_error_px"] = float(tracking["noisy_error_px"])
        from rnnpb.perception import pose_available, pose_benchmark

        if pose_available():
            pose = pose_benchmark()
            figures["pose_tracking_ms_median"] = float(pose["median_ms"])
            figures["pose_tracking_ms_p90"] = float(pose["p90_ms"])
            figures["pose_tracking_ms_p95"] = float(pose["p95_ms"])
            figures["pose_tracking_cpu_ms_median"] = float(pose["cpu_median_ms"])
            figures["pose_detection_ms_median"] = float(pose["detect_median_ms"])
            figures["pose_detection_ms_p95"] = float(pose["detect_p95_ms"])
            figures["pose_detection_cpu_ms_median"] = float(pose["detect_cpu_median_ms"])
        next_part()
    bar.close()

    print(
        f"rnnpb {__version__} bench — {note}, jax {jax.__version__}, "
        f"{platform.processor() or platform.machine()}"
    )
    print(f"  {processor_note()}")
    print(
        f"  learning iteration (6 seq x 50 steps):   {train_ms:8.3f} ms median "
        f"(50,000 iterations ~ {train_ms * 50:.0f} s)"
    )
    print(
        f"  the same, its iterations in JAX:         {train_jax_ms:8.3f} ms median "
        f"({train_jax_ms / train_ms:.2f}x the native)"
    )
    print(
        f"  on-line step (L={online.window}, {online.iterations} it.): "
        f"{figures['online_step_ms_median']:8.3f} ms median, "
        f"{figures['online_step_ms_p99']:.3f} ms p99 (over {args.steps} steps)"
    )
    cost = (
        figures["online_step_ms_median"] / figures["online_step_without_phase_restarts_ms_median"]
        - 1
    )
    print(
        f"  on-line step without phase restarts:     "
        f"{figures['online_step_without_phase_restarts_ms_median']:8.3f} ms median "
        f"(phase restarts cost {cost:+.0%})"
    )
    print(
        f"  on-line step, safety on ({SAFETY_GUARD_TIMED}+filter):"
        f"{figures['online_step_safety_on_ms_median']:8.3f} ms median (the filter "
        f"{figures['command_filter_ms_median']:.3f} ms of it)"
    )
    print(
        f"    processor time per step (no waiting for a core): guard off "
        f"{figures['online_step_off_cpu_ms_median']:.3f} ms median"
    )
    for name in guarded:
        label = {
            "barrier": "barrier (newest step)",
            "barrier_3_steps": "barrier on 3 steps",
            "barrier_window": "barrier on the window",
            "meta_level": "meta-level (steering where the PB drives, inhibition)",
        }.get(name, name)
        print(
            f"    the step with the {label} alone: "
            f"{figures[f'online_step_{name}_ms_median']:8.3f} ms median, processor time "
            f"{figures[f'online_step_{name}_cpu_ms_median']:.3f} ms"
        )
    print("  side by side in this run (median, p99, ratio of medians to the paper's step):")
    labels = {
        "paper": "the paper's regression",
        "default": "the default",
        "default_numba": "the default, its loop by numba",
        "default_guarded": "default, detectors, guard and filter",
        "batched_per_session": f"per session of {BATCHED_SESSIONS} in one call",
        "two_level": "two levels (routines, with the prior)",
    }
    for name, label in labels.items():
        if name == "two_level":
            continue
        print(
            f"    {label + ':':<39}{figures[f'online_step_{name}_ms_median']:8.3f} ms median, "
            f"{figures[f'online_step_{name}_ms_p99']:.3f} ms p99, "
            f"{figures[f'online_step_{name}_vs_paper']:.2f}x"
        )
    print(
        f"    {f'{BATCHED_SESSIONS} sessions in one call:':<39}"
        f"{figures['online_batched_step_ms_median']:8.3f} ms median "
        f"({figures['online_batched_step_vs_default']:.2f}x one default step)"
    )
    print(
        f"    {labels['two_level'] + ':':<39}{figures['online_step_two_level_ms_median']:8.3f} "
        f"ms median, {figures['online_step_two_level_ms_p99']:.3f} ms p99, "
        f"{figures['online_step_two_level_vs_paper']:.2f}x"
    )
    print(
        f"      the routine level's part:           "
        f"{figures['online_step_two_level_follower_ms_median']:8.3f} ms median, "
        f"{figures['online_step_two_level_follower_ms_p99']:.3f} ms p99 "
        f"({figures['online_step_two_level_follower_share']:.0%} of the step)"
    )
    print(
        f"      the prior went down on {figures['online_step_two_level_prior_share']:.0%} of "
        f"the steps; budget: the step period dt, {figures['online_step_budget_ms']:.0f} ms "
        f"(the p99 is "
        f"{figures['online_step_two_level_ms_p99'] / figures['online_step_budget_ms']:.1%} "
        "of it)"
    )
    print(
        f"  on-line step, the float64 reference:    {reference_ms:8.3f} ms median "
        f"(over {args.reference_steps} steps; the float32 step "
        f"{figures['online_speedup_vs_reference']:.1f}x faster)"
    )
    cores = int(figures["dyad_cores"])
    print(
        f"  two coupled agents, one step of both:    "
        f"{figures['dyad_step_ms_median']:8.3f} ms median "
        f"({figures['dyad_step_vs_one_agent']:.2f}x one agent's step of "
        f"{figures['dyad_step_one_agent_ms_median']:.3f} ms, one after the other)"
    )
    print(
        f"{f'    side by side, on {cores} core' + ('s:' if cores > 1 else ':'):<43}"
        f"{figures['dyad_step_side_by_side_ms_median']:8.3f} ms median "
        f"({figures['dyad_step_side_by_side_vs_one_agent']:.2f}x; processor time "
        f"{figures['dyad_step_side_by_side_cpu_vs_one_agent']:.2f}x)"
    )
    if "tracking_frames_per_s" in figures:
        print(
            f"  colour-ball tracking 640x480:            {figures['tracking_ms_median']:8.3f} "
            f"ms median ({figures['tracking_frames_per_s']:.0f} frames/s); centre error "
            f"{figures['tracking_clean_error_px']:.2f} px clean, "
            f"{figures['tracking_noisy_error_px']:.2f} px noisy"
        )
        if "pose_tracking_ms_median" in figures:
            print(
                f"  bare-hand pose tracking 640x480:         "
                f"{figures['pose_tracking_ms_median']:8.3f} ms median, "
                f"{figures['pose_tracking_ms_p95']:.3f} ms p95, processor time "
                f"{figures['pose_tracking_cpu_ms_median']:.3f} ms (target 40 ms)"
            )
            print(
                f"    finding the body afresh:               "
                f"{figures['pose_detection_ms_median']:8.3f} ms median, "
                f"{figures['pose_detection_ms_p95']:.3f} ms p95, processor time "
                f"{figures['pose_detection_cpu_ms_median']:.3f} ms"
            )
        else:
            from rnnpb.perception import HANDS_INSTALL

            print(f"  bare-hand pose tracking: not measured, no pose model ({HANDS_INSTALL})")
    if args.json:
        document = {
            **figures,
            "rnnpb_version": __version__,
            "jax_version": jax.__version__,
            "machine": platform.machine(),
            "python": platform.python_version(),
            "note": note,
            "processor": processor_note(),
            "online_config": online.to_dict(),
        }
        with atomic_write(args.json, "w", encoding="utf-8") as handle:
            json.dump(document, handle, indent=2)
        print(f"wrote {args.json}")
    return 0


def bench_model(network, sequences, data):
    """The network the steps are timed with: the paper's sizes, fresh random weights (the
    arithmetic costs the same for any), learning set ``sequences``' patterns and, as a model
    learned today keeps them, their taught hands (``data``), which recognition matches what
    it sees against."""
    import jax
    import numpy as np

    from rnnpb.model import TrainedModel
    from rnnpb.model.network import init_params

    rng = np.random.default_rng(0)
    return TrainedModel(
        network=network,
        params=init_params(network, jax.random.PRNGKey(0)),
        lower=data.lower,
        upper=data.upper,
        sequence_pb=rng.uniform(0.2, 0.8, (len(sequences), network.pb_size)),
        sequence_patterns=data.patterns,
        initial_context=np.full((len(sequences), network.context_size), 0.5),
        taught_sensory=data.inputs[..., : network.sensory_size].astype(np.float64),
    )


def learning_chunk_times(data, network, chunk: int = 200, repeats: int = 7) -> dict:
    """Milliseconds per learning iteration of the paper's learning on ``data``, per chunk of
    ``chunk`` iterations, ``repeats`` chunks after a warm-up one: ``native`` (the learning's
    default chunk, native where it runs) and ``JAX`` (the compiled JAX chunk), alternately."""
    import time

    import jax

    from rnnpb.model import learning
    from rnnpb.model.learning import TrainConfig

    config = TrainConfig.paper()
    state = learning.init_state(data, network, config)
    inputs = jax.numpy.asarray(data.inputs, jax.numpy.float32)
    valid = jax.numpy.asarray(data.valid)
    every_pb = jax.numpy.ones(data.valid.shape[0], bool)
    runners = {
        "native": learning.chunk_runner(config),
        "JAX": learning.chunk_runner(config, native=False),
    }
    times: dict[str, list[float]] = {name: [] for name in runners}
    for repeat in range(repeats + 1):
        for name, run_chunk in runners.items():
            t0 = time.perf_counter()
            jax.block_until_ready(run_chunk(state, inputs, valid, chunk, every_pb))
            if repeat:  # the first is the warm-up
                times[name].append((time.perf_counter() - t0) / chunk * 1e3)
    return times


def processor_note() -> str:
    """The processor and the instruction sets the compiled code was built for: the native
    loops' (``RNNPB_NATIVE_CPU``, else this processor's) and numba's (``NUMBA_CPU_NAME``,
    else this processor's)."""
    import importlib

    name = ""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as info:
            name = next(
                (line.split(":", 1)[1].strip() for line in info if "model name" in line), ""
            )
    except OSError:
        pass
    llvm = importlib.import_module("llvmlite.binding")
    host = llvm.get_host_cpu_name()
    features = llvm.get_host_cpu_features().flatten()
    isa = "AVX-512" if "+avx512f" in features else "AVX2" if "+avx2" in features else "SSE"
    native = os.environ.get("RNNPB_NATIVE_CPU") or host
    numba = os.environ.get("NUMBA_CPU_NAME") or host
    return (
        f"processor {name or 'unknown'} ({host}, {isa}); native loops built for {native}, "
        f"numba's code for {numba}"
    )


ROUTINE_LEARNED_DRAW = 201
"""The demonstrator's draw the bench's routines are learned from (a development draw of the
routines study, never an exam draw)."""
ROUTINE_PERFORMED_DRAW = 101
"""The demonstrator's draw that performs routine A in the timed stream (another development
draw: the routines are followed, not replayed)."""
ROUTINE_REPEATS = 4
"""Times the timed stream performs routine A in a row (about 450 steps, more than the default
run's; a longer run starts it over)."""


def _routine_level() -> tuple[TwoLevelMirror, np.ndarray, list[float], float]:
    """The two levels (:class:`rnnpb.model.routines.TwoLevelMirror`, with the prior) over
    the shipped model, with the on-line regression ``interact --routines`` chooses for it:
    the routines study's two routines learned over it, and routine A performed by the
    demonstrator, several times in a row. Returns the two-level mirror (its follower appends
    the milliseconds of each ``observe`` to the returned list), the hands stream, that list
    and the model's step period dt (s).

    The routines are learned (:func:`~rnnpb.model.routines.learn_from_events`, the default
    :class:`~rnnpb.model.routines.RoutineLearning`) from one performance of each, twice in a
    row (so that the level knows how the routine starts over), cut into segments at the
    demonstrator's own switch steps rather than from the lower level's PB run over the
    recording as ``learn_routines`` does: the codes and the order are the same, the
    boundaries a step or two apart, and the bench saves running the recordings through the
    lower level."""
    import time

    import numpy as np

    from rnnpb.demonstrator import routine_scenario
    from rnnpb.experiments.scenarios.routines import ROUTINES
    from rnnpb.model import TrainedModel
    from rnnpb.model.routines import (
        RoutineFollower,
        RoutineLearning,
        Segment,
        SegmentConfig,
        TwoLevelMirror,
        learn_from_events,
        routine_events,
    )
    from rnnpb.models import SHIPPED_MODEL

    lower = TrainedModel.load(SHIPPED_MODEL)
    names = list(lower.pattern_pb)
    codes = np.array(list(lower.pattern_pb.values()))
    events = []
    for parts in ROUTINES.values():
        performed = routine_scenario(parts, seed=ROUTINE_LEARNED_DRAW, repeats=2)
        bounds = [0, *performed.switch_steps, performed.n_steps]
        segments = []
        for start, stop in zip(bounds[:-1], bounds[1:], strict=True):
            k = names.index(performed.labels[start])
            segments.append(Segment(start, stop, codes[k], k))
        events.append(routine_events(segments))
    routines = learn_from_events(
        lower.fingerprint, codes, list(ROUTINES), events, RoutineLearning(), SegmentConfig()
    )
    times: list[float] = []

    class TimedFollower(RoutineFollower):
        """The follower, timing its own share of each two-level step."""

        def observe(self, lower_pb: np.ndarray) -> FollowStep:
            t0 = time.perf_counter()
            said = super().observe(lower_pb)
            times.append((time.perf_counter() - t0) * 1e3)
            return said

    stream = routine_scenario(
        ROUTINES["A"], seed=ROUTINE_PERFORMED_DRAW, repeats=ROUTINE_REPEATS
    ).sensory
    # Compile the step with a prior (one more restart candidate) before any timing.
    warm = TwoLevelMirror(lower, routines)
    warm.mirror.step(stream[0], prior_pb=codes[0])
    two_level = TwoLevelMirror(lower, routines)
    two_level.follower = TimedFollower(routines)
    return two_level, stream, times, lower.dt


def _dyad_worker_start(cores: list[int]) -> None:
    from rnnpb import _xla

    _xla.configure()
    _xla.single_threaded()
    _xla.compilation_cache()
    if cores and hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, set(cores))


def _dyad_figures(model: Any, online: Any, steps: int) -> dict[str, float]:
    """Time two coupled agents against one, in a fresh process on up to two cores."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    cores = _CORES[:2]
    with ProcessPoolExecutor(
        1,
        mp_context=multiprocessing.get_context("spawn"),
        initializer=_dyad_worker_start,
        initargs=(cores,),
    ) as pool:
        return pool.submit(dyad_timing, model, online, steps).result()


def dyad_timing(model: Any, online: Any, steps: int) -> dict[str, float]:
    """One step of two coupled agents (each regressing, moving its body and showing it)
    against one agent's step, alternately: the agents one after the other, and side by side
    (:class:`rnnpb.interaction.dyad.Dyad`). The single agent watches a robot moving as the
    dyad's agents do (its own partner, which it follows), so that it sees the same kind of
    movement. Medians of wall-clock and of processor time (all threads), in ms and as ratios."""
    import time

    import numpy as np

    from rnnpb.interaction.dyad import Dyad, RobotAgent, usable_cores

    def agents() -> tuple[RobotAgent, RobotAgent]:
        return RobotAgent(model, online=online, name="a"), RobotAgent(
            model, online=online, name="b"
        )

    figures: dict[str, float] = {"dyad_cores": float(usable_cores())}
    kinds = {"dyad_step": False, "dyad_step_side_by_side": True}
    for prefix, side_by_side in kinds.items():
        pair = Dyad(*agents(), side_by_side=side_by_side)
        watcher = Dyad(*agents(), side_by_side=False)
        solo, partner = watcher.a, watcher.b
        for _ in range(40):
            pair.step()
            watcher.step()
        both, one, both_cpu, one_cpu = [], [], [], []
        for _ in range(steps):
            t0, c0 = time.perf_counter(), time.process_time()
            pair.step()
            both.append(time.perf_counter() - t0)
            both_cpu.append(time.process_time() - c0)
            view = watcher.view(partner)
            t0, c0 = time.perf_counter(), time.process_time()
            solo.act(view)
            one.append(time.perf_counter() - t0)
            one_cpu.append(time.process_time() - c0)
            partner.act(watcher.view(solo))  # the partner moves on, untimed
        figures[f"{prefix}_ms_median"] = float(np.median(both)) * 1e3
        figures[f"{prefix}_vs_one_agent"] = float(np.median(both) / np.median(one))
        figures[f"{prefix}_cpu_vs_one_agent"] = float(np.median(both_cpu) / np.median(one_cpu))
        figures[f"{prefix}_one_agent_ms_median"] = float(np.median(one)) * 1e3
    return figures
