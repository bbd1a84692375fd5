"""Archive files: a JSON document and arrays in one ``.npz`` file, written atomically and read
trusting nothing — model files (:mod:`rnnpb.model.io`), training checkpoints
(:mod:`rnnpb.model.training`), routine files and safety maps.

An archive is NumPy's zip of ``.npy`` arrays, readable without rnnpb, with the JSON document
stored as the bytes of a ``meta.json`` member that names the format and its version. It is read
with ``allow_pickle=False``: an archive cannot run code.

Before an array is decompressed the zip's central directory is checked: only the members the
format names (``meta.json`` and, for a model, exactly the arrays its recorded network sizes
imply), each no larger than those sizes allow, all together at most
:data:`MAX_ARCHIVE_BYTES`. Each array's own header must match the size of its member. The limits
and what they refuse are in docs/robustness.md.
"""

from __future__ import annotations

import io
import json
import math
import os
import tokenize
import zipfile
import zlib
from collections.abc import Callable
from pathlib import Path
from typing import Any, cast

import numpy as np

from rnnpb import __version__
from rnnpb._atomic import atomic_write
from rnnpb._reading import open_regular_file
from rnnpb.errors import ModelFileError

MAX_ARCHIVE_BYTES = 512 * 2**20
"""Largest total uncompressed size of a model or checkpoint archive (512 MiB)."""
MAX_META_BYTES = 16 * 2**20
"""Largest ``meta.json`` member (16 MiB)."""
MAX_MEMBERS = 4096
"""Most members an archive may hold."""
NPY_HEADER_MARGIN = 64 * 2**10
"""Room allowed for a ``.npy`` header on top of its data (NumPy's own limit is 10,000 bytes)."""
MAX_ITEM_BYTES = 8
"""Widest number an array may be stored as (float64, int64): the basis of the size bounds."""
NETWORK_DTYPE = np.float32
"""The dtype the network computes in: every stored value must be finite in it."""
_NPY_MAGIC = b"\x93NUMPY"

Members = Callable[[Path, dict[str, Any]], dict[str, tuple[int, ...] | None]]
"""A format's members from its meta.json: ``members(path, meta)`` -> name -> shape (None: any
shape)."""


def save_archive(
    path: str | os.PathLike[str], meta: dict[str, Any], arrays: dict[str, np.ndarray]
) -> None:
    """Write ``meta`` (JSON) and ``arrays`` into one ``.npz`` file, atomically."""
    payload = dict(arrays)
    payload["meta.json"] = np.frombuffer(json.dumps(meta, indent=1).encode("utf-8"), np.uint8)
    buffer = io.BytesIO()
    # NumPy's stub types the arrays' keywords with ``allow_pickle: bool`` among them.
    np.savez(buffer, **cast("dict[str, Any]", payload))
    with atomic_write(path, "wb") as handle:
        handle.write(buffer.getvalue())


def load_archive(
    path: str | os.PathLike[str],
    fmt: str,
    version: int | tuple[int, ...],
    members: Members | None = None,
) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """Read an archive written by :func:`save_archive` and check its format and version.

    The zip's central directory is checked before anything is decompressed: every member must
    be a ``.npy`` array, there are at most :data:`MAX_MEMBERS`, their uncompressed sizes add
    up to at most :data:`MAX_ARCHIVE_BYTES` and ``meta.json`` to at most
    :data:`MAX_META_BYTES`. ``version`` is the format version, or the versions, it accepts.
    Then ``members(path, meta)`` (the format's own: a model's, a training checkpoint's; None:
    whatever the archive holds) names the arrays the archive must hold, with their shapes
    where known: another member, a missing one, or one larger than its shape allows
    (:data:`MAX_ITEM_BYTES` per element plus :data:`NPY_HEADER_MARGIN`) is refused. Each
    array's header must agree with its shape and with the size of its member before its data
    is read. Any problem raises :class:`ModelFileError` naming the file.
    """
    path = Path(path)
    kind = fmt.removeprefix("rnnpb-")  # what the messages call the file: "model", "checkpoint"
    handle = open_regular_file(
        path, ModelFileError, f"an rnnpb {kind} file (.npz)", MAX_ARCHIVE_BYTES, "rb"
    )
    with handle:
        if handle.read(len(_NPY_MAGIC)) == _NPY_MAGIC:
            raise ModelFileError(
                f"{path}: is a single .npy array, not an .npz archive (an "
                f"rnnpb {kind} file is a zip of .npy arrays)"
            )
        handle.seek(0)
        try:
            with zipfile.ZipFile(handle) as archive:
                return _read_archive(path, archive, fmt, version, members)
        # Damage inside a zip surfaces, besides BadZipFile, as zlib.error (a compressed
        # member), NotImplementedError (a flipped compression method) or RuntimeError (a
        # flipped "encrypted" flag); all three were found by fuzzing. A damaged .npy header
        # inside can also stop NumPy's header parser with tokenize.TokenError or SyntaxError
        # (fuzzing too).
        except (
            zipfile.BadZipFile,
            zlib.error,
            NotImplementedError,
            RuntimeError,
            EOFError,
            OSError,
            ValueError,
            tokenize.TokenError,
            SyntaxError,
        ) as error:
            if isinstance(error, ModelFileError):
                raise
            raise ModelFileError(
                f"{path}: not a readable rnnpb {kind} file (truncated or not "
                f"an .npz archive: {one_line(error)})"
            ) from None


def _read_archive(
    path: Path,
    archive: zipfile.ZipFile,
    fmt: str,
    version: int | tuple[int, ...],
    members: Members | None,
) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    kind = fmt.removeprefix("rnnpb-")
    infos = archive.infolist()
    if len(infos) > MAX_MEMBERS:
        raise ModelFileError(
            f"{path}: holds {len(infos)} members, more than the "
            f"{MAX_MEMBERS} an rnnpb {kind} file may have"
        )
    by_name: dict[str, zipfile.ZipInfo] = {}
    for info in infos:
        if not info.filename.endswith(".npy"):
            raise ModelFileError(
                f"{path}: holds the member {shown(info.filename)}, which is not a .npy array"
            )
        key = info.filename[: -len(".npy")]
        if key in by_name:
            raise ModelFileError(f"{path}: holds the member {shown(info.filename)} twice")
        by_name[key] = info
    total = sum(info.file_size for info in infos)
    if total > MAX_ARCHIVE_BYTES:
        raise ModelFileError(
            f"{path}: its members would take {total / 2**20:.0f} MiB "
            f"uncompressed, more than the {MAX_ARCHIVE_BYTES // 2**20} MiB "
            f"an rnnpb {kind} file may hold"
        )
    meta_info = by_name.pop("meta.json", None)
    if meta_info is None:
        raise ModelFileError(f"{path}: not an rnnpb {kind} file (no meta.json inside)")
    if meta_info.file_size > MAX_META_BYTES:
        raise ModelFileError(
            f"{path}: meta.json is {meta_info.file_size / 2**20:.0f} MiB, more "
            f"than the {MAX_META_BYTES // 2**20} MiB allowed"
        )
    meta_array = _read_npy(path, archive, meta_info, None)
    if meta_array.dtype != np.uint8 or meta_array.ndim != 1:
        raise ModelFileError(
            f"{path}: meta.json is not stored as bytes ({meta_array.dtype} {meta_array.shape})"
        )
    try:
        meta = json.loads(meta_array.tobytes().decode("utf-8"))
    # ValueError covers bad UTF-8, bad JSON and integers too long to convert; RecursionError
    # a document nested too deeply.
    except (ValueError, RecursionError) as error:
        raise ModelFileError(f"{path}: meta.json is not valid JSON ({one_line(error)})") from None
    if not isinstance(meta, dict) or meta.get("format") != fmt:
        found = meta.get("format") if isinstance(meta, dict) else None
        raise ModelFileError(f"{path}: not an rnnpb {kind} file (format is {shown(found)})")
    versions = (version,) if isinstance(version, int) else tuple(version)
    found_version = meta.get("format_version")
    if isinstance(found_version, bool) or found_version not in versions:
        expected = " or ".join(str(v) for v in versions)
        raise ModelFileError(
            f"{path}: {kind} format version "
            f"{shown(found_version)} is not supported by rnnpb "
            f"{__version__} (expects {expected})"
        )
    shapes: dict[str, tuple[int, ...] | None] = (
        members(path, meta) if members is not None else dict.fromkeys(by_name)
    )
    unknown = [name for name in by_name if name not in shapes]
    if unknown:
        raise ModelFileError(
            f"{path}: holds the unexpected member(s) "
            f"{', '.join(shown(n) for n in unknown[:5])}; an rnnpb {kind} file "
            "holds only its own arrays"
        )
    for name, shape in shapes.items():
        if name not in by_name:
            raise ModelFileError(f"{path}: missing array {name!r}")
        if shape is not None:
            limit = math.prod(shape) * MAX_ITEM_BYTES + NPY_HEADER_MARGIN
            if by_name[name].file_size > limit:
                raise ModelFileError(
                    f"{path}: member {name!r} is {by_name[name].file_size:,} bytes uncompressed, "
                    f"more than an array of shape {shape} takes ({limit:,} at most); refused "
                    "before reading it"
                )
    arrays = {name: _read_npy(path, archive, by_name[name], shapes[name]) for name in shapes}
    return meta, arrays


def _read_npy(
    path: Path, archive: zipfile.ZipFile, info: zipfile.ZipInfo, shape: tuple[int, ...] | None
) -> np.ndarray:
    """One ``.npy`` member, its header checked against ``shape`` and the member's size first."""
    name = info.filename[: -len(".npy")]
    # ZipFile.open's stub says IO[bytes]; reading a member gives a ZipExtFile (readinto).
    with cast(zipfile.ZipExtFile, archive.open(info)) as member:
        if member.read(len(_NPY_MAGIC)) != _NPY_MAGIC:
            raise ModelFileError(f"{path}: member {name!r} is not a .npy array")
        member.seek(0)
        version = np.lib.format.read_magic(member)
        if version == (1, 0):
            found, fortran, dtype = np.lib.format.read_array_header_1_0(member)
        elif version == (2, 0):
            found, fortran, dtype = np.lib.format.read_array_header_2_0(member)
        else:
            raise ModelFileError(
                f"{path}: member {name!r} is a .npy file of version "
                f"{version}, which rnnpb does not read"
            )
        header_size = member.tell()
        found = tuple(int(n) for n in found)
        if dtype.hasobject:
            raise ModelFileError(
                f"{path}: array {name!r} holds Python objects ({dtype}); "
                "rnnpb files hold numbers only and are never unpickled"
            )
        if shape is not None and found != tuple(shape):
            raise ModelFileError(
                f"{path}: array {name!r} has shape {found}, expected "
                f"{tuple(shape)} for the network config in the file"
            )
        # The header alone decides what NumPy would allocate: hold it to the member's size.
        n_bytes = math.prod(found) * dtype.itemsize
        if n_bytes != info.file_size - header_size:
            raise ModelFileError(
                f"{path}: array {name!r} claims {n_bytes:,} bytes but its "
                f"member holds {info.file_size - header_size:,}"
            )
        buffer = bytearray(n_bytes)
        view, done = memoryview(buffer), 0
        while done < n_bytes:
            read = member.readinto(view[done:])
            if not read:
                raise ModelFileError(f"{path}: array {name!r} is cut short")
            done += read
    array = np.frombuffer(buffer, dtype=dtype) if dtype.itemsize else np.empty(0, dtype)
    return array.reshape(found, order="F" if fortran else "C")


def one_line(error: BaseException) -> str:
    """An error's message on one line of at most 200 characters, for a message naming a file."""
    text = " ".join(str(error).split())
    return text if len(text) <= 200 else text[:200] + "…"


def shown(value: object) -> str:
    """A value read from a file, as a message shows it: its repr, cut at 60 characters."""
    text = repr(value)
    return text if len(text) <= 60 else text[:60] + "…"


def check_numeric(
    path: Path, name: str, array: np.ndarray, dtype: type[np.floating] = NETWORK_DTYPE
) -> None:
    """Raise :class:`ModelFileError` unless ``array`` holds real numbers finite in ``dtype``.

    A value stored as float64 beyond float32's range (about 3.4e38) would become infinite in
    the network and is refused like NaN.
    """
    if array.dtype.kind not in "fiu":
        raise ModelFileError(
            f"{path}: array {name!r} has dtype {array.dtype}, expected real numbers"
        )
    if not np.all(np.isfinite(array)):
        raise ModelFileError(f"{path}: array {name!r} contains NaN or infinite values")
    with np.errstate(over="ignore", invalid="ignore"):
        cast = array.astype(dtype)
    if not np.all(np.isfinite(cast)):
        raise ModelFileError(
            f"{path}: array {name!r} has values beyond the range of "
            f"{np.dtype(dtype).name} (the network's dtype, max "
            f"{np.finfo(dtype).max:.3g})"
        )
