"""``recording.json``: what `rnnpb record` wrote into a data folder, and at which step time.

One file per folder, beside the sequence CSVs, with one entry per pattern recorded into it::

    {"format": "rnnpb-recording", "format_version": 1, "dt": 0.4, "framing_m": 1.5,
     "recordings": {"wave": {"source": ..., "steps": ..., "sequences": [...], ...}}}

A folder holds data of one step time and one framing (where a person's body stood in the
robot camera's view; absent or null when every recording was framed by the camera itself):
recording at another ``dt`` into it is refused, a person recorded into it is framed as the
folder is, and `rnnpb train` learns a model at the ``dt`` and framing its folders agree on.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

from rnnpb._atomic import atomic_write
from rnnpb.errors import ConfigError, DataFileError

RECORDING_FILE = "recording.json"
RECORDING_FORMAT = "rnnpb-recording"
RECORDING_FORMAT_VERSION = 1
MAX_RECORDING_BYTES = 4 * 2**20


def read_recording(folder: Path) -> dict[str, Any] | None:
    """The folder's recording.json, checked; None when there is none."""
    path = Path(folder) / RECORDING_FILE
    if not path.exists():
        return None
    from rnnpb._reading import open_regular_file

    with open_regular_file(path, DataFileError, "a JSON file", MAX_RECORDING_BYTES) as handle:
        try:
            data = json.load(handle)
        except (json.JSONDecodeError, UnicodeDecodeError) as error:
            raise DataFileError(f"{path}: not valid JSON ({str(error).splitlines()[0]})") from None
    if not isinstance(data, dict) or data.get("format") != RECORDING_FORMAT:
        raise DataFileError(f"{path}: not an rnnpb recording file")
    if data.get("format_version") != RECORDING_FORMAT_VERSION:
        raise DataFileError(
            f"{path}: recording format version {data.get('format_version')!r}; this rnnpb "
            f"reads {RECORDING_FORMAT_VERSION}"
        )
    dt = data.get("dt")
    if not isinstance(dt, (int, float)) or isinstance(dt, bool) or not math.isfinite(dt) or dt <= 0:
        raise DataFileError(f"{path}: 'dt' is not a positive number of seconds")
    if not isinstance(data.get("recordings"), dict):
        raise DataFileError(f"{path}: 'recordings' is not an object")
    framing = data.get("framing_m")
    if framing is not None and (
        not isinstance(framing, (int, float))
        or isinstance(framing, bool)
        or not math.isfinite(framing)
        or not 0.5 <= framing <= 3.0
    ):
        raise DataFileError(f"{path}: 'framing_m' is not a distance from 0.5 to 3 m")
    return data


def write_recording(
    folder: Path, pattern: str, dt: float, entry: dict[str, Any], framing: float | None = None
) -> Path:
    """Add (or replace) ``pattern``'s entry in the folder's recording.json, atomically;
    ``framing`` (metres) is the folder's framing once a person's body was framed into it."""
    folder = Path(folder)
    data = read_recording(folder) or {
        "format": RECORDING_FORMAT,
        "format_version": RECORDING_FORMAT_VERSION,
        "dt": dt,
        "recordings": {},
    }
    check_folder_dt(folder, dt, data)
    if framing is not None:
        held = data.get("framing_m")
        if held is not None and not math.isclose(held, framing, rel_tol=1e-9):
            raise ConfigError(
                f"{folder / RECORDING_FILE}: the folder is framed at {held:g} m, not {framing:g} m"
            )
        data["framing_m"] = framing
    data["recordings"][pattern] = entry
    path = folder / RECORDING_FILE
    with atomic_write(path, encoding="utf-8") as handle:
        json.dump(data, handle, indent=1)
        handle.write("\n")
    return path


def check_folder_dt(folder: Path, dt: float, data: dict[str, Any] | None = None) -> None:
    """Refuse recording at ``dt`` into a folder that holds data of another step time."""
    data = data if data is not None else read_recording(folder)
    if data is not None and not math.isclose(data["dt"], dt, rel_tol=1e-9):
        raise ConfigError(
            f"{Path(folder) / RECORDING_FILE}: the folder holds data recorded at dt "
            f"{data['dt']:g} s; record at --dt {data['dt']:g} or into another --out folder"
        )


def _agreed(
    paths: list[str], value_of: Callable[[Path], float | None], disagree: Callable[..., str]
) -> tuple[float, list[Path]] | None:
    """The value the data folders' recording.json files agree on (``value_of(folder)``, None
    where a folder gives none), and those files; None when none gives one. A data file's
    folder is its parent. Disagreeing files raise :class:`ConfigError` with
    ``disagree(first, value, other, other_value)``."""
    folders = dict.fromkeys(Path(p) if Path(p).is_dir() else Path(p).parent for p in paths)
    found = [
        (float(value), folder / RECORDING_FILE)
        for folder in folders
        if (value := value_of(folder)) is not None
    ]
    if not found:
        return None
    value, first = found[0]
    for other_value, other in found[1:]:
        if not math.isclose(other_value, value, rel_tol=1e-9):
            raise ConfigError(disagree(first, value, other, other_value))
    return value, [path for _, path in found]


def data_dt(paths: list[str]) -> tuple[float, list[Path]] | None:
    """The step time the data folders' recording.json files agree on, and those files; None
    when none has one. Disagreeing files raise :class:`ConfigError` naming two of them."""

    def dt_of(folder: Path) -> float | None:
        data = read_recording(folder)
        return None if data is None else data["dt"]

    return _agreed(
        paths,
        dt_of,
        lambda first, dt, other, other_dt: (
            f"the data were recorded at different step times ({first}: dt {dt:g} s, "
            f"{other}: dt {other_dt:g} s); a model learns at one dt: record them again "
            "at one --dt"
        ),
    )


def folder_framing(folder: Path) -> float | None:
    """The framing (metres) a folder's recordings of a person's body share, None when it has
    none (no recording.json, or only camera-framed data)."""
    data = read_recording(folder) if Path(folder).is_dir() else None
    return None if data is None else data.get("framing_m")


def data_framing(paths: list[str]) -> tuple[float, list[Path]] | None:
    """The framing the data folders agree on, and the recording files that give it; None when
    none gives one. Folders framed differently raise :class:`ConfigError` naming two."""
    return _agreed(
        paths,
        folder_framing,
        lambda first, framing, other, other_framing: (
            f"the data frame the person differently ({first}: {framing:g} m, {other}: "
            f"{other_framing:g} m); a model learns one framing: record them into one folder, "
            f"or again with --framing {max(framing, other_framing):g}"
        ),
    )
