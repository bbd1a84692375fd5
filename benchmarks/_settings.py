"""The variants a benchmark compares, as the command line writes them.

A variant is ``default`` (the preset's values) or ``key=value`` pairs joined by commas, e.g.
``learning_rate=0.3`` or ``pb.learning_rate=0.5,pb.k_nb=0.2``: ``pb.KEY`` is a value of the
PB update's table (``[learning.pb]``, ``[online.pb]``), a value is read as TOML (``0.3``,
``false``) and otherwise kept as text (``recorded``).
"""

from __future__ import annotations

import tomllib
from typing import Any


def variant_tables(text: str, section: str) -> dict[str, dict[str, Any]]:
    """A variant as a ``--config`` file's tables of ``section`` (``{section: ...,
    section.pb: ...}``; none for ``default``), as :class:`rnnpb.presets.Overrides` holds them."""
    if text.strip() == "default":
        return {}
    changes: dict[str, dict[str, Any]] = {}
    for pair in text.split(","):
        key, sign, value = pair.partition("=")
        if not sign or not key.strip():
            raise SystemExit(f"variant {text!r}: expected key=value[,key=value], got {pair!r}")
        key = key.strip()
        try:
            parsed = tomllib.loads(f"v = {value.strip()}")["v"]
        except tomllib.TOMLDecodeError:
            parsed = value.strip()
        if key.startswith("pb."):
            changes.setdefault(f"{section}.pb", {})[key[3:]] = parsed
        else:
            changes.setdefault(section, {})[key] = parsed
    return changes


def apply_variant(config: Any, text: str, section: str) -> Any:
    """``config`` (a ``TrainConfig``, ``OnlineConfig`` ...) with variant ``text``: its settings
    replaced, its tuned values by ``with_tuning``, as a ``--config`` file's table would."""
    from rnnpb.model._tuned import with_values
    from rnnpb.presets import Overrides

    return with_values(config, Overrides(variant_tables(text, section), text).values(section))


def processor() -> str:
    """The machine the figures come from (the exam ledger's wording)."""
    from rnnpb.experiments.exams.ledger import processor as named

    return named()
