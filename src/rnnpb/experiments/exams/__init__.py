"""Each study's exam: the draws its targets are judged on, and each target's fixed definition.

An exam is a TOML file of this package, ``<study>.toml``, installed with rnnpb::

    [exam]
    study = "novelty"
    version = 1                     # a changed definition or draw is a new version

    [draws]                         # every seed the exam runs on, by what it seeds
    user = [7000, 7001]
    shapes = ["one-arm", "figure-eight"]   # optional: the shapes judged
    learning_sets = ["1", "full"]          # optional: the learning sets judged
    learn_styles = ["normal"]              # optional: any other list of names is a named draw

    [parameters]                    # optional: numbers every target's definition shares
    settle_steps = 24

    [sources]                       # optional: data the exam reads, where to get each
    clip_a = "owner/name@commit:path/in/repository.mp4"

    [[excluded]]                    # draws already used to choose or check a setting
    first = 0
    last = 1
    why = "the detector's settings were chosen on them"

    [targets.novel_within_3_cycles] # one table per target: its fixed definition
    counts = "novel movements called novel within 36 steps of their start, as a share"
    compare = ">="                  # the measured value against the limit: ">=" or "<="
    limit = 0.95
    [targets.novel_within_3_cycles.parameters]   # optional: this definition's own numbers
    steps = 36

``rnnpb study NAME --exam --out DIR`` runs the study on its exam's draws (:func:`load_exam`)
and judges every target by the exam's definitions (:meth:`Exam.judge`). A study judges its
targets by the same definitions on any draws; only an exam's draws make the verdict an exam.

Each exam has a fingerprint (:attr:`Exam.fingerprint`): a hash of its parsed ``[draws]``,
``[parameters]`` and ``[targets]``, and ``[sources]`` where it has one (:func:`exam_fingerprint`;
not of its comments, its version or its ``[[excluded]]`` draws, which may grow as more draws
are used elsewhere).
``versions.toml`` beside the exams records every version's fingerprint
(:func:`recorded_versions`): a value changed without a new version is caught by the tests and
refused by ``--exam`` (:func:`check_recorded`). Every exam run is written in the exam ledger
(:mod:`rnnpb.experiments.exams.ledger`), and a version is judged once.
"""

from __future__ import annotations

import functools
import math
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from importlib import resources
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

from rnnpb._fingerprint import read_registry, values_fingerprint
from rnnpb.errors import ConfigError

if TYPE_CHECKING:
    from rnnpb.experiments.summary import Target

COMPARISONS = (">=", "<=")
REGISTRY = "versions.toml"
"""The file of this package that records every exam version's fingerprint (not an exam)."""
FINGERPRINTED = ("draws", "parameters", "targets")
"""The tables of an exam file its fingerprint covers (and ``[sources]`` where it has one)."""


@dataclass(frozen=True)
class ExamTarget:
    """One target's fixed definition: what is counted (``counts``, in words), the measured
    value's comparison with ``limit``, and the definition's other numbers (``parameters``,
    e.g. the steps within which a lock-on counts)."""

    name: str
    counts: str
    compare: str
    limit: float
    parameters: Mapping[str, float] = field(default_factory=dict)

    def met(self, value: float | None) -> bool:
        """Whether ``value`` meets the target (a missing or undefined value does not)."""
        if value is None or not math.isfinite(value):
            return False
        return value >= self.limit if self.compare == ">=" else value <= self.limit

    def parameter(self, name: str) -> float:
        if name not in self.parameters:
            raise ConfigError(f"exam target {self.name!r} has no parameter {name!r}")
        return self.parameters[name]


@dataclass(frozen=True)
class ExcludedDraws:
    """Draws ``first`` … ``last`` (inclusive) already used to choose or check a setting, and
    so never an exam's."""

    first: int
    last: int
    why: str

    def __contains__(self, draw: int) -> bool:
        return self.first <= draw <= self.last


@dataclass(frozen=True)
class Exam:
    """A study's exam (:func:`load_exam`): ``seeds`` (what each seeds → its seeds), the
    shapes and learning sets judged (empty: the study's own), the numbers every definition
    shares (``parameters``), the draws excluded and the targets' definitions, in the file's
    order."""

    study: str
    version: int
    seeds: Mapping[str, tuple[int, ...]]
    shapes: tuple[str, ...]
    learning_sets: tuple[str, ...]
    excluded: tuple[ExcludedDraws, ...]
    targets: Mapping[str, ExamTarget]
    parameters: Mapping[str, float] = field(default_factory=dict)
    names: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    sources: Mapping[str, str] = field(default_factory=dict)
    fingerprint: str = ""

    def draws(self) -> frozenset[int]:
        """Every seed the exam runs on."""
        return frozenset(s for seeds in self.seeds.values() for s in seeds)

    def name_list(self, name: str) -> tuple[str, ...]:
        """A draw named by text (a list of names in ``[draws]``: styles, takes …)."""
        if name not in self.names:
            raise ConfigError(f"the {self.study} exam names no {name!r} draws")
        return self.names[name]

    def seed_list(self, name: str) -> tuple[int, ...]:
        if name not in self.seeds:
            raise ConfigError(f"the {self.study} exam names no {name!r} seeds")
        return self.seeds[name]

    def parameter(self, name: str) -> float:
        if name not in self.parameters:
            raise ConfigError(f"the {self.study} exam has no parameter {name!r}")
        return self.parameters[name]

    def target(self, name: str) -> ExamTarget:
        if name not in self.targets:
            raise ConfigError(f"the {self.study} exam defines no target {name!r}")
        return self.targets[name]

    def judge(self, values: Mapping[str, float | None]) -> dict[str, bool]:
        """Each target met or not, from its measured value (``values[name]``)."""
        missing = [name for name in self.targets if name not in values]
        if missing:
            raise ConfigError(f"the {self.study} exam's targets {missing} were not measured")
        return {name: target.met(values[name]) for name, target in self.targets.items()}

    def verdicts(
        self, measures: Mapping[str, Any], detail: Callable[[ExamTarget, float], str]
    ) -> dict[str, Target]:
        """Each target met or not from ``measures`` (by name), with ``detail(target, value)``
        saying by how much."""
        from rnnpb.experiments.summary import Target

        met = self.judge({key: measures[key] for key in self.targets})
        return {
            key: Target(met[key], detail(target, measures[key]), _figure(measures[key]))
            for key, target in self.targets.items()
        }

    def describe(self) -> str:
        """One sentence for a report: which exam judged it, on which draws."""
        named = {**self.seeds, **self.names}
        seeds = "; ".join(f"{k} {', '.join(map(str, v))}" for k, v in named.items())
        return (
            f"**Exam** `{self.study}` version {self.version} "
            f"(`rnnpb/experiments/exams/{self.study}.toml`): draws {seeds}. Every target is "
            "judged by the exam's definitions."
        )

    def to_json(self) -> dict[str, Any]:
        return {
            "study": self.study,
            "version": self.version,
            "seeds": {k: list(v) for k, v in self.seeds.items()},
            "shapes": list(self.shapes),
            "learning_sets": list(self.learning_sets),
            **({"names": {k: list(v) for k, v in self.names.items()}} if self.names else {}),
            "fingerprint": self.fingerprint,
        }


def _figure(value: Any) -> float | None:
    """A measured value as a target records it: a number, or None where none was taken."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return value


def exam_names() -> tuple[str, ...]:
    """The studies with an exam file."""
    files = resources.files(__name__).iterdir()
    names = (f.name for f in files if f.name.endswith(".toml") and f.name != REGISTRY)
    return tuple(sorted(name[:-5] for name in names))


def exam_fingerprint(data: Mapping[str, Any]) -> str:
    """The fingerprint of a parsed exam file's values: its draws, parameters and targets."""
    values = {key: data.get(key, {}) for key in FINGERPRINTED}
    if "sources" in data:
        values["sources"] = data["sources"]
    return values_fingerprint(values)


@dataclass(frozen=True)
class RecordedVersion:
    """One exam version as ``versions.toml`` records it: the fingerprint of its values, any
    earlier fingerprint the same version had before it was first run (``earlier``, with
    ``note`` saying why), and ``commit``, one where an older version's file can be read
    (``""``: the file in this package)."""

    study: str
    version: int
    fingerprint: str
    commit: str
    earlier: tuple[str, ...] = ()
    note: str = ""


@functools.cache
def recorded_versions() -> Mapping[tuple[str, int], RecordedVersion]:
    """Every exam version ``versions.toml`` records, by (study, version)."""
    where = f"exam {REGISTRY}"
    data = read_registry(__name__, REGISTRY, where)
    recorded: dict[tuple[str, int], RecordedVersion] = {}
    for study, versions in data.items():
        for i, entry in enumerate(_list(versions, f"{where}: {study}")):
            at = f"{where}: {study}[{i}]"
            entry = _table(entry, at)
            _keys(
                entry,
                at,
                {"version", "fingerprint", "commit", "earlier", "note"},
                {"version", "fingerprint"},
            )
            version = _whole(entry["version"], at + ".version")
            if (study, version) in recorded:
                raise ConfigError(f"{at}: version {version} is recorded twice")
            earlier = tuple(_text(f, at + ".earlier") for f in _list(entry.get("earlier", []), at))
            if earlier and not entry.get("note"):
                raise ConfigError(f"{at}: earlier fingerprints need a note saying why")
            recorded[study, version] = RecordedVersion(
                study,
                version,
                _text(entry["fingerprint"], at + ".fingerprint"),
                str(entry.get("commit", "")),
                earlier,
                str(entry.get("note", "")),
            )
    return MappingProxyType(recorded)


def check_recorded(exam: Exam) -> None:
    """Raise :class:`ConfigError` unless ``versions.toml`` records ``exam``'s version with
    the fingerprint of the values it holds now: a value changed without a new version."""
    recorded = recorded_versions().get((exam.study, exam.version))
    if recorded is None:
        raise ConfigError(
            f"the {exam.study} exam's version {exam.version} is not recorded in "
            f"rnnpb/experiments/exams/{REGISTRY}: record its fingerprint {exam.fingerprint} "
            "before it is run"
        )
    if recorded.fingerprint != exam.fingerprint:
        raise ConfigError(
            f"the {exam.study} exam's values changed under version {exam.version} "
            f"(fingerprint {exam.fingerprint}, recorded {recorded.fingerprint}): a changed "
            "value is a new version, with fresh draws"
        )


def load_exam(name: str) -> Exam:
    """The exam of study ``name``; any problem with its file is one :class:`ConfigError`
    line naming the file."""
    where = f"exam {name}.toml"
    file = resources.files(__name__).joinpath(f"{name}.toml")
    if not file.is_file():
        raise ConfigError(f"no exam for study {name!r} (exams: {', '.join(exam_names())})")
    try:
        data = tomllib.loads(file.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as error:
        raise ConfigError(f"{where}: cannot read it ({error})") from None
    except tomllib.TOMLDecodeError as error:
        raise ConfigError(f"{where}: not TOML ({error})") from None
    try:
        exam = parse_exam(data)
    except ConfigError as error:
        raise ConfigError(f"{where}: {error}") from None
    if exam.study != name:
        raise ConfigError(f"{where}: it is the exam of {exam.study!r}")
    return exam


def parse_exam(data: Mapping[str, Any]) -> Exam:
    """An :class:`Exam` from a parsed exam file; a malformed one raises :class:`ConfigError`."""
    known = {"exam", "draws", "parameters", "excluded", "targets", "sources"}
    _keys(data, "the file", known, {"exam", "draws", "targets"})
    head = _table(data["exam"], "[exam]")
    _keys(head, "[exam]", {"study", "version"}, {"study", "version"})
    study = _text(head["study"], "exam.study")
    version = _whole(head["version"], "exam.version")
    if version < 1:
        raise ConfigError(f"exam.version must be >= 1, got {version}")

    draws = _table(data["draws"], "[draws]")
    seeds: dict[str, tuple[int, ...]] = {}
    shapes: tuple[str, ...] = ()
    sets: tuple[str, ...] = ()
    names: dict[str, tuple[str, ...]] = {}
    for key, value in draws.items():
        if key == "shapes":
            shapes = tuple(_text(v, "draws.shapes") for v in _list(value, "draws.shapes"))
        elif key == "learning_sets":
            sets = tuple(_text(v, "draws.learning_sets") for v in _list(value, key))
        elif _list(value, f"draws.{key}") and all(isinstance(v, str) for v in value):
            names[key] = tuple(_text(v, f"draws.{key}") for v in value)
        else:
            seeds[key] = tuple(_whole(v, f"draws.{key}") for v in _list(value, f"draws.{key}"))
            if not seeds[key] or min(seeds[key]) < 0:
                raise ConfigError(f"draws.{key} must list seeds >= 0")
    if not seeds:
        raise ConfigError("[draws] names no seeds")

    excluded = []
    for i, entry in enumerate(_list(data.get("excluded", []), "excluded")):
        where = f"excluded[{i}]"
        entry = _table(entry, where)
        _keys(entry, where, {"first", "last", "why"}, {"first", "last", "why"})
        first = _whole(entry["first"], where + ".first")
        last = _whole(entry["last"], where + ".last")
        if last < first:
            raise ConfigError(f"{where}: last {last} is before first {first}")
        excluded.append(ExcludedDraws(first, last, _text(entry["why"], where + ".why")))
    used = sorted(
        d for d in {s for v in seeds.values() for s in v} if any(d in e for e in excluded)
    )
    if used:
        raise ConfigError(f"draws {used} are excluded: they were used to choose a setting")

    targets = {}
    for name, entry in _table(data["targets"], "[targets]").items():
        where = f"targets.{name}"
        entry = _table(entry, where)
        _keys(
            entry,
            where,
            {"counts", "compare", "limit", "parameters"},
            {"counts", "compare", "limit"},
        )
        compare = entry["compare"]
        if compare not in COMPARISONS:
            raise ConfigError(f"{where}.compare must be one of {COMPARISONS}, got {compare!r}")
        parameters = _parameters(entry.get("parameters", {}), where + ".parameters")
        targets[name] = ExamTarget(
            name,
            _text(entry["counts"], where + ".counts"),
            compare,
            _number(entry["limit"], where + ".limit"),
            MappingProxyType(parameters),
        )
    if not targets:
        raise ConfigError("[targets] defines no target")
    return Exam(
        study,
        version,
        MappingProxyType(seeds),
        shapes,
        sets,
        tuple(excluded),
        MappingProxyType(targets),
        MappingProxyType(_parameters(data.get("parameters", {}), "[parameters]")),
        MappingProxyType(names),
        MappingProxyType(
            {
                key: _text(value, f"sources.{key}")
                for key, value in _table(data.get("sources", {}), "[sources]").items()
            }
        ),
        exam_fingerprint(data),
    )


def _parameters(value: Any, where: str) -> dict[str, float]:
    return {key: _number(v, f"{where}.{key}") for key, v in _table(value, where).items()}


def _keys(table: Mapping[str, Any], where: str, allowed: set[str], required: set[str]) -> None:
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise ConfigError(f"{where}: unknown key(s) {unknown} (known: {sorted(allowed)})")
    missing = sorted(required - set(table))
    if missing:
        raise ConfigError(f"{where}: missing {missing}")


def _table(value: Any, where: str) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise ConfigError(f"{where} must be a table")
    return value


def _list(value: Any, where: str) -> list[Any]:
    if not isinstance(value, list):
        raise ConfigError(f"{where} must be a list")
    return value


def _text(value: Any, where: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise ConfigError(f"{where} must be a non-empty string, got {value!r}")
    return value


def _whole(value: Any, where: str) -> int:
    if not isinstance(value, int) or isinstance(value, bool):
        raise ConfigError(f"{where} must be a whole number, got {value!r}")
    return value


def _number(value: Any, where: str) -> float:
    """A finite number, kept whole if written whole (a count of steps stays a count)."""
    if not isinstance(value, int | float) or isinstance(value, bool) or not math.isfinite(value):
        raise ConfigError(f"{where} must be a finite number, got {value!r}")
    return value


__all__ = [
    "REGISTRY",
    "Exam",
    "ExamTarget",
    "ExcludedDraws",
    "RecordedVersion",
    "check_recorded",
    "exam_fingerprint",
    "exam_names",
    "load_exam",
    "parse_exam",
    "recorded_versions",
]
