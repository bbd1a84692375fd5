"""rnnpb presets: what the learning presets' values rest on."""

from __future__ import annotations

import argparse
from pathlib import Path

NAME = "presets"
HELP = "show each learning preset value's evidence; --check reruns the cheap harnesses"
DESCRIPTION = """\
  rnnpb presets evidence NAME
prints every value of the learning preset NAME (paper or fast) with its kind of evidence:
  paper       the paper's value (Ito & Tani 2004);
  documented  set for a reason its note states, not measured;
  unmeasured  chosen on a measure that cannot be repeated (a search or harness not kept),
              or set when a part was built and never searched;
  measured    its command (a harness in the checkout's benchmarks/ or tools/) reproduces
              its figure on development draws;
then each source: its command (or the note that says why it has none), draws and figure.
--json FILE writes the same as JSON.

  rnnpb presets evidence --check NAME
runs again, from a checkout, every measured source's harness that is cheap and says what
it expects (docs/model.md, "Settings"), and exits with status 1, naming each, when a figure
differs from its expectation. --source ID checks the sources named, cheap or not.

Example:
  rnnpb presets evidence fast
  rnnpb presets evidence --check --source fast-learning fast
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from rnnpb.presets import PRESET_NAMES

    actions = parser.add_subparsers(dest="action", required=True, metavar="ACTION")
    evidence = actions.add_parser(
        "evidence",
        help="each value's evidence: its kind and the command that measures it",
        description="Each value of a learning preset and its evidence (rnnpb presets --help).",
    )
    evidence.add_argument("name", metavar="NAME", choices=PRESET_NAMES, help="paper or fast")
    evidence.add_argument(
        "--check",
        action="store_true",
        help="run the cheap harnesses again and fail when a figure differs from the expected",
    )
    evidence.add_argument(
        "--source",
        action="append",
        default=[],
        metavar="ID",
        help="with --check: check this source (again for more), cheap or not",
    )
    evidence.add_argument("--json", metavar="FILE", help="also write the table as JSON")


def run(args: argparse.Namespace) -> int:
    from rnnpb.errors import ConfigError
    from rnnpb.presets import load_preset

    preset = load_preset(args.name)
    if args.source and not args.check:
        raise ConfigError("--source goes with --check")
    if args.check:
        return _check(preset, args.source)
    print(_table(preset))
    if args.json:
        _write_json(preset, Path(args.json))
        print(f"wrote {args.json}")
    return 0


def _table(preset) -> str:
    from rnnpb.presets.evidence import evidence_rows, kind_counts

    rows = evidence_rows(preset)
    cells = [(f"[{r.section}] {r.key}", _value(r.value), r.kind, r.source.id) for r in rows]
    cells.insert(0, ("setting", "value", "kind", "source"))
    widths = [max(len(c[i]) for c in cells) for i in range(3)]
    lines = [f"preset {preset.name}, version {preset.version}: {preset.description}", ""]
    lines += [f"{a:{widths[0]}}  {b:{widths[1]}}  {c:{widths[2]}}  {d}" for a, b, c, d in cells]
    counts = kind_counts(preset)
    lines += ["", "values by kind: " + ", ".join(f"{k} {n}" for k, n in counts.items()), ""]
    used = dict.fromkeys(r.source.id for r in rows)
    for source_id in used:
        source = preset.sources[source_id]
        lines.append(
            f"[{source.id}] {source.kind}" + (f", {source.cost}" if source.command else "")
        )
        if source.command:
            lines.append(f"    command: {source.command}")
        if source.draws:
            lines.append(f"    draws: {', '.join(map(str, source.draws))}")
        if source.figure:
            lines.append(f"    figure: {source.figure}")
        if source.expect:
            expected = ", ".join(f"{k} = {v}" for k, v in source.expect.items())
            lines.append(f"    expects: {expected} (± {source.tolerance:g})")
        if source.note:
            lines.append(f"    note: {source.note}")
    return "\n".join(lines)


def _value(value) -> str:
    if isinstance(value, tuple):
        return "[" + ", ".join(map(str, value)) + "]"
    return repr(value) if isinstance(value, str) else str(value)


def _write_json(preset, path: Path) -> None:
    import json

    from rnnpb._atomic import atomic_write
    from rnnpb.presets.evidence import evidence_rows, kind_counts

    rows = evidence_rows(preset)
    data = {
        "preset": preset.name,
        "version": preset.version,
        "counts": kind_counts(preset),
        "values": [r.to_json() for r in rows],
        "sources": {
            s.id: {
                "kind": s.kind,
                "command": s.command,
                "draws": list(s.draws),
                "figure": s.figure,
                "note": s.note,
                "cost": s.cost,
                "expect": dict(s.expect),
                "tolerance": s.tolerance,
            }
            for s in (preset.sources[i] for i in dict.fromkeys(r.source.id for r in rows))
        },
    }
    with atomic_write(path, encoding="utf-8") as handle:
        handle.write(json.dumps(data, indent=1, ensure_ascii=False) + "\n")


def _check(preset, only: list[str]) -> int:
    import sys

    from rnnpb.errors import ConfigError
    from rnnpb.presets.evidence import check, checked_sources, checkout

    sources = checked_sources(preset, only)
    root = checkout()
    if root is None:
        raise ConfigError(
            "the harnesses are in a checkout's benchmarks/ and tools/, which this rnnpb is not "
            "run from: run rnnpb from a checkout to check the evidence"
        )
    if not sources:
        print(f"preset {preset.name}: no cheap measured source says what it expects")
        return 0
    failed = []
    for source in sources:
        print(f"{source.id}: {source.command}", flush=True)
        result = check(source, root)
        print("  " + result.describe(source.tolerance), flush=True)
        if not result.held:
            failed.append(source.id)
    if failed:
        print(
            f"rnnpb: the evidence of preset {preset.name} differs from what it expects: "
            f"{', '.join(failed)}",
            file=sys.stderr,
        )
        return 1
    print(f"preset {preset.name}: {len(sources)} harness(es) gave the figures expected")
    return 0
