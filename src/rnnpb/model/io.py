"""Trained models and their files.

A model file is a single ``.npz`` archive (NumPy's zip of ``.npy`` arrays, readable without
rnnpb) holding the weights, each training sequence's learned PB and initial context, the
normalization and a JSON document ``meta.json`` with the format name and version, the network
config, the pattern names, the training config and the training results. It is read with
``allow_pickle=False``: a model file cannot run code. Writes are atomic.
"""

from __future__ import annotations

import io
import json
import os
import tokenize
import zipfile
import zlib
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb import __version__
from rnnpb._atomic import atomic_write
from rnnpb.errors import ModelFileError
from rnnpb.model.network import (
    NetworkConfig,
    Params,
    param_shapes,
    params_from_numpy,
    params_to_numpy,
)

MODEL_FORMAT = "rnnpb-model"
MODEL_FORMAT_VERSION = 1


@dataclass(frozen=True)
class TrainedModel:
    """A trained RNNPB with what is needed to use it.

    Attributes
    ----------
    network : NetworkConfig
    params : Params
    lower, upper : array, shape (I,)
        Normalization of the sensory-motor vector: ``x_norm = (x - lower) / (upper - lower)``.
        Sensory values are already in [0, 1] (lower 0, upper 1); motor values are normalized by
        the robot's joint limits.
    sequence_pb : array, shape (S, P)
        The learned PB of each training sequence (the mean of its PB profile).
    sequence_patterns : tuple of str, length S
        The pattern each training sequence demonstrates.
    initial_context : array, shape (S, C)
        The learned initial context of each training sequence.
    meta : dict
        Training config, results and provenance (JSON-serializable).
    """

    network: NetworkConfig
    params: Params
    lower: np.ndarray
    upper: np.ndarray
    sequence_pb: np.ndarray
    sequence_patterns: tuple[str, ...]
    initial_context: np.ndarray
    meta: dict[str, Any] = field(default_factory=dict)

    @property
    def patterns(self) -> tuple[str, ...]:
        """Pattern names in order of first appearance."""
        return tuple(dict.fromkeys(self.sequence_patterns))

    @property
    def pattern_pb(self) -> dict[str, np.ndarray]:
        """Each pattern's PB: the mean of its sequences' learned PBs, shape (P,)."""
        names = np.asarray(self.sequence_patterns)
        return {name: self.sequence_pb[names == name].mean(axis=0) for name in self.patterns}

    def pattern_initial_context(self, pattern: str) -> np.ndarray:
        names = np.asarray(self.sequence_patterns)
        return self.initial_context[names == pattern].mean(axis=0)

    @property
    def mean_initial_context(self) -> np.ndarray:
        return self.initial_context.mean(axis=0)

    def normalize(self, x: np.ndarray) -> np.ndarray:
        """Raw sensory-motor values (..., I) → normalized (..., I)."""
        return (np.asarray(x) - self.lower) / (self.upper - self.lower)

    def denormalize(self, x: np.ndarray) -> np.ndarray:
        """Normalized sensory-motor values (..., I) → raw (..., I)."""
        return np.asarray(x) * (self.upper - self.lower) + self.lower

    def nearest_pattern(self, pb: np.ndarray) -> tuple[str, float]:
        """The learned pattern whose PB is nearest (Euclidean) to ``pb``, and the distance."""
        names = list(self.pattern_pb)
        distances = [float(np.linalg.norm(np.asarray(pb) - self.pattern_pb[n])) for n in names]
        best = int(np.argmin(distances))
        return names[best], distances[best]

    # --- files ---------------------------------------------------------------------------
    def save(self, path: str | os.PathLike[str]) -> None:
        """Write the model to ``path`` (``.npz``) atomically."""
        meta = {
            "format": MODEL_FORMAT,
            "format_version": MODEL_FORMAT_VERSION,
            "rnnpb_version": __version__,
            "network": asdict(self.network),
            "sequence_patterns": list(self.sequence_patterns),
            **{k: v for k, v in self.meta.items() if k not in ("format", "format_version")},
        }
        arrays = {f"params/{k}": v for k, v in params_to_numpy(self.params).items()}
        arrays.update(lower=np.asarray(self.lower), upper=np.asarray(self.upper),
                      sequence_pb=np.asarray(self.sequence_pb),
                      initial_context=np.asarray(self.initial_context))
        save_archive(path, meta, arrays)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> TrainedModel:
        """Read a model file; any problem raises :class:`ModelFileError` naming the file."""
        meta, arrays = load_archive(path, MODEL_FORMAT, MODEL_FORMAT_VERSION)
        path = Path(path)
        try:
            network = NetworkConfig(**meta["network"])
            patterns = tuple(str(p) for p in meta["sequence_patterns"])
        except (KeyError, TypeError, ValueError) as error:
            raise ModelFileError(f"{path}: bad network config or pattern list in meta.json "
                                 f"({error})") from None
        expected = {f"params/{k}": s for k, s in param_shapes(network).items()}
        n_seq = len(patterns)
        expected.update(lower=(network.io_size,), upper=(network.io_size,),
                        sequence_pb=(n_seq, network.pb_size),
                        initial_context=(n_seq, network.context_size))
        for name, shape in expected.items():
            if name not in arrays:
                raise ModelFileError(f"{path}: missing array {name!r}")
            if arrays[name].shape != shape:
                raise ModelFileError(f"{path}: array {name!r} has shape {arrays[name].shape}, "
                                     f"expected {shape} for the network config in the file")
            check_numeric(path, name, arrays[name])
        if np.any(arrays["upper"] <= arrays["lower"]):
            raise ModelFileError(f"{path}: normalization has upper <= lower")
        params = params_from_numpy({k[len("params/"):]: v for k, v in arrays.items()
                                    if k.startswith("params/")})
        extra = {k: v for k, v in meta.items()
                 if k not in ("format", "format_version", "network", "sequence_patterns")}
        return cls(network=network, params=params, lower=arrays["lower"].astype(np.float64),
                   upper=arrays["upper"].astype(np.float64),
                   sequence_pb=arrays["sequence_pb"].astype(np.float64),
                   sequence_patterns=patterns,
                   initial_context=arrays["initial_context"].astype(np.float64), meta=extra)


def save_archive(path: str | os.PathLike[str], meta: dict[str, Any],
                 arrays: dict[str, np.ndarray]) -> None:
    """Write ``meta`` (JSON) and ``arrays`` into one ``.npz`` file, atomically."""
    payload = dict(arrays)
    payload["meta.json"] = np.frombuffer(json.dumps(meta, indent=1).encode("utf-8"), np.uint8)
    buffer = io.BytesIO()
    np.savez(buffer, **payload)
    with atomic_write(path, "wb") as handle:
        handle.write(buffer.getvalue())


def load_archive(path: str | os.PathLike[str], fmt: str, version: int
                 ) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """Read an archive written by :func:`save_archive` and check its format and version."""
    path = Path(path)
    if not path.exists():
        raise ModelFileError(f"{path}: no such file")
    if path.is_dir():
        raise ModelFileError(f"{path}: is a directory, expected an rnnpb {fmt} file (.npz)")
    try:
        with open(path, "rb") as handle, np.load(handle, allow_pickle=False) as archive:
            arrays = {name: archive[name] for name in archive.files}
    except MemoryError:
        raise ModelFileError(f"{path}: not a readable rnnpb {fmt} file (an array in it claims "
                             "more memory than there is)") from None
    # Damage inside a zip surfaces, besides BadZipFile, as zlib.error (a compressed member),
    # NotImplementedError (a flipped compression method) or RuntimeError (a flipped
    # "encrypted" flag); all three were found by fuzzing. A damaged .npy header inside can
    # also stop NumPy's header parser with tokenize.TokenError or SyntaxError (fuzzing too).
    except (zipfile.BadZipFile, zlib.error, NotImplementedError, RuntimeError, EOFError, OSError,
            ValueError, tokenize.TokenError, SyntaxError) as error:
        raise ModelFileError(f"{path}: not a readable rnnpb {fmt} file (truncated or not an "
                             f".npz archive: {_one_line(error)})") from None
    if "meta.json" not in arrays:
        raise ModelFileError(f"{path}: not an rnnpb {fmt} file (no meta.json inside)")
    try:
        meta = json.loads(arrays.pop("meta.json").tobytes().decode("utf-8"))
    # ValueError covers bad UTF-8, bad JSON and integers too long to convert; RecursionError
    # a document nested too deeply.
    except (ValueError, RecursionError) as error:
        raise ModelFileError(f"{path}: meta.json is not valid JSON "
                             f"({_one_line(error)})") from None
    if not isinstance(meta, dict) or meta.get("format") != fmt:
        found = meta.get("format") if isinstance(meta, dict) else None
        raise ModelFileError(f"{path}: not an rnnpb {fmt} file (format is {found!r})")
    if meta.get("format_version") != version:
        raise ModelFileError(f"{path}: {fmt} format version {meta.get('format_version')!r} is "
                             f"not supported by rnnpb {__version__} (expects {version})")
    return meta, arrays


def _one_line(error: BaseException) -> str:
    text = " ".join(str(error).split())
    return text if len(text) <= 200 else text[:200] + "…"


def check_numeric(path: Path, name: str, array: np.ndarray) -> None:
    """Raise :class:`ModelFileError` unless ``array`` holds finite real numbers."""
    if array.dtype.kind not in "fiu":
        raise ModelFileError(f"{path}: array {name!r} has dtype {array.dtype}, expected real "
                             "numbers")
    if not np.all(np.isfinite(array)):
        raise ModelFileError(f"{path}: array {name!r} contains NaN or infinite values")
