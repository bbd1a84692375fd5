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
file and the key, before any work starts. Values the file does not name stay as they are.
"""

from __future__ import annotations

import argparse
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, Protocol, Self, TypeVar

from rnnpb.errors import ConfigError

if TYPE_CHECKING:
    from rnnpb.presets import Preset


RUN_SECTIONS = (
    "online",
    "recognition",
    "recognition_untaught",
    "teaching",
    "teaching.cutter",
    "consolidation",
)
"""The tables a run of the interaction reads (``rnnpb interact``, ``rnnpb serve``;
:mod:`rnnpb.interaction.settings`); ``rnnpb interact`` reads the last three with --learn."""


class _Tuned(Protocol):
    """A config with tuned values (:class:`rnnpb.model.TrainConfig` and the like)."""

    __dataclass_fields__: ClassVar[dict[str, Any]]

    def with_tuning(self, **changes: Any) -> Self: ...


Config = TypeVar("Config", bound=_Tuned)


def add_config_argument(parser: argparse.ArgumentParser, uses: tuple[str, ...]) -> None:
    """Add ``--config FILE`` to a command that reads the sections ``uses``."""
    tables = ", ".join(f"[{name}]" for name in uses)
    parser.add_argument(
        "--config",
        metavar="FILE",
        help=f"a TOML file of preset values to use instead ({tables}; docs/model.md)",
    )


@dataclass(frozen=True)
class ConfigFile:
    """A checked ``--config`` file.

    Attributes
    ----------
    path : str
    tables : mapping of str to dict
        Each section the file names (``"online"``, ``"online.pb"``, ...) to its values, each of
        the kind the preset's value has.
    """

    path: str
    tables: Mapping[str, Mapping[str, Any]]

    def section(self, name: str) -> dict[str, Any]:
        """Section ``name``'s values, its ``pb`` subsection as a dict under ``"pb"`` (empty
        when the file does not name it)."""
        from rnnpb.model._tuned import table_values

        return table_values(self.tables, name)

    def preset(self, name: str) -> Preset:
        """Learning preset ``name`` with this file's values over its own (each overridden
        value's evidence is this file), for a job that reads a preset's section directly."""
        from rnnpb.presets import load_preset

        return load_preset(name).overridden(self.tables, self.path)

    def apply(self, config: Config, section: str) -> Config:
        """``config`` with section ``section``'s values: its settings by
        :func:`dataclasses.replace`, its tuned values by ``with_tuning``."""
        from rnnpb.model._tuned import apply_table

        return apply_table(config, self.tables, section)


def read_config(path: str | None, uses: tuple[str, ...], command: str) -> ConfigFile | None:
    """The checked ``--config`` file at ``path`` (None: no file given) for a command that
    reads the sections ``uses`` (a section's ``.pb`` subsection comes with it)."""
    if path is None:
        return None
    from rnnpb.presets import load_preset, read_overrides

    data = read_overrides(path)
    # The paper preset has every section; its values give each key's kind.
    checked = load_preset("paper").overridden(data, path)
    tables: dict[str, dict[str, Any]] = {}
    for section, key in _keys(data, ()):
        base = section.removesuffix(".pb")
        if base not in uses:
            raise ConfigError(
                f"{path}: [{section}] does not apply to rnnpb {command} "
                f"(it reads {', '.join(f'[{name}]' for name in uses)})"
            )
        tables.setdefault(section, {})[key] = checked.section(section)[key]
    return ConfigFile(path, tables)


def _keys(table: Mapping[str, Any], path: tuple[str, ...]):
    for key, value in table.items():
        if isinstance(value, dict):
            yield from _keys(value, (*path, key))
        else:
            yield ".".join(path), key
