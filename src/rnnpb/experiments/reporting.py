"""What every report of rnnpb shares: formatting values, markdown tables, embedded figures, the
versions block, and writing ``report.md`` and ``results.json`` so that neither is ever half
written.

A study's report is then a few section functions over its result objects::

    lines = ["# My study", "", *table(("measure", "value"), [("lock-on", fmt(steps))]),
             "", embed("lock-on", "lock.png")]
    write_outputs(out, lines, {"config": asdict(config), "versions": versions(), ...})
"""

from __future__ import annotations

import json
import math
import os
import platform
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb._atomic import atomic_write

REPORT_FILE = "report.md"
RESULTS_FILE = "results.json"
FIGURES_DIR = "figures"


def fmt(value: Any, digits: int = 1) -> str:
    """A measure for a table: ``never`` for None (the event never happened), ``–`` for NaN
    (not measured), floats to ``digits`` decimals."""
    if value is None:
        return "never"
    if isinstance(value, float):
        if math.isnan(value):
            return "–"
        return f"{value:.{digits}f}"
    return str(value)


def sci(value: float) -> str:
    """A round number in short scientific notation: ``3e-4`` (not ``0.0003`` or ``3e-04``)."""
    mantissa, exponent = f"{value:.0e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def median_and_worst(values: Sequence[Any]) -> str:
    """``median M, worst W`` of step counts; None (never) counts as the worst."""
    if not values:
        return "–"
    if any(v is None for v in values):
        finite = [v for v in values if v is not None]
        worst = "never"
    else:
        finite = list(values)
        worst = fmt(max(values))
    median = fmt(float(np.median(finite))) if finite else "–"
    return f"median {median}, worst {worst}"


def row(cells: Iterable[Any]) -> str:
    """One markdown table row."""
    return "| " + " | ".join(str(c) for c in cells) + " |"


def table(header: Sequence[str], rows: Iterable[Sequence[Any]]) -> list[str]:
    """A markdown table, as lines."""
    return [row(header), "|" + "---|" * len(header), *(row(r) for r in rows)]


def embed(alt: str, name: str) -> str:
    """A figure of ``figures/`` embedded in the report."""
    return f"![{alt}]({FIGURES_DIR}/{name})"


def versions() -> dict[str, str]:
    """The versions and the machine a run's numbers come from."""
    import jax
    import mujoco

    return {
        "python": platform.python_version(),
        "jax": jax.__version__,
        "numpy": np.__version__,
        "mujoco": mujoco.__version__,
        "machine": platform.machine(),
        "cpus": str(os.cpu_count()),
    }


def jsonable(value: Any) -> Any:
    """Plain JSON values: string keys, lists for tuples and arrays, NaN and inf as null."""
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (np.floating, float)):
        return None if not math.isfinite(float(value)) else float(value)
    if isinstance(value, np.integer):
        return int(value)
    return value


def write_json(path: str | os.PathLike[str], results: dict[str, Any]) -> None:
    """Write ``results``, made JSON-ready, atomically."""
    with atomic_write(path, "w", encoding="utf-8") as handle:
        json.dump(jsonable(results), handle, indent=1)


def write_lines(path: str | os.PathLike[str], lines: Sequence[str]) -> None:
    """Write a report's lines atomically."""
    with atomic_write(path, "w", encoding="utf-8") as handle:
        handle.write("\n".join(lines))


def write_outputs(
    out: str | os.PathLike[str], report: Sequence[str], results: dict[str, Any]
) -> None:
    """Write ``out/results.json`` and ``out/report.md``, each atomically."""
    out = Path(out)
    write_json(out / RESULTS_FILE, results)
    write_lines(out / REPORT_FILE, report)
