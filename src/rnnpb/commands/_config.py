"""``--config FILE``, shared by the commands that take settings: a TOML file of preset values
that override the learning preset's for one run (research; docs/model.md, "Settings").

The file has the preset files' sections (``src/rnnpb/presets/paper.toml``) and any of their
keys, e.g.::

    [online]
    surprise_gate = 0.0       # the regression without the gate
    [online.pb]
    k_nb = 0.1
    [recognition]
    switch_steps = 4

A command reads the sections it uses (``uses``); an unknown section or key, a value of the
wrong kind or a section the command does not use is one :class:`ConfigError` line naming the
file and the key, before any work starts. Values the file does not name stay as they are. The
checked file (:class:`rnnpb.presets.Overrides`) goes unchanged to the code that makes each
config, which reads it as it reads the preset.
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rnnpb.presets import Overrides


RUN_SECTIONS = (
    "online",
    "recognition",
    "recognition_untaught",
    "teaching",
    "teaching.cutter",
    "consolidation",
)
"""The tables a run of the interaction reads (``rnnpb interact``, ``rnnpb serve``);
``rnnpb interact`` reads the last three with --learn."""
TEACHING_SECTIONS = ("teaching", "teaching.cutter", "consolidation")
"""The tables of a ``--config`` file only teaching reads."""


def add_config_argument(parser: argparse.ArgumentParser, uses: tuple[str, ...]) -> None:
    """Add ``--config FILE`` to a command that reads the sections ``uses``."""
    tables = ", ".join(f"[{name}]" for name in uses)
    parser.add_argument(
        "--config",
        metavar="FILE",
        help=f"a TOML file of preset values to use instead ({tables}; docs/model.md)",
    )


def read_config(path: str | None, uses: tuple[str, ...], command: str) -> Overrides | None:
    """The checked ``--config`` file at ``path`` (None: no file given) for a command that
    reads the sections ``uses`` (a section's ``.pb`` subsection comes with it)."""
    if path is None:
        return None
    from rnnpb.presets import Overrides

    return Overrides.read(path, uses, f"rnnpb {command}")
