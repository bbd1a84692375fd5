"""The learning presets' measured choices, as data.

Each learning preset is one versioned TOML file in this package: ``paper.toml`` for models
learned by the paper's algorithm, ``fast.toml`` for the fast preset (Adam). A file holds the
values chosen for that preset's models, one table per job — ``[learning]``, ``[online]``,
``[recognition]``, ``[recognition_untaught]``, ``[consolidation]``, ``[teaching]``, ... — and,
for every value, its evidence: ``[evidence.<section>]`` maps each key to the id of a
``[sources.<id>]`` entry that says what kind of evidence it is, which command measures it, on
which draws, and which figure it met.

A source's ``kind`` (:data:`KINDS`) is one of:

- ``paper``: the paper's value (Ito & Tani 2004); no command, draws or figure;
- ``documented``: a value set for a reason the note states (an operational choice, the
  package's reading of the paper, a value derived from another), not measured; no command,
  draws or figure;
- ``unmeasured``: a chosen value that no repeatable measure supports: measured by a search or
  harness that was not kept (the figure and draws say what it measured then, the note why it
  cannot be rerun), or set when a part was built and never searched. A command, if given,
  repeats a measure *like* the one that chose it, whose figure may differ;
- ``measured``: its ``command`` (``python benchmarks/NAME.py ...`` or ``python tools/NAME.py
  ...``, run from a checkout) reproduces its ``figure`` on its ``draws`` (development draws).

A measured source may also say how dear its harness is, ``cost = "cheap"`` (seconds on one
core, from a checkout, with no input prepared beforehand) or ``"costly"`` (the default), and
what it expects, ``expect = {figure = value, ..., tolerance = t}``: the harness writes its
figures as JSON to the file its command names ``JSON``, each key of ``expect`` is a path into
that JSON (``/`` between levels), a number held to within ``tolerance`` (absolute, default 0)
and anything else exactly. In a command, ``DIR`` is a folder the harness writes in and
``JSON`` that file; ``rnnpb presets evidence --check NAME`` runs the cheap harnesses with
fresh ones and fails when a figure differs (:mod:`rnnpb.presets.evidence`).

A nested table is a section of its own, named by its dotted path: ``[online.pb]`` is section
``"online.pb"``, its evidence ``[evidence.online.pb]``. Lists are read as tuples, so a
section's values are hashable, as the compiled code needs its static settings to be.

>>> preset = load_preset("paper")
>>> preset.section("online")["surprise_gate"]
0.035
>>> preset.evidence("online", "surprise_gate").draws
(100, 200, 300)
>>> preset.evidence("online", "window").kind
'paper'

:func:`load_preset` reads a preset by name (cached); :func:`read_preset` any file in the same
format. A ``--config`` file is :class:`Overrides` (:meth:`Overrides.read`): its tables, checked
against the preset files, are read where the preset's are — over any preset
(:meth:`Overrides.preset`, a :meth:`Preset.overridden`) or as one section's values
(:meth:`Overrides.values`). Every malformed file, unknown name or unknown setting is a one-line
:class:`ConfigError`.

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

from rnnpb._fingerprint import read_registry, values_fingerprint
from rnnpb.errors import ConfigError

PRESET_NAMES: tuple[str, ...] = ("paper", "fast")
"""The learning presets, as ``rnnpb train --preset`` and the model files name them."""
REGISTRY = "versions.toml"
"""The file of this package that records each preset version's fingerprint."""

KINDS: tuple[str, ...] = ("paper", "documented", "unmeasured", "measured")
"""The kinds of evidence a source is (see the module)."""
COSTS: tuple[str, ...] = ("cheap", "costly")
"""How dear a measured source's harness is to run again: ``cheap`` ones ``--check`` reruns."""
HARNESS_FOLDERS: tuple[str, ...] = ("benchmarks", "tools")
"""Where in a checkout the harnesses that measure a preset's values live."""

_RESERVED = ("name", "version", "description", "evidence", "sources")
_SOURCE_FIELDS = {"kind": str, "command": str, "draws": list, "figure": str, "note": str}
_OPTIONAL_FIELDS = ("cost", "expect")


@dataclass(frozen=True)
class Source:
    """Where a value comes from.

    Attributes
    ----------
    id : str
    command : str
        ``measured``: the harness that reproduces the figure (``python benchmarks/NAME.py
        ...`` or ``python tools/NAME.py ...``); ``unmeasured``: ``""``, or a harness that
        repeats a measure like the one that chose the value (its figure may differ);
        ``paper`` and ``documented``: ``""``.
    draws : tuple of int
        The draws of the user (scenario seeds) or learning seeds the figure comes from.
    figure : str
        What the value met, in a line (``""`` for a value that claims no measure).
    note : str
        The reason (``paper``, ``documented``), what was measured then and why it cannot be
        rerun (``unmeasured``), or anything else a reader needs.
    kind : str
        One of :data:`KINDS`.
    cost : str
        One of :data:`COSTS` (a measured source's; ``costly`` unless the file says).
    expect : mapping of str to value
        The figures the harness's JSON must hold (paths with ``/`` between levels).
    tolerance : float
        How far a number of ``expect`` may lie from the figure the harness gives.
    """

    id: str
    command: str
    draws: tuple[int, ...]
    figure: str
    note: str
    kind: str = "documented"
    cost: str = "costly"
    expect: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))
    tolerance: float = 0.0

    @property
    def claims_a_measure(self) -> bool:
        """Whether the source gives a figure or draws: something was measured."""
        return bool(self.figure or self.draws)

    @property
    def harness(self) -> str:
        """The harness's path in a checkout (``benchmarks/NAME.py``), ``""`` without one."""
        words = self.command.split()
        return words[1] if len(words) > 1 and words[0] == "python" else ""


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

    def values(self, section: str) -> dict[str, Any]:
        """Section ``section``'s values with its ``pb`` section (``[section.pb]``), if any, as
        a dict under ``"pb"``: what a config of the section takes."""
        values = dict(self.section(section))
        return _with_pb(values, self._sections, section)

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
        source = Source(f"override:{origin}", "", (), "", f"set by {origin}", "documented")
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


@dataclass(frozen=True)
class Overrides:
    """Values put over a preset's for one run: a ``--config`` file (research; docs/model.md,
    "Settings"), handed unchanged to the code that makes each config.

    Attributes
    ----------
    tables : mapping of str to dict
        Each section the file names, dotted (``"online"``, ``"online.pb"``), to its values,
        each of the kind the preset's value has (plain dicts: a worker process gets them
        pickled).
    origin : str
        Where they come from (the file's path): the evidence of each value they change.
    """

    tables: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    origin: str = "--config"

    @classmethod
    def read(cls, path: str | Path, reads: tuple[str, ...] = (), reader: str = "") -> Overrides:
        """The ``--config`` file at ``path``, checked: each key must be one of the preset
        files', its value of that key's kind, and its section (with its ``.pb`` section) one of
        ``reads`` (empty: any), which ``reader`` (``"rnnpb train"``) reads. Every problem is
        one :class:`ConfigError` line naming the file and the key."""
        data = read_overrides(path)
        # The paper preset has every section; its values give each key's kind.
        checked = load_preset("paper").overridden(data, str(path))
        tables: dict[str, dict[str, Any]] = {}
        for keys, key, _ in _leaves(data, str(path), ()):
            section = ".".join(keys)
            if reads and section.removesuffix(".pb") not in reads:
                raise ConfigError(
                    f"{path}: [{section}] does not apply to {reader} "
                    f"(it reads {', '.join(f'[{name}]' for name in reads)})"
                )
            tables.setdefault(section, {})[key] = checked.section(section)[key]
        return cls(tables, str(path))

    @property
    def names(self) -> tuple[str, ...]:
        """The sections the file names."""
        return tuple(self.tables)

    def values(self, section: str) -> dict[str, Any]:
        """Section ``section``'s values as :meth:`Preset.values` gives a preset's (``pb``
        nested); empty when the file does not name it."""
        return _with_pb(dict(self.tables.get(section, {})), self.tables, section)

    def preset(self, name: str) -> Preset:
        """Learning preset ``name`` with these values over its own (each changed value's
        evidence: :attr:`origin`)."""
        preset = load_preset(name)
        return preset.overridden(self.tables, self.origin) if self.tables else preset


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
    data = read_registry(__name__, REGISTRY, where)
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
    return {
        source_id: _source(source_id, entry, f"{origin}: [sources.{source_id}]")
        for source_id, entry in table.items()
    }


def _source(source_id: str, entry: Any, where: str) -> Source:
    """One ``[sources.<id>]`` entry, checked (see the module); every problem one line."""
    required = set(_SOURCE_FIELDS)
    if not isinstance(entry, dict) or not required <= set(entry) <= required | set(
        _OPTIONAL_FIELDS
    ):
        raise ConfigError(
            f"{where} must hold exactly {', '.join(_SOURCE_FIELDS)} (and may hold "
            f"{' and '.join(_OPTIONAL_FIELDS)})"
        )
    for key, kind in _SOURCE_FIELDS.items():
        if not isinstance(entry[key], kind):
            raise ConfigError(f"{where} {key} must be a {kind.__name__}")
    draws = entry["draws"]
    if not all(isinstance(d, int) and not isinstance(d, bool) for d in draws):
        raise ConfigError(f"{where} draws must be whole numbers")
    kind, command = entry["kind"], entry["command"]
    if kind not in KINDS:
        raise ConfigError(f"{where} kind must be one of {', '.join(KINDS)}, got {kind!r}")
    if kind in ("paper", "documented"):
        if command or draws or entry["figure"]:
            raise ConfigError(
                f"{where} is {kind}: it claims no measure, so its command, draws and figure "
                "are empty (a measured value is 'measured', one measured once 'unmeasured')"
            )
    if kind != "measured" and not entry["note"]:
        raise ConfigError(f"{where} is {kind}: its note must say why the value is what it is")
    if kind == "measured" and not (command and entry["figure"]):
        raise ConfigError(f"{where} is measured: it needs the command and the figure it gives")
    if command and not _is_harness(command):
        forms = " or ".join(f"'python {folder}/NAME.py ...'" for folder in HARNESS_FOLDERS)
        raise ConfigError(
            f"{where} command must run a harness of the checkout, {forms}; got {command!r:.60}"
        )
    cost, expect = entry.get("cost", "costly"), entry.get("expect", {})
    if ("cost" in entry or "expect" in entry) and kind != "measured":
        raise ConfigError(f"{where} is {kind}: only a measured source has a cost or expect")
    if cost not in COSTS:
        raise ConfigError(f"{where} cost must be one of {', '.join(COSTS)}, got {cost!r}")
    if not isinstance(expect, dict):
        raise ConfigError(f"{where} expect must be a table of figures")
    if expect and "JSON" not in command.split():
        raise ConfigError(
            f"{where} expect needs the command to name JSON, the file its harness writes"
        )
    figures = dict(expect)
    tolerance = figures.pop("tolerance", 0.0)
    if isinstance(tolerance, bool) or not isinstance(tolerance, int | float) or tolerance < 0:
        raise ConfigError(f"{where} expect.tolerance must be a number >= 0, got {tolerance!r}")
    if expect and not figures:
        raise ConfigError(f"{where} expect names no figure besides its tolerance")
    for key, value in figures.items():
        if not isinstance(value, bool | int | float | str):
            raise ConfigError(
                f"{where} expect.{key} must be a number, true or false, or text, got {value!r}"
            )
    return Source(
        source_id,
        command,
        tuple(draws),
        entry["figure"],
        entry["note"],
        kind,
        cost,
        MappingProxyType(figures),
        float(tolerance),
    )


def _is_harness(command: str) -> bool:
    """Whether ``command`` runs a script of the checkout's benchmarks/ or tools/."""
    words = command.split()
    if len(words) < 2 or words[0] != "python":
        return False
    folder, _, script = words[1].partition("/")
    return folder in HARNESS_FOLDERS and script.endswith(".py") and "/" not in script


def _leaves(table: Mapping[str, Any], origin: str, path: tuple[str, ...]):
    """(section path, key, value) for every value that is not a table."""
    if not isinstance(table, Mapping):
        raise ConfigError(f"{origin}: [{'.'.join(path)}] must be a table")
    for key, value in table.items():
        if isinstance(value, dict):
            yield from _leaves(value, origin, (*path, key))
        else:
            yield path, key, value


def _with_pb(
    values: dict[str, Any], sections: Mapping[str, Mapping[str, Any]], section: str
) -> dict[str, Any]:
    """``values`` of ``section`` with its ``pb`` section of ``sections`` as a dict under "pb"."""
    if f"{section}.pb" in sections:
        values["pb"] = dict(sections[f"{section}.pb"])
    return values


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
    "COSTS",
    "HARNESS_FOLDERS",
    "KINDS",
    "PRESET_NAMES",
    "REGISTRY",
    "Overrides",
    "Preset",
    "RecordedVersion",
    "Source",
    "load_preset",
    "read_overrides",
    "read_preset",
    "recorded_versions",
]
