"""rnnpb train: learn movement patterns from sequence files."""

from __future__ import annotations

import argparse

from rnnpb.commands._config import add_config_argument

NAME = "train"
CONFIG_SECTIONS = ("learning",)
SAFE_POINTS = True  # Ctrl-C stops between training chunks (rnnpb._interrupt)
HELP = "learn movement patterns from sequence CSV files"
DESCRIPTION = """\
Learn movement patterns from demonstrations: paired user-hand / robot-joint sequences.

Each CSV file has a header row and one row per step with the columns
  step, lhy lhz rhy rhz (user hands in the camera view plane, 0..1),
  lshp lshr lshy lelp rshp rshr rshy relp (robot joints, radians)
and optionally `pattern` (the pattern's name). Without a `pattern` column the file name
names it: wave_1.csv and wave_2.csv are two samples of pattern `wave`.
Motor values are normalized by the robot's joint limits (they must lie within them).

Presets: `paper` is the paper's algorithm (gradient descent with momentum, 50,000
iterations); `fast` uses Adam with noise on the inputs and needs about 3,000 iterations.
Options given explicitly override the preset; --config FILE overrides any of its [learning]
values (the optimizer, the rates, the PB update's coefficients: docs/model.md). The model
records the preset's name and version (`rnnpb info`).

Every step of the data is checked first, by the check `rnnpb record` writes by: a hand outside
the view ([0, 1]) or a joint outside its limits, and the robot's own safety checker: a step
whose joint angles put an arm through the body or the other arm, or move a joint faster than
its servo can, is refused (one line naming the file and the step) unless --allow-unsafe (which
still refuses values outside their ranges); `rnnpb record`'s data always pass.

Step time: a model is learned at one step time and plays at it only (`rnnpb interact` and
`serve` refuse another). It is the dt the data folders' recording.json files (written by
`rnnpb record`) agree on, else --dt, else the paper's 0.4 s; `rnnpb info` shows it.
Framing: data recorded from a person's body (motion capture, bare hands) were framed at a
distance in the robot camera's view; the folders must agree on it, the model keeps it, and a
person the model watches is framed alike.

A checkpoint is written next to the model (MODEL.checkpoint.npz) every
--checkpoint-every iterations; --resume continues from it. Once the model is written the
checkpoint is removed (--keep-checkpoint keeps it); an interrupted run keeps it.

Example:
  rnnpb data --out data/
  rnnpb train --data data/patterns --out model.npz --preset fast
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--data",
        nargs="+",
        required=True,
        metavar="FILE_OR_DIR",
        help="sequence CSV files, or directories of them",
    )
    parser.add_argument(
        "--out", required=True, metavar="MODEL", help="where to write the trained model (.npz)"
    )
    parser.add_argument(
        "--preset",
        choices=("paper", "fast"),
        default="paper",
        help="training algorithm preset (default: paper)",
    )
    parser.add_argument("--iterations", type=int, help="learning iterations")
    parser.add_argument(
        "--allow-unsafe",
        action="store_true",
        help="learn data with colliding or too-fast steps (refused by default)",
    )
    parser.add_argument(
        "--input-noise", type=float, help="std. dev. of noise on the teacher-forced inputs"
    )
    add_config_argument(parser, CONFIG_SECTIONS)
    parser.add_argument(
        "--dt",
        type=float,
        help="seconds per step the data were recorded at (default: from the data's "
        "recording.json, else 0.4, the paper's)",
    )
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--hidden", type=int, default=40, help="hidden units (default 40)")
    parser.add_argument("--context", type=int, default=30, help="context units (default 30)")
    parser.add_argument("--pb-size", type=int, default=4, help="PB units (default 4)")
    parser.add_argument(
        "--checkpoint-every",
        type=int,
        metavar="N",
        help="write a checkpoint every N iterations (default 5000)",
    )
    parser.add_argument(
        "--resume", action="store_true", help="continue from MODEL.checkpoint.npz if it exists"
    )
    parser.add_argument(
        "--keep-checkpoint",
        action="store_true",
        help="keep MODEL.checkpoint.npz after the model is written",
    )
    parser.add_argument(
        "--no-progress",
        action="store_true",
        help="no progress bar (there is none when stderr is not a terminal)",
    )


def checkpoint_path_for(model_path: str) -> str:
    base = model_path[:-4] if model_path.endswith(".npz") else model_path
    return base + ".checkpoint.npz"


def run(args: argparse.Namespace) -> int:
    # A model that cannot be written is refused before training, not after it.
    from rnnpb._atomic import check_writable

    check_writable(args.out, "model")

    from dataclasses import replace
    from pathlib import Path

    import numpy as np

    from rnnpb import _interrupt
    from rnnpb.commands._checks import step_count
    from rnnpb.commands._config import read_config
    from rnnpb.commands._recording import data_framing
    from rnnpb.commands.progress import progress_bar
    from rnnpb.errors import DataFileError
    from rnnpb.model import NetworkConfig, TrainConfig, train
    from rnnpb.robot import JOINT_LIMITS
    from rnnpb.safety import check_data
    from rnnpb.sequences import read_sequence_files
    from rnnpb.vectors import MOTOR_NAMES, SENSORY_NAMES

    # Before the data are read: an untrained model written as if it had learned is no result.
    step_count("--iterations", args.iterations, high=10_000_000)
    step_count("--checkpoint-every", args.checkpoint_every, high=10_000_000)
    overrides = read_config(args.config, CONFIG_SECTIONS, NAME)
    sequences = read_sequence_files(args.data)
    dt, dt_origin = _step_time(args.dt, args.data)
    framing = data_framing(args.data)
    safety = check_data(sequences, dt=dt)
    if safety.unsafe and not args.allow_unsafe:
        raise DataFileError(
            f"{safety.first} ({safety.unsafe} unsafe steps; record with `rnnpb record`, "
            "which retargets safely, or pass --allow-unsafe)"
        )
    # The preset, with the --config file's values over it: read the same way.
    config = TrainConfig.from_preset(
        args.preset if overrides is None else overrides.preset(args.preset)
    )
    changes = {
        k: v
        for k, v in {
            "iterations": args.iterations,
            "input_noise": args.input_noise,
            "checkpoint_every": args.checkpoint_every,
        }.items()
        if v is not None
    }
    config = replace(config, seed=args.seed, **changes)
    network = NetworkConfig(
        pb_size=args.pb_size, hidden_size=args.hidden, context_size=args.context
    )
    patterns = sorted({s.pattern for s in sequences})
    print(
        f"training on {len(sequences)} sequences of {len(patterns)} pattern(s): "
        f"{', '.join(patterns)}; {config.iterations} iterations ({args.preset} preset, "
        f"{config.optimizer})"
    )
    print(f"data safety: {safety.describe()}")
    bar = progress_bar(
        total=config.iterations, unit="it", desc="training", disable=args.no_progress
    )

    def after_chunk(progress) -> None:
        bar.update(progress.iteration - bar.n)
        bar.set_postfix(mse=f"{progress.mse:.2e}")
        # A safe point: the chunk's error has been read back, so no XLA work is in flight.
        _interrupt.check()

    checkpoint = Path(checkpoint_path_for(args.out))
    try:
        model = train(
            sequences,
            JOINT_LIMITS,
            network,
            config,
            progress=after_chunk,
            checkpoint_path=checkpoint,
            resume=args.resume,
        )
    finally:
        bar.close()
    _interrupt.check()  # interrupted during the last chunk: no model file
    model = replace(model, meta={**model.meta, "dt": dt})
    if framing is not None:
        model.meta["framing_m"] = framing[0]
    model.meta["data_safety"] = {
        "steps": safety.steps,
        "collision": safety.collision,
        "speed": safety.speed,
        "limit": safety.limit,
        "dt": safety.dt,
        "allowed_unsafe": bool(safety.unsafe),
    }
    model.save(args.out)
    if not args.keep_checkpoint:
        # The finished model holds all the checkpoint did; left beside it, it is a second file
        # that looks like a model (and the dashboard would offer it).
        checkpoint.unlink(missing_ok=True)
    info = model.meta["training"]
    mse = np.asarray(info["mse_per_output"])
    names = (*SENSORY_NAMES, *MOTOR_NAMES)
    print(f"wrote {args.out} after {info['iterations']} iterations in {info['seconds']:.1f} s")
    print(f"learned at dt {dt:g} s ({dt_origin}); it plays at that step")
    if framing is not None:
        print(f"a person is framed at {framing[0]:g} m, as the data were (from {framing[1][0]})")
    print(
        f"final mean squared error per output: max {mse.max():.2e}, mean {mse.mean():.2e} "
        f"(RMS max {np.sqrt(mse.max()):.2e}); worst output: {names[int(mse.argmax())]}"
    )
    for name, pb in model.pattern_pb.items():
        print(f"  pattern {name}: PB = {np.array2string(pb, precision=3)}")
    return 0


def _step_time(given: float | None, data: list[str]) -> tuple[float, str]:
    """The step time to learn at and where it came from (see DESCRIPTION)."""
    import math

    from rnnpb.commands._checks import finite_seconds
    from rnnpb.commands._recording import data_dt
    from rnnpb.errors import ConfigError
    from rnnpb.model.io import DEFAULT_DT, MAX_DT

    if given is not None:
        finite_seconds("--dt", given, high=MAX_DT)
    recorded = data_dt(data)
    if recorded is None:
        return (DEFAULT_DT, "the paper's") if given is None else (given, "--dt")
    dt, files = recorded
    if given is not None and not math.isclose(given, dt, rel_tol=1e-9):
        raise ConfigError(
            f"--dt {given:g}: the data were recorded at dt {dt:g} s ({files[0]}); learn them "
            f"at --dt {dt:g}, or record them again with --dt {given:g}"
        )
    return dt, f"from {files[0]}" + (f" and {len(files) - 1} more" if len(files) > 1 else "")
