"""rnnpb safety: learn where in its PB space the robot's behaviour is unsafe."""

from __future__ import annotations

import argparse

NAME = "safety"
HELP = "learn the safety map of a model (where in PB space behaviour is unsafe)"
DESCRIPTION = """\
Safety by experience (the paper's section 4.1; docs/safety.md).

  rnnpb safety learn --model M.npz
explores the model's PB space: closed-loop generation from many PB values, each run checked
for self-collision, servo speed, joints pressed against their limits and motion that never
settles. The meta-level network learns PB -> risk from it; the map, with the experienced PBs
for familiarity, is written beside the model as M.safety.npz (or --out).

  rnnpb safety show --model M.npz
describes the stored map.

Example:
  rnnpb safety learn --model model.npz --samples 2000
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    actions = parser.add_subparsers(dest="action", required=True, metavar="ACTION")
    learn = actions.add_parser("learn", help="explore the PB space and learn the map")
    learn.add_argument("--model", required=True, metavar="MODEL", help="trained model (.npz)")
    learn.add_argument(
        "--out",
        metavar="MAP",
        help="where to write the map (default: MODEL.safety.npz beside the model)",
    )
    learn.add_argument(
        "--samples", type=int, default=2000, help="PB values explored (default 2000)"
    )
    learn.add_argument(
        "--steps", type=int, default=80, help="closed-loop steps generated from each (default 80)"
    )
    learn.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    learn.add_argument("--no-progress", action="store_true", help="no progress bar")
    show = actions.add_parser("show", help="describe the stored map")
    show.add_argument("--model", required=True, metavar="MODEL", help="trained model (.npz)")


def run(args: argparse.Namespace) -> int:
    from rnnpb.model import TrainedModel
    from rnnpb.safety import (
        ExplorationConfig,
        MetaConfig,
        describe_safety_map,
        learn_safety_map,
        safety_map_path,
    )

    if args.action == "show":
        print(describe_safety_map(safety_map_path(args.model)))
        return 0
    model = TrainedModel.load(args.model)
    exploration = ExplorationConfig(samples=args.samples, steps=args.steps, seed=args.seed)
    bar = None
    if not args.no_progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=exploration.samples, unit="PB", desc="exploring", dynamic_ncols=True)

    def progress(done: int, total: int) -> None:
        if bar is not None:
            bar.update(done - bar.n)

    try:
        stored = learn_safety_map(model, exploration, MetaConfig(seed=args.seed), progress=progress)
    finally:
        if bar is not None:
            bar.close()
    out = args.out or safety_map_path(args.model)
    stored.save(out)
    print(f"wrote {out}")
    print(describe_safety_map(out))
    return 0
