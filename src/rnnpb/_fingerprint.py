"""The fingerprint of a file's values: what changes when a value changes, and nothing else.

A versioned file of values (an exam's draws and targets, a learning preset's settings) records
a ``version`` that must rise whenever a value changes. Its fingerprint is a hash of the values
as parsed, so comments, layout, the order of a table's keys and the way a number is spelled
(``0.90`` or ``0.9``) leave it alone, while any changed value, a whole number written as a
float (``1`` or ``1.0``: the readers keep counts whole), an added or removed key, or a
reordered list (lists are drawn in order) changes it. A committed record of each version's
fingerprint lets a test tell a changed value from a new version.
"""

from __future__ import annotations

import hashlib
import json
import tomllib
from importlib import resources
from typing import Any

from rnnpb.errors import ConfigError

FINGERPRINT_DIGITS = 16
"""Hex digits kept of the SHA-256: 64 bits, far more than the versions a file will have."""


def values_fingerprint(values: Any) -> str:
    """A short hex fingerprint of ``values`` (tables, lists, tuples, strings, numbers, booleans
    as a TOML reader gives them)."""
    text = json.dumps(values, sort_keys=True, separators=(",", ":"), ensure_ascii=False)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:FINGERPRINT_DIGITS]


def read_registry(package: str, name: str, where: str) -> dict[str, Any]:
    """The versions' record ``name`` shipped in ``package`` (a TOML file), read as a table;
    a :class:`ConfigError` beginning with ``where`` when it cannot be read or parsed."""
    try:
        return tomllib.loads(resources.files(package).joinpath(name).read_text("utf-8"))
    except (OSError, UnicodeDecodeError) as error:
        raise ConfigError(f"{where}: cannot read it ({error})") from None
    except tomllib.TOMLDecodeError as error:
        raise ConfigError(f"{where}: not TOML ({error})") from None


__all__ = ["FINGERPRINT_DIGITS", "read_registry", "values_fingerprint"]
