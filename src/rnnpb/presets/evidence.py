"""Each preset value's evidence as one table, and the cheap harnesses run again.

:func:`evidence_rows` gives every value of a preset with its source's kind (``paper``,
``documented``, ``unmeasured``, ``measured``: :data:`rnnpb.presets.KINDS`); :func:`check`
runs a measured source's harness from the checkout (its ``command``, ``DIR`` and ``JSON``
replaced by fresh temporary paths, the checkout's ``src`` first on the path) and holds the
JSON it writes to the source's ``expect``. ``rnnpb presets evidence [--check] NAME`` is the
command line of both.

>>> from rnnpb.presets import load_preset
>>> rows = evidence_rows(load_preset("fast"))
>>> next(r for r in rows if (r.section, r.key) == ("online", "window")).kind
'paper'
"""

from __future__ import annotations

import json
import math
import os
import shlex
import subprocess
import sys
import tempfile
import time
from collections import Counter
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rnnpb.errors import ConfigError
from rnnpb.presets import HARNESS_FOLDERS, KINDS, Preset, Source

CHECK_TIMEOUT_S = 900
"""The longest a harness run by ``--check`` may take before it counts as failed."""


@dataclass(frozen=True)
class EvidenceRow:
    """One value of a preset and its evidence."""

    section: str
    key: str
    value: Any
    kind: str
    source: Source

    def to_json(self) -> dict[str, Any]:
        value = list(self.value) if isinstance(self.value, tuple) else self.value
        return {
            "section": self.section,
            "key": self.key,
            "value": value,
            "kind": self.kind,
            "source": self.source.id,
        }


@dataclass(frozen=True)
class FigureCheck:
    """One expected figure against the one the harness gave (None: it gave none)."""

    key: str
    expected: Any
    got: Any
    held: bool


@dataclass(frozen=True)
class CheckResult:
    """A harness run again: each figure held or not, or the error that stopped it."""

    source: str
    figures: tuple[FigureCheck, ...]
    error: str
    seconds: float

    @property
    def held(self) -> bool:
        return not self.error and all(f.held for f in self.figures)

    def describe(self, tolerance: float) -> str:
        """One line: held, or what differs."""
        if self.error:
            return f"{self.source}: FAILED ({self.error})"
        parts = [
            f"{f.key} {_shown(f.got)}"
            + ("" if f.held else f" (expected {_shown(f.expected)} ± {tolerance:g})")
            for f in self.figures
        ]
        verdict = "held" if self.held else "DIFFERS"
        return f"{self.source}: {verdict} in {self.seconds:.0f} s: " + "; ".join(parts)


def evidence_rows(preset: Preset) -> tuple[EvidenceRow, ...]:
    """Every value of ``preset``, in the file's order, with its source and kind."""
    return tuple(
        EvidenceRow(section, key, value, preset.evidence(section, key).kind, source)
        for section in preset.sections
        for key, value in preset.section(section).items()
        for source in (preset.evidence(section, key),)
    )


def kind_counts(preset: Preset) -> dict[str, int]:
    """How many of ``preset``'s values are of each kind (every kind named, 0 if none)."""
    counts = Counter(row.kind for row in evidence_rows(preset))
    return {kind: counts.get(kind, 0) for kind in KINDS}


def checkout() -> Path | None:
    """The checkout this package runs from (its ``src/rnnpb`` beside ``benchmarks/`` and
    ``tools/``), None for an installed package: the harnesses are not installed with it."""
    root = Path(__file__).resolve().parents[3]
    package = Path(__file__).resolve().parents[1]
    if package != root / "src" / "rnnpb":
        return None
    return root if all((root / folder).is_dir() for folder in HARNESS_FOLDERS) else None


def checked_sources(preset: Preset, only: Iterable[str] = ()) -> tuple[Source, ...]:
    """The sources ``--check`` runs: those named in ``only`` (each a measured source with an
    expectation), else every cheap one with an expectation."""
    only = tuple(only)
    for name in only:
        source = preset.sources.get(name)
        if source is None or source.kind != "measured" or not source.expect:
            raise ConfigError(
                f"preset {preset.name!r} has no measured source {name!r} with an expectation "
                f"to check (those it has: {', '.join(_expecting(preset)) or 'none'})"
            )
    if only:
        return tuple(preset.sources[name] for name in only)
    sources = preset.sources.values()
    return tuple(s for s in sources if s.kind == "measured" and s.cost == "cheap" and s.expect)


def check(source: Source, root: Path, timeout: float = CHECK_TIMEOUT_S) -> CheckResult:
    """Run ``source``'s harness from the checkout at ``root`` and hold its figures to the
    source's ``expect``."""
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="rnnpb-evidence-") as temporary:
        figures_file = Path(temporary) / "figures.json"
        folder = Path(temporary) / "out"
        words = shlex.split(source.command)
        argv = [sys.executable, str(root / words[1])]
        for word in words[2:]:
            argv.append({"JSON": str(figures_file), "DIR": str(folder)}.get(word, word))
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join(
            p for p in (str(root / "src"), env.get("PYTHONPATH", "")) if p
        )
        env.setdefault("MPLBACKEND", "Agg")
        try:
            done = subprocess.run(
                argv,
                cwd=root,
                env=env,
                capture_output=True,
                text=True,
                timeout=timeout,
                check=False,
            )
        except subprocess.TimeoutExpired:
            return _failed(source, f"took longer than {timeout:.0f} s", started)
        except OSError as error:
            return _failed(source, f"could not start: {error}", started)
        if done.returncode != 0:
            last = (done.stderr.strip().splitlines() or [""])[-1]
            return _failed(source, f"the harness exited {done.returncode}: {last}", started)
        try:
            data = json.loads(figures_file.read_text(encoding="utf-8"))
        except (OSError, json.JSONDecodeError) as error:
            return _failed(source, f"the harness wrote no JSON figures ({error})", started)
    checks = tuple(
        _held(key, expected, _figure(data, key), source.tolerance)
        for key, expected in source.expect.items()
    )
    return CheckResult(source.id, checks, "", time.perf_counter() - started)


def _expecting(preset: Preset) -> list[str]:
    return [s.id for s in preset.sources.values() if s.kind == "measured" and s.expect]


def _failed(source: Source, error: str, started: float) -> CheckResult:
    return CheckResult(source.id, (), error, time.perf_counter() - started)


def _figure(data: Any, key: str) -> Any:
    """The value at ``key`` (levels joined by ``/``) of the harness's JSON, None if absent."""
    for part in key.split("/"):
        if not isinstance(data, Mapping) or part not in data:
            return None
        data = data[part]
    return data


def _held(key: str, expected: Any, got: Any, tolerance: float) -> FigureCheck:
    number = isinstance(expected, int | float) and not isinstance(expected, bool)
    if number:
        held = (
            isinstance(got, int | float)
            and not isinstance(got, bool)
            and math.isfinite(got)
            and abs(got - expected) <= tolerance
        )
    else:
        held = got == expected
    return FigureCheck(key, expected, got, held)


def _shown(value: Any) -> str:
    if value is None:
        return "none given"
    return f"{value:.6g}" if isinstance(value, float) else str(value)


__all__ = [
    "CHECK_TIMEOUT_S",
    "CheckResult",
    "EvidenceRow",
    "FigureCheck",
    "check",
    "checked_sources",
    "checkout",
    "evidence_rows",
    "kind_counts",
]
