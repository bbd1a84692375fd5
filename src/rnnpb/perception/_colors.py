"""Ball colours as HSV ranges, and the JSON colour file that holds them.

OpenCV's 8-bit HSV: hue in [0, 179] (degrees / 2), saturation and value in [0, 255]. Red sits
on both sides of hue 0, so a hue range whose low end is above its high end wraps through 0:
``[170, 8]`` means 170…179 and 0…8.

The colour file::

    {
      "format": "rnnpb-ball-colors",
      "version": 1,
      "left":  {"name": "red",  "hue": [170, 8],   "saturation": [120, 255], "value": [60, 255]},
      "right": {"name": "blue", "hue": [100, 130], "saturation": [120, 255], "value": [50, 255]}
    }

``left`` is the ball on the user's left hand (sensory ``lhy lhz``), ``right`` the one on the
user's right hand (``rhy rhz``).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb._atomic import atomic_write
from rnnpb.errors import ConfigError

COLOR_FILE_FORMAT = "rnnpb-ball-colors"
COLOR_FILE_VERSION = 1
HUE_MAX = 179
CHANNEL_MAX = 255
MAX_COLOR_FILE_BYTES = 2**20
"""Largest colour file read (1 MiB)."""


def _check_pair(value: Any, name: str, upper: int, where: str, allow_wrap: bool) -> tuple[int, int]:
    if (
        not isinstance(value, (list, tuple))
        or len(value) != 2
        or not all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) for v in value)
    ):
        raise ConfigError(
            f"{where}field {name!r}: expected [low, high] with two integers, got {value!r}"
        )
    low, high = int(value[0]), int(value[1])
    for v in (low, high):
        if not 0 <= v <= upper:
            raise ConfigError(f"{where}field {name!r}: {v} is outside 0…{upper}")
    if low > high and not allow_wrap:
        raise ConfigError(f"{where}field {name!r}: low {low} is above high {high}")
    return low, high


@dataclass(frozen=True)
class BallColor:
    """The HSV range of one ball's colour.

    Attributes
    ----------
    name : str
        A label for messages and the rendered overlay ("red", "blue", …).
    hue : (int, int)
        Hue range in [0, 179]; ``low > high`` wraps through 0 (red).
    saturation, value : (int, int)
        Saturation and value ranges in [0, 255], ``low <= high``.
    """

    name: str
    hue: tuple[int, int]
    saturation: tuple[int, int] = (120, CHANNEL_MAX)
    value: tuple[int, int] = (50, CHANNEL_MAX)
    where: str = field(default="", compare=False, repr=False)

    def __post_init__(self) -> None:
        prefix = f"{self.where}: " if self.where else ""
        if not isinstance(self.name, str) or not self.name:
            raise ConfigError(
                f"{prefix}field 'name': expected a non-empty string, got {self.name!r}"
            )
        object.__setattr__(self, "hue", _check_pair(self.hue, "hue", HUE_MAX, prefix, True))
        object.__setattr__(
            self,
            "saturation",
            _check_pair(self.saturation, "saturation", CHANNEL_MAX, prefix, False),
        )
        object.__setattr__(
            self, "value", _check_pair(self.value, "value", CHANNEL_MAX, prefix, False)
        )

    @property
    def wraps(self) -> bool:
        """Whether the hue range goes through 0 (as red's does)."""
        return self.hue[0] > self.hue[1]

    def bounds(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """``cv2.inRange`` lower/upper bounds: one pair, or two when the hue wraps."""
        s, v = self.saturation, self.value
        if not self.wraps:
            return [
                (
                    np.array([self.hue[0], s[0], v[0]], np.uint8),
                    np.array([self.hue[1], s[1], v[1]], np.uint8),
                )
            ]
        return [
            (
                np.array([self.hue[0], s[0], v[0]], np.uint8),
                np.array([HUE_MAX, s[1], v[1]], np.uint8),
            ),
            (np.array([0, s[0], v[0]], np.uint8), np.array([self.hue[1], s[1], v[1]], np.uint8)),
        ]

    def contains(self, hsv: np.ndarray) -> np.ndarray:
        """Whether HSV values, shape (..., 3), fall in this range (numpy, for checks)."""
        hsv = np.asarray(hsv)
        h, s, v = hsv[..., 0], hsv[..., 1], hsv[..., 2]
        if self.wraps:
            in_hue = (h >= self.hue[0]) | (h <= self.hue[1])
        else:
            in_hue = (h >= self.hue[0]) & (h <= self.hue[1])
        return (
            in_hue
            & (s >= self.saturation[0])
            & (s <= self.saturation[1])
            & (v >= self.value[0])
            & (v <= self.value[1])
        )

    def to_json(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "hue": list(self.hue),
            "saturation": list(self.saturation),
            "value": list(self.value),
        }


RED = BallColor("red", (170, 8), (120, CHANNEL_MAX), (60, CHANNEL_MAX))
BLUE = BallColor("blue", (100, 130), (120, CHANNEL_MAX), (50, CHANNEL_MAX))


@dataclass(frozen=True)
class BallColors:
    """The two balls' colours: ``left`` on the user's left hand, ``right`` on the right."""

    left: BallColor = RED
    right: BallColor = BLUE

    def __post_init__(self) -> None:
        for side in ("left", "right"):
            if not isinstance(getattr(self, side), BallColor):
                raise ConfigError(f"ball colours: {side!r} must be a BallColor")

    @property
    def balls(self) -> tuple[BallColor, BallColor]:
        """(left, right), in the order of the sensory vector."""
        return self.left, self.right

    def to_json(self) -> dict[str, Any]:
        return {
            "format": COLOR_FILE_FORMAT,
            "version": COLOR_FILE_VERSION,
            "left": self.left.to_json(),
            "right": self.right.to_json(),
        }


def ball_colors_from_json(data: Any, where: str = "colour config") -> BallColors:
    """Validate a parsed colour file; raises :class:`ConfigError` naming ``where`` and the field."""
    if not isinstance(data, dict):
        raise ConfigError(
            f"{where}: expected a JSON object with 'left' and 'right', got {type(data).__name__}"
        )
    if data.get("format", COLOR_FILE_FORMAT) != COLOR_FILE_FORMAT:
        raise ConfigError(
            f"{where}: field 'format': expected {COLOR_FILE_FORMAT!r}, got {data.get('format')!r}"
        )
    version = data.get("version", COLOR_FILE_VERSION)
    if version != COLOR_FILE_VERSION:
        raise ConfigError(
            f"{where}: field 'version': this rnnpb reads version "
            f"{COLOR_FILE_VERSION}, got {version!r}"
        )
    unknown = set(data) - {"format", "version", "left", "right"}
    if unknown:
        raise ConfigError(f"{where}: unknown field(s) {', '.join(sorted(unknown))}")
    sides = {}
    for side in ("left", "right"):
        entry = data.get(side)
        if not isinstance(entry, dict):
            raise ConfigError(
                f"{where}: field {side!r}: expected an object with 'hue', "
                f"'saturation' and 'value', got {entry!r}"
            )
        unknown = set(entry) - {"name", "hue", "saturation", "value"}
        if unknown:
            raise ConfigError(
                f"{where}: field {side!r}: unknown field(s) {', '.join(sorted(unknown))}"
            )
        if "hue" not in entry:
            raise ConfigError(f"{where}: field '{side}.hue' is missing")
        sides[side] = BallColor(
            name=entry.get("name", side),
            hue=entry["hue"],
            saturation=entry.get("saturation", [120, CHANNEL_MAX]),
            value=entry.get("value", [50, CHANNEL_MAX]),
            where=f"{where}: {side}",
        )
    return BallColors(sides["left"], sides["right"])


def _dotted(error: ConfigError, path: Path) -> ConfigError:
    # "PATH: left: field 'hue': …" reads better as "PATH: field 'left.hue': …".
    text = str(error)
    for side in ("left", "right"):
        text = text.replace(f"{path}: {side}: field '", f"{path}: field '{side}.")
    return ConfigError(text)


def load_ball_colors(path: str | os.PathLike[str]) -> BallColors:
    """Read and validate a colour file (format above)."""
    from rnnpb._reading import open_regular_file

    path = Path(path)
    if not path.exists() or path.is_dir():
        raise ConfigError(f"{path}: no such colour file")
    # A FIFO or a device is refused before it is opened, an endless or huge file before it is
    # read: a colour file is a few hundred bytes.
    handle = open_regular_file(
        path, ConfigError, "a colour file (JSON)", MAX_COLOR_FILE_BYTES, encoding="utf-8-sig"
    )
    try:
        # utf-8-sig: editors on Windows may start the file with a byte-order mark.
        with handle:
            text = handle.read(MAX_COLOR_FILE_BYTES + 1)
        data = None if len(text) > MAX_COLOR_FILE_BYTES else json.loads(text)
    except OSError as error:
        raise ConfigError(f"{path}: cannot read: {error.strerror or error}") from None
    # ValueError covers bad UTF-8, bad JSON and integers too long to convert; RecursionError
    # a document nested too deeply.
    except (ValueError, RecursionError) as error:
        raise ConfigError(f"{path}: not valid JSON: {error}") from None
    if len(text) > MAX_COLOR_FILE_BYTES:
        raise ConfigError(f"{path}: grew past {MAX_COLOR_FILE_BYTES:,} bytes while being read")
    try:
        return ball_colors_from_json(data, str(path))
    except ConfigError as error:
        raise _dotted(error, path) from None


def save_ball_colors(path: str | os.PathLike[str], colors: BallColors) -> None:
    """Write a colour file atomically."""
    data = colors.to_json()
    lines = [f'  "format": {json.dumps(data["format"])},', f'  "version": {data["version"]},']
    for side in ("left", "right"):
        fields = ", ".join(f"{json.dumps(k)}: {json.dumps(v)}" for k, v in data[side].items())
        lines.append(f'  "{side}": {{{fields}}}')
    with atomic_write(path, "w", encoding="utf-8") as handle:
        handle.write("{\n" + "\n".join(lines[:-1]) + ",\n" + lines[-1] + "\n}\n")
