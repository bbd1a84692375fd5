"""``rnnpb memory``: look into the short-term memory beside a model, forget an episode, export
episodes as sequence CSVs."""

from __future__ import annotations

import argparse

NAME = "memory"
HELP = "list, show, merge, split, forget or export the episodes in a model's short-term memory"
DESCRIPTION = """\
The short-term memory is the SQLite file beside a model (MODEL.memory.sqlite) holding the
movements the robot kept during an interaction (episodes: whole cycles of the hands it saw and
its joint angles for them, when, from which source, which model saw them, their status kept,
learned or discarded) and the sequences each consolidation rehearsed. MEMORY is the model file
or the memory file itself.

Episodes of one movement share a pattern name: a performance of a shape the memory holds is
merged with it when it is kept (its note says "merged with episode N" and how alike the two
shapes are), and a pattern is learned from all its episodes. A merge that joined two different
movements is undone with split; two episodes of one movement kept apart are joined with merge.

  rnnpb memory list MEMORY              the episodes (by movement) and the consolidations
  rnnpb memory show MEMORY ID           one episode in detail
  rnnpb memory merge MEMORY ID INTO     episode ID is another performance of episode INTO's
                                        movement (it takes INTO's pattern name)
  rnnpb memory split MEMORY ID [--name NAME]
                                        episode ID is a movement of its own (default name:
                                        the next free new-N)
  rnnpb memory forget MEMORY ID         delete an episode and its movement
  rnnpb memory export MEMORY --out DIR  episodes as sequence CSVs (for rnnpb train)

A learned episode is part of a model version and is neither merged nor split.
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    actions = parser.add_subparsers(dest="action", metavar="ACTION", required=True)
    listing = actions.add_parser("list", help="the episodes and the consolidations")
    listing.add_argument("memory", metavar="MEMORY", help="model .npz or .memory.sqlite file")
    listing.add_argument(
        "--status", choices=("kept", "learned", "discarded"), help="only episodes of this status"
    )
    show = actions.add_parser("show", help="one episode in detail")
    show.add_argument("memory", metavar="MEMORY")
    show.add_argument("id", type=int, metavar="ID")
    merge = actions.add_parser("merge", help="join an episode to another's movement")
    merge.add_argument("memory", metavar="MEMORY")
    merge.add_argument("id", type=int, metavar="ID")
    merge.add_argument("into", type=int, metavar="INTO")
    split = actions.add_parser("split", help="make an episode a movement of its own")
    split.add_argument("memory", metavar="MEMORY")
    split.add_argument("id", type=int, metavar="ID")
    split.add_argument("--name", help="its pattern name (default: the next free new-N)")
    forget = actions.add_parser("forget", help="delete an episode")
    forget.add_argument("memory", metavar="MEMORY")
    forget.add_argument("id", type=int, metavar="ID")
    export = actions.add_parser("export", help="episodes as sequence CSVs")
    export.add_argument("memory", metavar="MEMORY")
    export.add_argument("--out", required=True, metavar="DIR")
    export.add_argument(
        "--id",
        type=int,
        nargs="+",
        dest="ids",
        metavar="ID",
        help="these episodes (default every episode of --status)",
    )
    export.add_argument(
        "--status",
        choices=("kept", "learned", "discarded"),
        help="only episodes of this status (default all)",
    )


def _merged(note: str) -> str:
    """The merge or split an episode's note records last, or ""."""
    parts = [p for p in note.split("; ") if p.startswith(("merged with ", "split from "))]
    return parts[-1] if parts else ""


def _free_name(memory) -> str:
    taken = {e.pattern for e in memory.episodes()}
    n = 1
    while f"new-{n}" in taken:
        n += 1
    return f"new-{n}"


def _when(seconds: float) -> str:
    import time

    return time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(seconds))


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    import numpy as np

    from rnnpb.errors import ConfigError
    from rnnpb.memory import MemoryStore
    from rnnpb.sequences import write_sequence

    with MemoryStore(args.memory, create=False) as memory:
        if args.action == "list":
            episodes = memory.episodes(args.status)
            print(f"{memory.path}: {len(episodes)} episode{'' if len(episodes) == 1 else 's'}")
            for pattern in dict.fromkeys(e.pattern for e in episodes):
                group = [e for e in episodes if e.pattern == pattern]
                print(f"  {pattern}: {len(group)} performance{'' if len(group) == 1 else 's'}")
                for e in group:
                    merged = _merged(e.note)
                    print(
                        f"    {e.id:4d}  {_when(e.created_at)}  {e.status:9s}  "
                        f"{e.n_steps:4d} steps, {e.n_cycles} cycles  from {e.source}  "
                        f"(model {e.model})" + (f"  {merged}" if merged else "")
                    )
            consolidations = memory.consolidations()
            if consolidations:
                print(f"{len(consolidations)} consolidations")
            for c in consolidations:
                learned = ", ".join(str(i) for i in c.episode_ids) or "none"
                print(
                    f"  {c.id:4d}  {_when(c.created_at)}  {c.status:6s}  episodes {learned}, "
                    f"{c.n_rehearsed} rehearsed sequences, {c.seconds:.1f} s  "
                    f"{c.model_before} -> {c.model_after}"
                    + (f"  ({c.message})" if c.message else "")
                )
        elif args.action == "show":
            episode = memory.episode(args.id)
            e = episode.summary
            print(f"episode {e.id}: pattern {e.pattern!r}, {e.status}")
            print(f"  kept {_when(e.created_at)} from {e.source}, seen by model {e.model}")
            print(
                f"  {e.n_steps} steps, {e.n_cycles} whole cycles"
                + (f"; note: {e.note}" if e.note else "")
            )
            low, high = episode.sensory.min(axis=0), episode.sensory.max(axis=0)
            for name, a, b in zip(("lhy", "lhz", "rhy", "rhz"), low, high, strict=True):
                print(f"  {name} {a:.3f} .. {b:.3f}")
            print(f"  joint range (rad) {float(np.ptp(episode.motor, axis=0).max()):.3f} at most")
        elif args.action == "merge":
            from rnnpb.interaction.repeats import shape_distance

            moved, into = memory.episode(args.id), memory.episode(args.into)
            distance = shape_distance(moved.sensory, into.sensory)
            pattern = memory.merge(args.id, args.into, f"shape distance {distance:.2f}")
            print(
                f"episode {args.id} merged with episode {args.into}: pattern {pattern}, "
                f"{len(memory.group(pattern))} performances (shape distance {distance:.2f})"
            )
        elif args.action == "split":
            name = args.name or _free_name(memory)
            before = memory.episode_summary(args.id).pattern
            memory.split(args.id, name)
            print(f"episode {args.id} split from {before}: now pattern {name}")
        elif args.action == "forget":
            memory.forget(args.id)
            print(f"forgot episode {args.id} ({memory.path})")
        else:
            ids = args.ids or [e.id for e in memory.episodes(args.status)]
            if not ids:
                raise ConfigError(f"{memory.path}: no episodes to export")
            out = Path(args.out)
            if out.exists() and not out.is_dir():
                raise ConfigError(f"--out {out}: exists and is not a directory")
            out.mkdir(parents=True, exist_ok=True)
            for episode_id in ids:
                episode = memory.episode(episode_id)
                path = out / f"{episode.summary.pattern}_{episode_id}.csv"
                write_sequence(path, episode.sequence())
                print(
                    f"episode {episode_id} ({episode.summary.pattern}, "
                    f"{episode.summary.n_steps} steps) -> {path}"
                )
    return 0
