"""The learning presets' measured choices, as data.

Each learning preset is one versioned TOML file in this package: ``paper.toml`` for models
learned by the paper's algorithm, ``fast.toml`` for the fast preset (Adam). A file holds the
values chosen for that preset's models, one table per job — ``[learning]``, ``[online]``,
``[recognition]``, ``[recognition_untaught]``, ``[consolidation]``, ``[teaching]``, ... — and,
for every value, its evidence: ``[evidence.<section>]`` maps each key to the id of a
``[sources.<id>]`` entry that says which command chose it (``""`` where the search script is
not kept), on which draws, and which figure it met.

A nested table is a section of its own, named by its dotted path: ``[online.pb]`` is section
``"online.pb"``, its evidence ``[evidence.online.pb]``. Lists are read as tuples, so a
section's values are hashable, as the compiled code needs its static settings to be.

>>> preset = load_preset("paper")
>>> preset.section("online")["surprise_gate"]
0.035
>>> preset.evidence("online", "surprise_gate").draws
(100, 200, 300)

:func:`load_preset` reads a preset by name (cached); :func:`read_preset` any file in the same
format; :meth:`Preset.overridden` applies a ``--config`` file's values over a preset. Every
malformed file, unknown name or unknown setting is a one-line :class:`ConfigError`.

A preset's ``version`` rises whenever a value changes, and ``versions.toml`` beside the presets
records each version's fingerprint (:attr:`Preset.fingerprint`, a hash of the values, not of
the evidence or the comments; :func:`recorded_versions`): a value changed without a new
version fails the tests. Version 1's values changed while it was current (the record began
with version 2), so a model that records version 1 may have learned with any of them.
"""

from __future__ import annotations

import functools
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from types import MappingProxyType
from typing import Any

from rnnpb._fingerprint import values_fingerprint
from rnnpb.errors import ConfigError

PRESET_NAMES: tuple[str, ...] = ("paper", "fast")
"""The learning presets, as ``rnnpb train --preset`` and the model files name them."""
REGISTRY = "versions.toml"
"""The file of this package that records each preset version's fingerprint."""

_RESERVED = ("name", "version", "description", "evidence", "sources")
_SOURCE_FIELDS = {"command": str, "draws": list, "figure": str, "note": str}


@dataclass(frozen=True)
class Source:
    """Where a value comes from.

    Attributes
    ----------
    id : str
    command : str
        The command that measured the choice; ``""`` when the search that chose it is not
        kept (``note`` then says where the choice was made).
    draws : tuple of int
        The draws of the user (scenario seeds) or learning seeds it was chosen on.
    figure : str
        What the choice met, in a line.
    note : str
    """

    id: str
    command: str
    draws: tuple[int, ...]
    figure: str
    note: str


@dataclass(frozen=True)
class Preset:
    """One learning preset's measured choices and their evidence (see the module).

    Attributes
    ----------
    name : str
    version : int
        Raised whenever a value changes; a model records the version it was learned with.
    description : str
    sources : mapping of str to Source
    """

    name: str
    version: int
    description: str
    sources: Mapping[str, Source]
    _sections: Mapping[str, Mapping[str, Any]] = field(repr=False)
    _evidence: Mapping[str, Mapping[str, str]] = field(repr=False)

    @property
    def fingerprint(self) -> str:
        """A hash of the preset's values (every section's, not the evidence): what a
        changed value changes (:mod:`rnnpb._fingerprint`)."""
        return values_fingerprint({name: dict(values) for name, values in self._sections.items()})

    @property
    def sections(self) -> tuple[str, ...]:
        """Every section's name, nested ones dotted (``"online.pb"``)."""
        return tuple(self._sections)

    def section(self, name: str) -> Mapping[str, Any]:
        """Section ``name``'s values (read-only), without its nested sections."""
        try:
            return self._sections[name]
        except KeyError:
            raise ConfigError(
                f"preset {self.name!r} has no section [{name}]; it has {', '.join(self._sections)}"
            ) from None

    def evidence(self, section: str, key: str) -> Source:
        """The source of section ``section``'s value ``key``."""
        if key not in self.section(section):
            raise ConfigError(f"preset {self.name!r} has no setting {key!r} in [{section}]")
        return self.sources[self._evidence[section][key]]

    def overridden(self, overrides: Mapping[str, Any], origin: str) -> Preset:
        """This preset with ``overrides`` (sections as in the preset files) over its values.

        Every overridden value's evidence becomes ``origin`` (a ``--config`` file's path). A
        section or key the preset does not have, or a value of another kind than the one it
        replaces, is a :class:`ConfigError` naming ``origin`` and the setting.
        """
        sections = {name: dict(values) for name, values in self._sections.items()}
        evidence = {name: dict(keys) for name, keys in self._evidence.items()}
        source = Source(f"override:{origin}", "", (), "", f"set by {origin}")
        for path, key, value in _leaves(overrides, origin, ()):
            section = ".".join(path)
            if section not in sections or key not in sections[section]:
                raise ConfigError(f"{origin}: unknown setting {key!r} in [{section or '-'}]")
            old = sections[section][key]
            sections[section][key] = _same_kind(_frozen(value), old, f"{origin}: [{section}] {key}")
            evidence[section][key] = source.id
        return Preset(
            self.name,
            self.version,
            self.description,
            MappingProxyType({**self.sources, source.id: source}),
            _freeze_sections(sections),
            MappingProxyType({k: MappingProxyType(v) for k, v in evidence.items()}),
        )


@functools.cache
def load_preset(name: str) -> Preset:
    """The learning preset called ``name`` (one of :data:`PRESET_NAMES`), read once."""
    if name not in PRESET_NAMES:
        raise ConfigError(
            f"unknown learning preset {name!r}; choose one of {', '.join(PRESET_NAMES)}"
        )
    text = resources.files(__name__).joinpath(f"{name}.toml").read_text(encoding="utf-8")
    preset = _parse(text, f"preset {name}.toml")
    if preset.name != name:
        raise ConfigError(f"preset {name}.toml: names itself {preset.name!r}")
    return preset


@dataclass(frozen=True)
class RecordedVersion:
    """One preset version as ``versions.toml`` records it: the fingerprint of its values, and
    the fingerprints of other values it held (``earlier``, oldest first, with ``note`` saying
    when): version 1's values changed while it was current."""

    preset: str
    version: int
    fingerprint: str
    earlier: tuple[str, ...] = ()
    note: str = ""


@functools.cache
def recorded_versions() -> Mapping[tuple[str, int], RecordedVersion]:
    """Every preset version ``versions.toml`` records, by (preset, version)."""
    where = f"preset {REGISTRY}"
    try:
        data = tomllib.loads(resources.files(__name__).joinpath(REGISTRY).read_text("utf-8"))
    except (OSError, UnicodeDecodeError) as error:
        raise ConfigError(f"{where}: cannot read it ({error})") from None
    except tomllib.TOMLDecodeError as error:
        raise ConfigError(f"{where}: not TOML ({error})") from None
    recorded: dict[tuple[str, int], RecordedVersion] = {}
    for name, versions in data.items():
        if not isinstance(versions, list):
            raise ConfigError(f"{where}: [[{name}]] must be a list of tables")
        for entry in versions:
            version, fingerprint = entry.get("version"), entry.get("fingerprint")
            earlier, note = entry.get("earlier", []), entry.get("note", "")
            if (
                isinstance(version, bool)
                or not isinstance(version, int)
                or not isinstance(fingerprint, str)
                or not isinstance(earlier, list)
                or not isinstance(note, str)
                or (earlier and not note)
            ):
                raise ConfigError(
                    f"{where}: [[{name}]] needs a whole version, a fingerprint string, and a "
                    "note beside any earlier fingerprints"
                )
            recorded[name, version] = RecordedVersion(
                name, version, fingerprint, tuple(map(str, earlier)), note
            )
    return MappingProxyType(recorded)


def read_preset(path: str | Path) -> Preset:
    """A preset read from the TOML file at ``path`` (the format of the shipped presets)."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as error:
        raise ConfigError(f"{path}: cannot read it ({error})") from None
    return _parse(text, str(path))


def read_overrides(path: str | Path) -> dict[str, Any]:
    """A ``--config`` file's tables, checked to be TOML (their keys are checked where applied)."""
    try:
        return tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as error:
        raise ConfigError(f"{path}: cannot read it ({error})") from None
    except tomllib.TOMLDecodeError as error:
        raise ConfigError(f"{path}: not TOML ({error})") from None


def _parse(text: str, origin: str) -> Preset:
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ConfigError(f"{origin}: not TOML ({error})") from None
    name, version = data.get("name"), data.get("version")
    description = data.get("description", "")
    if not isinstance(name, str) or not name:
        raise ConfigError(f"{origin}: 'name' must be a string")
    if isinstance(version, bool) or not isinstance(version, int) or version < 1:
        raise ConfigError(f"{origin}: 'version' must be a whole number >= 1, got {version!r}")
    if not isinstance(description, str):
        raise ConfigError(f"{origin}: 'description' must be a string")
    sources = _sources(data.get("sources", {}), origin)
    values = {key: value for key, value in data.items() if key not in _RESERVED}
    sections: dict[str, dict[str, Any]] = {}
    for path, key, value in _leaves(values, origin, ()):
        if not path:
            raise ConfigError(f"{origin}: {key!r} lies outside every section")
        sections.setdefault(".".join(path), {})[key] = _frozen(value)
    evidence_table = data.get("evidence", {})
    if not isinstance(evidence_table, dict):
        raise ConfigError(f"{origin}: [evidence] must be a table")
    evidence: dict[str, dict[str, str]] = {}
    for path, key, value in _leaves(evidence_table, origin, ()):
        section = ".".join(path)
        if section not in sections or key not in sections[section]:
            raise ConfigError(
                f"{origin}: evidence for {key!r} in [{section}], which has no such value"
            )
        if not isinstance(value, str) or value not in sources:
            raise ConfigError(
                f"{origin}: the evidence of [{section}] {key} names no source ({value!r})"
            )
        evidence.setdefault(section, {})[key] = value
    for section, keys in sections.items():
        missing = [key for key in keys if key not in evidence.get(section, {})]
        if missing:
            raise ConfigError(f"{origin}: [{section}] {missing[0]} has no evidence")
    return Preset(
        name,
        version,
        description,
        MappingProxyType(sources),
        _freeze_sections(sections),
        MappingProxyType({k: MappingProxyType(v) for k, v in evidence.items()}),
    )


def _sources(table: Any, origin: str) -> dict[str, Source]:
    if not isinstance(table, dict):
        raise ConfigError(f"{origin}: [sources] must be a table")
    sources = {}
    for source_id, entry in table.items():
        if not isinstance(entry, dict) or set(entry) != set(_SOURCE_FIELDS):
            raise ConfigError(
                f"{origin}: [sources.{source_id}] must hold exactly {', '.join(_SOURCE_FIELDS)}"
            )
        for key, kind in _SOURCE_FIELDS.items():
            if not isinstance(entry[key], kind):
                raise ConfigError(
                    f"{origin}: [sources.{source_id}] {key} must be a {kind.__name__}"
                )
        draws = entry["draws"]
        if not all(isinstance(d, int) and not isinstance(d, bool) for d in draws):
            raise ConfigError(f"{origin}: [sources.{source_id}] draws must be whole numbers")
        sources[source_id] = Source(
            source_id, entry["command"], tuple(draws), entry["figure"], entry["note"]
        )
    return sources


def _leaves(table: Mapping[str, Any], origin: str, path: tuple[str, ...]):
    """(section path, key, value) for every value that is not a table."""
    if not isinstance(table, Mapping):
        raise ConfigError(f"{origin}: [{'.'.join(path)}] must be a table")
    for key, value in table.items():
        if isinstance(value, dict):
            yield from _leaves(value, origin, (*path, key))
        else:
            yield path, key, value


def _frozen(value: Any) -> Any:
    if isinstance(value, list):
        return tuple(_frozen(item) for item in value)
    return value


def _same_kind(value: Any, old: Any, where: str) -> Any:
    """``value`` in place of ``old``: a whole number may stand for a float, nothing else."""
    if isinstance(old, bool) or isinstance(value, bool):
        ok = isinstance(old, bool) and isinstance(value, bool)
    elif isinstance(old, float):
        ok = isinstance(value, int | float)
        value = float(value) if ok else value
    else:
        ok = isinstance(value, type(old))
    if not ok:
        raise ConfigError(f"{where} must be a {type(old).__name__}, got {value!r:.40}")
    return value


def _freeze_sections(
    sections: Mapping[str, Mapping[str, Any]],
) -> Mapping[str, Mapping[str, Any]]:
    return MappingProxyType({name: MappingProxyType(dict(v)) for name, v in sections.items()})


__all__ = [
    "PRESET_NAMES",
    "REGISTRY",
    "Preset",
    "RecordedVersion",
    "Source",
    "load_preset",
    "read_overrides",
    "read_preset",
    "recorded_versions",
]
