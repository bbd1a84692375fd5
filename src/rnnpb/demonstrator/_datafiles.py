"""Writing the synthetic dataset to disk: sequence CSVs and the learning-set index."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from rnnpb._atomic import atomic_write
from rnnpb.errors import ConfigError
from rnnpb.sequences import write_sequence

from ._datasets import LEARNING_SETS, pattern_dataset
from ._user import PATTERN_DESCRIPTIONS, PATTERNS, PatternConfig

LEARNING_SETS_FILE = "learning_sets.json"
PATTERNS_DIR = "patterns"


def write_dataset(
    out: str | os.PathLike[str],
    seed: int = 0,
    period_steps: float = 12.0,
    n_steps: int = 50,
    samples_per_pattern: int = 2,
) -> dict[str, Any]:
    """Write the four patterns' demonstrations and the learning-set index.

    ``learning_sets.json`` maps each learning set (``"1"``-``"4"``, ``"full"``) to its
    patterns and its files (paths relative to ``out``), and records how the data was made.
    Returns the paths written and the demonstrations (``"sequences"``, for Figure 4:
    :func:`rnnpb.analysis.figures.plot_patterns`).
    """
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"{out}: exists and is not a directory")
    if n_steps < 2:
        raise ConfigError(f"--steps must be >= 2, got {n_steps}")
    if samples_per_pattern < 1:
        raise ConfigError(f"--samples must be >= 1, got {samples_per_pattern}")
    config = PatternConfig(period_steps=period_steps)
    sequences = pattern_dataset(seed, PATTERNS, samples_per_pattern, n_steps, config)
    files: dict[str, list[str]] = {p: [] for p in PATTERNS}
    for seq in sequences:
        relative = f"{PATTERNS_DIR}/{seq.pattern}_{seq.meta['sample']}.csv"
        write_sequence(out / relative, seq)
        files[seq.pattern].append(relative)
    index = {
        "format": "rnnpb-learning-sets",
        "version": 1,
        "generator": {
            "seed": seed,
            "period_steps": period_steps,
            "dt": config.dt,
            "n_steps": n_steps,
            "samples_per_pattern": samples_per_pattern,
        },
        "patterns": {
            p: {"description": PATTERN_DESCRIPTIONS[p], "files": files[p]} for p in PATTERNS
        },
        "learning_sets": {
            name: {"patterns": list(patterns), "files": [f for p in patterns for f in files[p]]}
            for name, patterns in LEARNING_SETS.items()
        },
    }
    with atomic_write(out / LEARNING_SETS_FILE, "w", encoding="utf-8") as handle:
        json.dump(index, handle, indent=2)
        handle.write("\n")
    return {
        "files": [out / f for p in PATTERNS for f in files[p]],
        "patterns_dir": out / PATTERNS_DIR,
        "learning_sets": out / LEARNING_SETS_FILE,
        "sequences": sequences,
    }
