"""What the model's configs share: the values each reads from its learning preset.

A config (:class:`~rnnpb.model.TrainConfig`, :class:`~rnnpb.model.OnlineConfig`,
:class:`~rnnpb.model.recognition.RecognitionConfig`) takes the settings a user changes as
constructor arguments; every other value is *tuned*: read from a section of a preset file
(:mod:`rnnpb.presets`), held in a :class:`Tuning`, and shown as a read-only dataclass field
(``init=False``), so that the config compares, hashes and serialises as one record of every
value — the compiled code sees the same static settings as before, and a recorded config
reads back the same. ``config.with_tuning(name=value)`` is the one way to change a tuned
value.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import fields, replace
from typing import Any, TypeVar

from rnnpb.errors import ConfigError
from rnnpb.presets import Preset, load_preset

Config = TypeVar("Config")


class Tuning(Mapping[str, Any]):
    """A config's tuned values and the preset they came from (frozen, hashable, picklable).

    Attributes
    ----------
    preset : str
        The learning preset the values were read from (``"paper"`` or ``"fast"``).
    """

    __slots__ = ("_items", "preset")
    preset: str
    _items: tuple[tuple[str, Any], ...]

    def __init__(self, preset: str, values: Mapping[str, Any]) -> None:
        object.__setattr__(self, "preset", preset)
        object.__setattr__(self, "_items", tuple(values.items()))

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError("a Tuning is frozen; use the config's with_tuning()")

    def __getitem__(self, key: str) -> Any:
        for name, value in self._items:
            if name == key:
                return value
        raise KeyError(key)

    def __iter__(self) -> Iterator[str]:
        return (name for name, _ in self._items)

    def __len__(self) -> int:
        return len(self._items)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Tuning):
            return NotImplemented
        return self.preset == other.preset and dict(self._items) == dict(other._items)

    def __hash__(self) -> int:
        return hash((self.preset, frozenset(self._items)))

    def __reduce__(self) -> tuple[Any, ...]:
        return (Tuning, (self.preset, dict(self._items)))

    def __repr__(self) -> str:
        return f"Tuning({self.preset!r}, {dict(self._items)!r})"


def tuned_names(cls: type) -> tuple[str, ...]:
    """The tuned fields of a config class: those the constructor does not take."""
    return tuple(f.name for f in fields(cls) if not f.init)


def user_names(cls: type) -> tuple[str, ...]:
    """The settings a user gives a config class's constructor."""
    return tuple(f.name for f in fields(cls) if f.init)


def section_values(preset: Preset | str, section: str) -> dict[str, Any]:
    """A preset section's values, with its ``pb`` subsection (if any) as a dict under "pb"."""
    return (load_preset(preset) if isinstance(preset, str) else preset).values(section)


def settle(config: Any, tuning: Mapping[str, Any] | None, default: Tuning, pb_type: Any) -> None:
    """In a config's ``__post_init__``: set its tuned fields from ``tuning``.

    ``tuning`` None takes ``default`` (the preset's); a :class:`Tuning` is taken as it is; a
    plain mapping changes ``default`` where it names a value. A ``pb`` value may be a
    mapping (``pb_type`` builds it). An unknown name is a :class:`ConfigError`.
    """
    names = tuned_names(type(config))
    if isinstance(tuning, Tuning):
        values = dict(tuning)
        preset = tuning.preset
    else:
        values = dict(default)
        preset = default.preset
        for key, value in (tuning or {}).items():
            if key not in names:
                raise ConfigError(
                    f"{type(config).__name__} has no tuned setting {key!r} "
                    f"(tuned: {', '.join(names)})"
                )
            values[key] = value
    missing = [name for name in names if name not in values]
    if missing:
        raise ConfigError(f"{type(config).__name__}: no value for {', '.join(missing)}")
    if "pb" in values and isinstance(values["pb"], Mapping):
        values["pb"] = pb_type(**values["pb"])
    for name in names:
        object.__setattr__(config, name, values[name])
    object.__setattr__(config, "_tuning", Tuning(preset, {n: values[n] for n in names}))


def tuning_of(config: Any) -> Tuning:
    """The :class:`Tuning` a config was made with."""
    return vars(config)["_tuning"]


def with_tuning(config: Config, changes: Mapping[str, Any]) -> Config:
    """``config`` with the tuned values in ``changes`` (a ``pb`` mapping changes the named
    coefficients only)."""
    current = tuning_of(config)
    values = dict(current)
    for key, value in changes.items():
        if key not in values:
            raise ConfigError(
                f"{type(config).__name__} has no tuned setting {key!r} "
                f"(tuned: {', '.join(values)}; settings: {', '.join(user_names(type(config)))})"
            )
        if key == "pb" and isinstance(value, Mapping):
            value = replace(values["pb"], **value)
        values[key] = value
    user = {name: getattr(config, name) for name in user_names(type(config))}
    return type(config)(**user, _tuning=Tuning(current.preset, values))  # type: ignore[call-arg]


def with_values(config: Config, values: Mapping[str, Any]) -> Config:
    """``config`` with ``values`` (a section's, as :meth:`rnnpb.presets.Overrides.values`
    gives a ``--config`` file's): its settings by :func:`dataclasses.replace`, its tuned
    values by ``with_tuning``."""
    if not values:
        return config
    settings = set(user_names(type(config)))
    tuned = {k: v for k, v in values.items() if k not in settings}
    changed = config.with_tuning(**tuned) if tuned else config  # type: ignore[attr-defined]
    return replace(changed, **{k: v for k, v in values.items() if k in settings})  # type: ignore[type-var]
