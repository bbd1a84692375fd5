"""Checks of command-line numbers, shared by the commands: each refuses a bad value with one
:class:`rnnpb.errors.ConfigError` line naming the option, before any work starts."""

from __future__ import annotations

import math

from rnnpb.errors import ConfigError

#: At most this many steps in one command (about 11 days at the paper's 0.4 s a step): a
#: bound on what a mistyped number can make a command allocate.
MAX_STEPS = 2_500_000


def finite_seconds(option: str, value: float, low: float = 0.0, high: float = 3600.0) -> float:
    """A duration in seconds: finite and in (``low``, ``high``]."""
    if not math.isfinite(value) or not low < value <= high:
        raise ConfigError(
            f"{option} must be a number of seconds in ({low:g}, {high:g}], got {value}"
        )
    return value


def step_count(option: str, value: int | None, low: int = 1, high: int = MAX_STEPS) -> int | None:
    """A number of steps in [``low``, ``high``] (``None`` passes: the option was not given)."""
    if value is not None and not low <= value <= high:
        raise ConfigError(f"{option} must be in [{low}, {high:,}], got {value:,}")
    return value


def played_dt(model: object, learned: float, given: float | None) -> float:
    """The step time to play a model at: the one it was learned at; ``given`` (``--dt``) must
    be it, else :class:`ConfigError` saying how to learn at that step."""
    if given is None or math.isclose(given, learned, rel_tol=1e-9):
        return learned
    raise ConfigError(
        f"--dt {given:g}: {model} was learned at dt {learned:g} s and plays at that step only; "
        f"to play at {given:g} s, record its movements with `rnnpb record --dt {given:g}` and "
        "learn them again (`rnnpb train` takes the step from their recording.json)"
    )
