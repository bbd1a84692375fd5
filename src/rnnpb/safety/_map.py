"""The safety map: the meta-level learned for one model, stored beside it.

A model ``M.npz`` has its map in ``M.safety.npz`` (a file of its own, so the model file and its
format stay as they are; ``rnnpb safety learn --model M.npz`` writes it). The map holds the
risk network's weights, the experienced PBs (for familiarity: a kernel density over them),
their labels, the labels' counts, the
checks' settings, the model's fingerprint (a map learned for another model is refused) and a
format version. A missing map is not an error where a caller chooses the documented fallback
(:func:`find_safety_map` returns None: the command filter still runs, the PB is not guarded);
a damaged one always is.
"""

from __future__ import annotations

import datetime
import hashlib
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import jax
import numpy as np

from rnnpb.errors import ModelFileError
from rnnpb.model import TrainedModel
from rnnpb.model.archive import check_numeric, load_archive, save_archive
from rnnpb.model.meta import MetaParams
from rnnpb.safety._meta import familiarity, risk

SAFETY_FORMAT = "rnnpb-safety-map"
SAFETY_FORMAT_VERSION = 2
"""2: PBs labelled by their own generation after its transient, from many starts (and the
familiarity a kernel density); a version-1 map (labelled by any unsafe step from one start) is
refused: it must be learned again."""


def safety_map_path(model_path: str | os.PathLike[str]) -> Path:
    """Where the map of the model at ``model_path`` lives: ``M.npz`` → ``M.safety.npz``."""
    path = Path(model_path)
    return path.with_name(path.name.removesuffix(".npz") + ".safety.npz")


def model_fingerprint(model: TrainedModel) -> str:
    """A short hash of the model's weights and normalization: which model a map belongs to."""
    digest = hashlib.sha256()
    for leaf in jax.tree_util.tree_leaves(model.params):
        digest.update(np.asarray(leaf, dtype=np.float32).tobytes())
    digest.update(np.asarray(model.lower, np.float64).tobytes())
    digest.update(np.asarray(model.upper, np.float64).tobytes())
    return digest.hexdigest()[:16]


@dataclass(frozen=True)
class SafetyMap:
    """The meta-level of one model.

    ``meta``: the risk network; ``experienced`` (N, P) the PBs whose behaviour was generated
    or visited; ``unsafe`` (N,) their labels; ``familiarity_width``; ``fingerprint`` of the
    model; ``info``: how it was learned (settings, counts, when).
    """

    meta: MetaParams
    experienced: np.ndarray
    unsafe: np.ndarray
    familiarity_width: float
    fingerprint: str
    info: dict[str, Any] = field(default_factory=dict)

    def risk(self, pb: np.ndarray) -> np.ndarray:
        """Learned risk of PBs (..., P), in [0, 1]."""
        return risk(self.meta, pb)

    def familiarity(self, pb: np.ndarray) -> np.ndarray:
        """Familiarity of PBs (..., P), in [0, 1]."""
        return familiarity(self.experienced, pb, self.familiarity_width)

    def check_model(self, model: TrainedModel, path: Path | str = "safety map") -> None:
        """Refuse a map that was learned for another model."""
        found = model_fingerprint(model)
        if found != self.fingerprint:
            raise ModelFileError(
                f"{path}: this safety map was learned for another model "
                f"(fingerprint {self.fingerprint}, the model's is {found}); "
                "run `rnnpb safety learn` for it"
            )

    def save(self, path: str | os.PathLike[str]) -> None:
        meta = {
            "format": SAFETY_FORMAT,
            "format_version": SAFETY_FORMAT_VERSION,
            "fingerprint": self.fingerprint,
            "familiarity_width": self.familiarity_width,
            "info": self.info,
        }
        arrays = {
            f"meta_{name}": np.asarray(value, np.float64)
            for name, value in self.meta._asdict().items()
        }
        arrays["experienced"] = np.asarray(self.experienced, np.float64)
        arrays["unsafe"] = np.asarray(self.unsafe, np.uint8)
        save_archive(path, meta, arrays)


def load_safety_map(path: str | os.PathLike[str], model: TrainedModel | None = None) -> SafetyMap:
    """Read a safety map; with ``model``, also check it belongs to that model. Raises
    :class:`ModelFileError` naming the file for a missing, damaged, foreign or newer map."""
    path = Path(path)
    meta, arrays = load_archive(path, SAFETY_FORMAT, (1, SAFETY_FORMAT_VERSION))
    if meta.get("format_version") != SAFETY_FORMAT_VERSION:
        raise ModelFileError(
            f"{path}: a version-{meta.get('format_version')} safety map (its PBs labelled by "
            "any unsafe step from one start); run `rnnpb safety learn` to learn it again"
        )
    names = [f"meta_{name}" for name in MetaParams._fields] + ["experienced", "unsafe"]
    missing = [n for n in names if n not in arrays]
    if missing:
        raise ModelFileError(f"{path}: safety map lacks array(s) {', '.join(missing)}")
    for name in names:
        check_numeric(path, name, arrays[name])
    params = MetaParams(*(arrays[f"meta_{n}"].astype(np.float64) for n in MetaParams._fields))
    experienced = arrays["experienced"].astype(np.float64)
    p = params.w1.shape[0] if params.w1.ndim == 2 else -1
    h = params.w1.shape[1] if params.w1.ndim == 2 else -1
    shapes_ok = (
        params.b1.shape == (h,)
        and params.w2.shape == (h, h)
        and params.b2.shape == (h,)
        and params.w3.shape == (h,)
        and params.b3.shape == ()
        and experienced.ndim == 2
        and experienced.shape[1] == p
        and arrays["unsafe"].shape == (len(experienced),)
    )
    if not shapes_ok:
        raise ModelFileError(f"{path}: safety map arrays have inconsistent shapes")
    try:
        width = float(meta["familiarity_width"])
        fingerprint = str(meta["fingerprint"])
    except (KeyError, TypeError, ValueError):
        raise ModelFileError(
            f"{path}: safety map meta.json lacks familiarity_width or fingerprint"
        ) from None
    if not width > 0:
        raise ModelFileError(f"{path}: familiarity_width must be > 0, got {width}")
    result = SafetyMap(
        params,
        experienced,
        arrays["unsafe"].astype(bool),
        width,
        fingerprint,
        meta.get("info") if isinstance(meta.get("info"), dict) else {},
    )
    if model is not None:
        if p != model.network.pb_size:
            raise ModelFileError(
                f"{path}: safety map is for {p} PB units, the model has {model.network.pb_size}"
            )
        result.check_model(model, path)
    return result


def find_safety_map(
    model_path: str | os.PathLike[str], model: TrainedModel | None = None
) -> SafetyMap | None:
    """The map beside the model at ``model_path``, or None when there is none (the fallback:
    the filter alone guards the robot). A map that is there but damaged or foreign raises."""
    path = safety_map_path(model_path)
    return load_safety_map(path, model) if path.exists() else None


def describe_safety_map(path: str | os.PathLike[str]) -> str:
    """One or two lines on the stored map at ``path`` (for ``rnnpb info``); a missing or
    damaged map is described, not raised."""
    path = Path(path)
    if not path.exists():
        return f"safety map: none ({path.name} missing; the command filter alone guards)"
    try:
        stored = load_safety_map(path)
    except ModelFileError as error:
        return f"safety map: unusable — {error}"
    n = len(stored.experienced)
    unsafe = int(stored.unsafe.sum())
    info = stored.info
    return (
        f"safety map (version {SAFETY_FORMAT_VERSION}): {n} experienced PBs, {unsafe} unsafe "
        f"({100 * unsafe / max(n, 1):.0f} %), learned {info.get('created', '?')}\n"
        f"  risk network {stored.meta.w1.shape[1]} hidden units; servo limit "
        f"{info.get('step_limit_rad', float('nan')):.2f} rad/step; model {stored.fingerprint}"
    )


def new_map(
    model: TrainedModel,
    meta: MetaParams,
    experienced: np.ndarray,
    unsafe: np.ndarray,
    width: float,
    info: dict[str, Any],
) -> SafetyMap:
    info = {"created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"), **info}
    return SafetyMap(meta, experienced, unsafe, width, model_fingerprint(model), info)
