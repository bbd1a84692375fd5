"""The dashboard's WebSocket message protocol: what a browser may send, checked strictly.

Every client message is one JSON object in a text frame of at most :data:`MAX_MESSAGE_BYTES`
bytes with a ``type`` field; anything else is rejected with a :class:`ProtocolError` whose
text goes back to the client as ``{"type": "error", "message": ...}`` (docs/dashboard.md).
Every number is checked for its type, for being finite and for its range before anything
else touches it: JSON integers have no size limit, and a 309-digit one overflows ``float``.
"""

from __future__ import annotations

import json
import math
from typing import Any

from rnnpb.demonstrator import NEW_SHAPES, PATTERNS
from rnnpb.errors import RnnpbError

MAX_MESSAGE_BYTES = 4096
"""Longest client message accepted (the longest valid one is well under 200 bytes)."""
MIN_DT, MAX_DT = 0.02, 5.0
"""Range of the loop's step, seconds."""
MODES = ("demonstrator", "pointer", "webcam")
PERCEPTIONS = ("balls", "pose")  # as rnnpb.perception.PERCEPTIONS; the webcam's trackers
ACTIONS = ("start", "stop", "reset")
PATTERN_CHOICES = (*PATTERNS, *NEW_SHAPES, "pause")
"""What the demonstrator performs: the paper's four patterns, the new shapes, a pause."""
TEACH_MODES = ("off", "confirm", "auto")
"""Teaching in the dashboard: keep nothing; keep new movements and consolidate when the
person confirms (the default); keep and consolidate automatically."""
TEACH_ACTIONS = ("confirm", "undo")
MAX_RENAME_LENGTH = 64
"""Longest text a rename may carry (a pattern name is at most 32 characters)."""
MAX_CAMERA_INDEX = 16
GAME_MODES = ("person", "robots")
GAME_ACTIONS = ("start", "stop")
MAX_NAME_LENGTH = 200


class ProtocolError(RnnpbError):
    """A client message that is not valid; the text says what is wrong with it."""


def _shown(value: Any) -> str:
    """A client's value for an error message: short, and never an exception itself (a huge
    integer can exceed Python's limit on digits converted to text)."""
    if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 64:
        # Not repr(): decimal text of a long integer is slow, and limited (sys.int_info).
        return f"an integer of about {int(value.bit_length() * math.log10(2)) + 1} digits"
    try:
        text = repr(value)
    except ValueError:
        text = f"a {type(value).__name__}"
    return text if len(text) <= 40 else text[:37] + "..."


def _number(value: Any, name: str, low: float, high: float) -> float:
    # bool is an int in Python; a JSON true is not a number here.
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ProtocolError(f"{name} must be a number, got {type(value).__name__}")
    # The range is checked before float(): comparing an int with a float is exact in Python
    # at any size, while float() of an integer beyond 1.8e308 raises OverflowError.
    if (isinstance(value, float) and not math.isfinite(value)) or not low <= value <= high:
        raise ProtocolError(f"{name} must be in [{low:g}, {high:g}], got {_shown(value)}")
    return float(value)


def _integer(value: Any, name: str, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise ProtocolError(f"{name} must be an integer in [{low}, {high}], got {_shown(value)}")
    return value


def _keys(message: dict[str, Any], allowed: tuple[str, ...]) -> None:
    extra = sorted(set(message) - {"type", *allowed})
    if extra:
        raise ProtocolError(
            f"message {message['type']!r} has unknown field(s) "
            f"{', '.join(_shown(k) for k in extra[:5])}"
        )
    missing = [k for k in allowed if k not in message]
    if missing:
        raise ProtocolError(f"message {message['type']!r} needs field(s) {', '.join(missing)}")


def parse_client_message(text: str | bytes | None) -> dict[str, Any]:
    """Validate one client message; returns it with values normalized.

    =============================================  ===========================================
    ``{"type": "hands", "hands": [a, b, c, d]}``   pointer positions ``lhy lhz rhy rhz`` in
                                                   [0, 1]; ``null`` for a hand not placed
    ``{"type": "mode", "mode": M}``                ``demonstrator``, ``pointer`` or ``webcam``
    ``{"type": "camera", "index": N}``             webcam index 0-16 (takes effect on the
                                                   next switch to ``webcam``)
    ``{"type": "perception", "perception": P}``    the webcam's hands: ``balls`` (coloured
                                                   balls) or ``pose`` (bare hands)
    ``{"type": "pattern", "pattern": P}``          demonstrator: ``"1"``-``"4"``, a new shape
                                                   (``figure-eight`` ...) or ``"pause"``
    ``{"type": "control", "action": A}``           ``start``, ``stop`` or ``reset``
    ``{"type": "dt", "dt": S}``                    seconds per step in [0.02, 5]
    ``{"type": "model", "name": NAME}``            one of the models the server offers
    ``{"type": "ping"}``                           answered with ``pong``
    ``{"type": "teach_mode", "mode": M}``          ``off``, ``confirm`` or ``auto``
    ``{"type": "teach", "action": A}``             ``confirm`` (consolidate a kept
                                                   movement: ``"pattern": P`` names it, else
                                                   the one the panel asks about) or ``undo``
                                                   (the previous version)
    ``{"type": "rename", "pattern": P,``           call a pattern learned (or kept) by
    ``"name": N}``                                 teaching ``N``
    ``{"type": "game", "action": A, "mode": M,``   the mirror game (``/game``): ``start`` or
    ``"model": NAME}``                             ``stop``; ``person`` or ``robots``; a model
                                                   name or ``null`` (the first)
    ``{"type": "game_hands", "hands": [...]}``     the person's hands in the game, as
                                                   ``hands``
    =============================================  ===========================================
    """
    if text is None:
        raise ProtocolError("messages must be JSON text, got a binary frame")
    if isinstance(text, bytes):
        raise ProtocolError("messages must be JSON text, got a binary frame")
    size = len(text.encode("utf-8"))
    if size > MAX_MESSAGE_BYTES:
        raise ProtocolError(f"message too large: {size} bytes (at most {MAX_MESSAGE_BYTES})")
    try:
        message = json.loads(text)
    except (ValueError, RecursionError) as error:  # ValueError: also too many digits
        raise ProtocolError(f"malformed JSON: {error}") from None
    if not isinstance(message, dict):
        raise ProtocolError(f"a message must be a JSON object, got {type(message).__name__}")
    kind = message.get("type")
    if not isinstance(kind, str):
        raise ProtocolError("a message needs a string field 'type'")
    if kind == "hands":
        _keys(message, ("hands",))
        hands = message["hands"]
        if not isinstance(hands, list) or len(hands) != 4:
            raise ProtocolError("hands must be a list of 4 values (lhy lhz rhy rhz)")
        values = []
        for name, value in zip(("lhy", "lhz", "rhy", "rhz"), hands, strict=True):
            values.append(math.nan if value is None else _number(value, name, 0.0, 1.0))
        return {"type": "hands", "hands": values}
    if kind == "game_hands":
        _keys(message, ("hands",))
        return {
            **parse_client_message(json.dumps({"type": "hands", "hands": message["hands"]})),
            "type": "game_hands",
        }
    if kind == "game":
        _keys(message, ("action", "mode", "model"))
        if not isinstance(message["action"], str) or message["action"] not in GAME_ACTIONS:
            raise ProtocolError(
                f"game action must be one of {', '.join(GAME_ACTIONS)}, got "
                f"{_shown(message['action'])}"
            )
        if not isinstance(message["mode"], str) or message["mode"] not in GAME_MODES:
            raise ProtocolError(
                f"game mode must be one of {', '.join(GAME_MODES)}, got {_shown(message['mode'])}"
            )
        model = message["model"]
        if model is not None and (not isinstance(model, str) or len(model) > MAX_NAME_LENGTH):
            raise ProtocolError(f"game model must be a model name or null, got {_shown(model)}")
        return {
            "type": "game",
            "action": message["action"],
            "mode": message["mode"],
            "model": model,
        }
    if kind == "mode":
        _keys(message, ("mode",))
        if not isinstance(message["mode"], str) or message["mode"] not in MODES:
            raise ProtocolError(
                f"mode must be one of {', '.join(MODES)}, got {_shown(message['mode'])}"
            )
        return {"type": "mode", "mode": message["mode"]}
    if kind == "camera":
        _keys(message, ("index",))
        return {
            "type": "camera",
            "index": _integer(message["index"], "camera index", 0, MAX_CAMERA_INDEX),
        }
    if kind == "perception":
        _keys(message, ("perception",))
        if not isinstance(message["perception"], str) or message["perception"] not in PERCEPTIONS:
            raise ProtocolError(
                f"perception must be one of {', '.join(PERCEPTIONS)}, got "
                f"{_shown(message['perception'])}"
            )
        return {"type": "perception", "perception": message["perception"]}
    if kind == "pattern":
        _keys(message, ("pattern",))
        pattern = message["pattern"]
        if isinstance(pattern, int) and not isinstance(pattern, bool) and 0 <= pattern <= 9:
            pattern = str(pattern)
        if not isinstance(pattern, str) or pattern not in PATTERN_CHOICES:
            raise ProtocolError(
                f"pattern must be one of {', '.join(PATTERN_CHOICES)}, got "
                f"{_shown(message['pattern'])}"
            )
        return {"type": "pattern", "pattern": pattern}
    if kind == "control":
        _keys(message, ("action",))
        if not isinstance(message["action"], str) or message["action"] not in ACTIONS:
            raise ProtocolError(
                f"action must be one of {', '.join(ACTIONS)}, got {_shown(message['action'])}"
            )
        return {"type": "control", "action": message["action"]}
    if kind == "dt":
        _keys(message, ("dt",))
        return {"type": "dt", "dt": _number(message["dt"], "dt", MIN_DT, MAX_DT)}
    if kind == "model":
        _keys(message, ("name",))
        name = message["name"]
        if not isinstance(name, str) or not 0 < len(name) <= 255:
            raise ProtocolError("model name must be a non-empty string")
        return {"type": "model", "name": name}
    if kind == "teach_mode":
        _keys(message, ("mode",))
        if not isinstance(message["mode"], str) or message["mode"] not in TEACH_MODES:
            raise ProtocolError(
                f"teach_mode must be one of {', '.join(TEACH_MODES)}, got {_shown(message['mode'])}"
            )
        return {"type": "teach_mode", "mode": message["mode"]}
    if kind == "teach":
        # ``pattern`` (optional, confirm only): the kept movement the person confirms.
        named = "pattern" in message
        _keys(message, ("action", "pattern") if named else ("action",))
        if not isinstance(message["action"], str) or message["action"] not in TEACH_ACTIONS:
            raise ProtocolError(
                f"teach action must be one of {', '.join(TEACH_ACTIONS)}, got "
                f"{_shown(message['action'])}"
            )
        if not named:
            return {"type": "teach", "action": message["action"]}
        pattern = message["pattern"]
        if message["action"] != "confirm":
            raise ProtocolError("teach pattern goes with the confirm action only")
        if not isinstance(pattern, str) or not 0 < len(pattern) <= MAX_RENAME_LENGTH:
            raise ProtocolError(
                f"teach pattern must be a string of 1 to {MAX_RENAME_LENGTH} characters, "
                f"got {_shown(pattern)}"
            )
        return {"type": "teach", "action": "confirm", "pattern": pattern}
    if kind == "rename":
        _keys(message, ("pattern", "name"))
        for key in ("pattern", "name"):
            value = message[key]
            if not isinstance(value, str) or not 0 < len(value) <= MAX_RENAME_LENGTH:
                raise ProtocolError(
                    f"rename {key} must be a string of 1 to {MAX_RENAME_LENGTH} characters, "
                    f"got {_shown(value)}"
                )
        return {"type": "rename", "pattern": message["pattern"], "name": message["name"]}
    if kind == "ping":
        _keys(message, ())
        return {"type": "ping"}
    raise ProtocolError(f"unknown message type {_shown(kind)}")
