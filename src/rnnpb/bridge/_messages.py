"""The bridge's messages and their encoding: one UTF-8 JSON object per Zenoh sample.

JSON, because a robot-side node in any language can read and write it with its standard
library, and a step's message is a few hundred bytes (benchmarks/bridge.py measures its cost).
Angles are radians; ``stamp`` is the sender's wall clock (Unix seconds, float); ``seq`` counts
the sender's messages from 1. Keys under a prefix (default ``rnnpb/robot``):

``PREFIX/joint_commands`` (the loop → the robot)::

    {"seq": 12, "stamp": 1764779000.125, "sender": "5f1c…",
     "names": ["lshp", …], "position": [0.1, …]}

``PREFIX/joint_states`` (the robot → the loop; after every command and at least once a step)::

    {"seq": 40, "stamp": 1764779000.127, "names": ["lshp", …], "position": [0.1, …],
     "ack": 12, "target": [0.1, …], "holding": false,
     "refused": {"malformed": 0, "stale": 0}, "clipped": 0, "slowed": 0}

``ack`` is the ``seq`` of the last command applied (null before the first), ``target`` the set
point the robot applied after its safeguards, ``holding`` whether its watchdog holds the pose;
``refused``, ``clipped`` and ``slowed`` count the commands it refused or changed.

Hands from a camera node elsewhere, on any key (``--source zenoh:KEY``)::

    {"seq": 7, "stamp": 1764779000.2, "values": [0.31, 0.62, null, null]}

``values`` are ``lhy lhz rhy rhz`` in [0, 1]; null for a hand not seen.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rnnpb.errors import RnnpbError
from rnnpb.vectors import SENSORY_SIZE

DEFAULT_PREFIX = "rnnpb/robot"
JOINT_COMMANDS = "joint_commands"
JOINT_STATES = "joint_states"
MAX_MESSAGE_BYTES = 64 * 1024
"""Larger samples are refused unread: a step's message is a few hundred bytes."""


class MessageError(RnnpbError):
    """A message on the bus that is not one of the bridge's (refused and counted)."""


@dataclass(frozen=True)
class JointCommand:
    """Joint targets for one step, in the robot's names and angles (radians)."""

    seq: int
    stamp: float
    names: tuple[str, ...]
    position: np.ndarray
    sender: str = ""


@dataclass(frozen=True)
class JointState:
    """What the robot reports: its joint angles now and what it did with the commands."""

    seq: int
    stamp: float
    names: tuple[str, ...]
    position: np.ndarray
    ack: int | None = None
    target: np.ndarray | None = None
    holding: bool = False
    refused: dict[str, int] = field(default_factory=dict)
    clipped: int = 0
    slowed: int = 0


@dataclass(frozen=True)
class HandsMessage:
    """The person's hands seen by a camera node: ``lhy lhz rhy rhz``, NaN where not seen."""

    seq: int
    stamp: float
    values: np.ndarray


def encode_command(command: JointCommand) -> bytes:
    return _dump(
        {
            "seq": command.seq,
            "stamp": command.stamp,
            "sender": command.sender,
            "names": list(command.names),
            "position": [float(x) for x in command.position],
        }
    )


def encode_state(state: JointState) -> bytes:
    return _dump(
        {
            "seq": state.seq,
            "stamp": state.stamp,
            "names": list(state.names),
            "position": [float(x) for x in state.position],
            "ack": state.ack,
            "target": None if state.target is None else [float(x) for x in state.target],
            "holding": state.holding,
            "refused": dict(state.refused),
            "clipped": state.clipped,
            "slowed": state.slowed,
        }
    )


def encode_hands(hands: HandsMessage) -> bytes:
    values = [None if not math.isfinite(v) else float(v) for v in hands.values]
    return _dump({"seq": hands.seq, "stamp": hands.stamp, "values": values})


def decode_command(payload: bytes) -> JointCommand:
    """A joint command; :class:`MessageError` says what is wrong with anything else."""
    obj = _load(payload)
    names = _names(obj)
    return JointCommand(
        seq=_seq(obj),
        stamp=_stamp(obj),
        names=names,
        position=_radians(obj, "position", len(names)),
        sender=_string(obj, "sender"),
    )


def decode_state(payload: bytes) -> JointState:
    obj = _load(payload)
    names = _names(obj)
    ack = obj.get("ack")
    if ack is not None and (isinstance(ack, bool) or not isinstance(ack, int)):
        raise MessageError("ack: must be an integer or null")
    target = obj.get("target")
    refused = obj.get("refused", {})
    if not isinstance(refused, dict) or not all(
        isinstance(v, int) and not isinstance(v, bool) for v in refused.values()
    ):
        raise MessageError("refused: must map reasons to counts")
    return JointState(
        seq=_seq(obj),
        stamp=_stamp(obj),
        names=names,
        position=_radians(obj, "position", len(names)),
        ack=ack,
        target=None if target is None else _radians(obj, "target", len(names)),
        holding=bool(obj.get("holding", False)),
        refused={str(k): int(v) for k, v in refused.items()},
        clipped=_count(obj, "clipped"),
        slowed=_count(obj, "slowed"),
    )


def decode_hands(payload: bytes) -> HandsMessage:
    obj = _load(payload)
    values = obj.get("values")
    if not isinstance(values, list) or len(values) != SENSORY_SIZE:
        raise MessageError(f"values: must be a list of {SENSORY_SIZE} numbers or nulls")
    out = np.full(SENSORY_SIZE, math.nan)
    for i, v in enumerate(values):
        if v is None:
            continue
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            raise MessageError(f"values[{i}]: must be a finite number or null")
        out[i] = float(v)
    return HandsMessage(seq=_seq(obj), stamp=_stamp(obj), values=out)


def _dump(obj: dict[str, Any]) -> bytes:
    return json.dumps(obj, allow_nan=False, separators=(",", ":")).encode("utf-8")


def _load(payload: bytes) -> dict[str, Any]:
    if len(payload) > MAX_MESSAGE_BYTES:
        raise MessageError(f"{len(payload)} bytes, more than {MAX_MESSAGE_BYTES}")
    try:
        obj = json.loads(payload.decode("utf-8"))
    except (UnicodeDecodeError, ValueError) as error:
        raise MessageError(f"not UTF-8 JSON: {error}") from None
    if not isinstance(obj, dict):
        raise MessageError("not a JSON object")
    return obj


def _seq(obj: dict[str, Any]) -> int:
    seq = obj.get("seq")
    if isinstance(seq, bool) or not isinstance(seq, int) or seq < 0:
        raise MessageError("seq: must be a whole number >= 0")
    return seq


def _stamp(obj: dict[str, Any]) -> float:
    stamp = obj.get("stamp")
    if isinstance(stamp, bool) or not isinstance(stamp, int | float) or not math.isfinite(stamp):
        raise MessageError("stamp: must be a finite number of seconds")
    return float(stamp)


def _string(obj: dict[str, Any], key: str) -> str:
    value = obj.get(key, "")
    if not isinstance(value, str):
        raise MessageError(f"{key}: must be a string")
    return value


def _count(obj: dict[str, Any], key: str) -> int:
    value = obj.get(key, 0)
    if isinstance(value, bool) or not isinstance(value, int):
        raise MessageError(f"{key}: must be a whole number")
    return value


def _names(obj: dict[str, Any]) -> tuple[str, ...]:
    names = obj.get("names")
    if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
        raise MessageError("names: must be a non-empty list of joint names")
    if len(set(names)) != len(names):
        raise MessageError("names: a joint is named twice")
    return tuple(names)


def _radians(obj: dict[str, Any], key: str, size: int) -> np.ndarray:
    values = obj.get(key)
    if not isinstance(values, list) or len(values) != size:
        raise MessageError(f"{key}: must be a list of {size} numbers (one per name)")
    for v in values:
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            raise MessageError(f"{key}: must hold finite numbers of radians")
    return np.asarray(values, dtype=np.float64)
