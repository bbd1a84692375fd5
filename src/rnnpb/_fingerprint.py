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
from typing import Any

FINGERPRINT_DIGITS = 16
"""Hex digits kept of the SHA-256: 64 bits, far more than the versions a file will have."""


def values_fingerprint(values: Any) -> str:
    """A short hex fingerprint of ``values`` (tables, lists, tuples, strings, numbers, booleans
    as a TOML reader gives them)."""
    text = json.dumps(values, sort_keys=True, separators=(",", ":"), ensure_ascii=False)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:FINGERPRINT_DIGITS]


__all__ = ["FINGERPRINT_DIGITS", "values_fingerprint"]
