"""Trained models and their files.

A model file is a single ``.npz`` archive (:mod:`rnnpb.model.archive`: NumPy's zip of ``.npy``
arrays, readable without rnnpb) holding the weights, each training sequence's learned PB and
initial context, the normalization and a JSON document ``meta.json`` with the format name and
version, the network config, the pattern names, the training config, the training results
and the model's history (:class:`HistoryEntry`: which patterns were learned when, by which
method, from which model). It is read with ``allow_pickle=False``: a model file cannot run
code. Writes are atomic.

Format 2 added the history; a file of format 1 still loads, with the history its training
record implies (one ``train`` entry, time unknown). Format 3 added the hands as taught
(``taught_sensory``, what recognition matches against); a file of format 1 or 2 loads without
them.

A model records the step time it was learned at (``meta["dt"]``, seconds; it plays at that step
only); a file without it was learned at the paper's 0.4 s (:data:`DEFAULT_DT`). It also records
where a person's body was framed in the robot camera's view when it learned
(``meta["framing_m"]``, metres: :mod:`rnnpb.learning_phase`); a person it watches is framed
alike; a file without it learned at the standard user's place, :data:`DEFAULT_FRAMING`.

Reading trusts nothing in the file. The archive is checked before an array is decompressed
(:func:`rnnpb.model.archive.load_archive`), against exactly the arrays the model's recorded
network sizes imply; then every value and the history. The limits and what they refuse are in
docs/robustness.md.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb import __version__
from rnnpb.errors import ModelFileError
from rnnpb.model.archive import check_numeric, load_archive, one_line, save_archive, shown
from rnnpb.model.network import (
    NetworkConfig,
    Params,
    param_shapes,
    params_from_numpy,
    params_to_numpy,
)
from rnnpb.presets import PRESET_NAMES
from rnnpb.sequences import pattern_name_problem
from rnnpb.vectors import MOTOR_NAMES

MODEL_FORMAT = "rnnpb-model"
MODEL_FORMAT_VERSION = 3
READABLE_MODEL_FORMAT_VERSIONS = (1, 2, 3)
"""Format versions :meth:`TrainedModel.load` reads (1: before the history was recorded; 2:
before the hands as taught were kept)."""
MAX_TAUGHT_STEPS = 100_000
"""Most steps of taught hands a model file may hold per sequence."""
HISTORY_METHODS = ("train", "rehearsal", "finetune", "replay", "scratch")
"""How a model's patterns were learned: a first training, or a consolidation method
(:mod:`rnnpb.model.consolidation`)."""
MAX_HISTORY = 1000
"""Most history entries a model file may hold."""

JOINT_LIMIT_TOLERANCE = 1e-9
"""Radians a motor normalization bound may lie outside the robot's joint limit (rounding)."""
DEFAULT_DT = 0.4
"""Seconds per step of a model that records none: the paper's step, all older files' step."""
MAX_DT = 60.0
DEFAULT_FRAMING = 1.0
"""Metres: the framing of a model that records none, the standard user's place
(:class:`rnnpb.demonstrator.UserBody`'s distance, where the demonstrator stands)."""


@dataclass(frozen=True)
class HistoryEntry:
    """One step of a model's life: its first training, or one consolidation.

    Attributes
    ----------
    method : str
        One of :data:`HISTORY_METHODS`.
    added : tuple of str
        The patterns this step learned anew (a first training: all of them).
    patterns : tuple of str
        The model's patterns after this step.
    parent, parent_fingerprint : str or None
        The file name and :attr:`TrainedModel.fingerprint` of the model this step started from
        (None for a first training).
    train_config : dict
        The :class:`~rnnpb.model.TrainConfig` of this step, as a dict.
    data_fingerprint : str or None
        :attr:`~rnnpb.model.learning.TrainingData.fingerprint` of what this step learned on
        (for rehearsal: the rehearsed and the new sequences).
    added_data_fingerprint : str or None
        The same of the real sequences of the ``added`` patterns alone, in the order given: what
        a later replay compares its data with.
    iterations : int
    seconds : float
    created : str or None
        When the step ended, UTC, ISO 8601; None where not recorded (a file of format 1).
    details : dict
        What the method adds (replay: whether the replayed data matched the record).
    """

    method: str
    added: tuple[str, ...]
    patterns: tuple[str, ...]
    parent: str | None = None
    parent_fingerprint: str | None = None
    train_config: dict[str, Any] = field(default_factory=dict)
    data_fingerprint: str | None = None
    added_data_fingerprint: str | None = None
    iterations: int = 0
    seconds: float = 0.0
    created: str | None = None
    details: dict[str, Any] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        out = asdict(self)
        out["added"], out["patterns"] = list(self.added), list(self.patterns)
        return out

    @classmethod
    def from_json(cls, path: Path | str, data: object) -> HistoryEntry:
        """An entry of a model file's meta.json, checked; :class:`ModelFileError` otherwise."""
        if not isinstance(data, dict):
            raise ModelFileError(f"{path}: a history entry is {type(data).__name__}, not an object")
        known = {f for f in cls.__dataclass_fields__}
        unknown = sorted(set(data) - known)
        if unknown:
            raise ModelFileError(
                f"{path}: a history entry has unknown field(s) "
                f"{', '.join(shown(k) for k in unknown[:5])}"
            )
        method = data.get("method")
        if method not in HISTORY_METHODS:
            raise ModelFileError(
                f"{path}: history method {shown(method)} is not one of {', '.join(HISTORY_METHODS)}"
            )
        names: dict[str, tuple[str, ...]] = {}
        for key in ("added", "patterns"):
            value = data.get(key)
            if not isinstance(value, list):
                raise ModelFileError(f"{path}: history field {key!r} is not a list")
            for name in value:
                problem = pattern_name_problem(name)
                if problem:
                    raise ModelFileError(f"{path}: history pattern name {shown(name)} {problem}")
            names[key] = tuple(value)
        kinds = {
            "parent": str,
            "parent_fingerprint": str,
            "data_fingerprint": str,
            "added_data_fingerprint": str,
            "created": str,
        }
        for key, kind in kinds.items():
            value = data.get(key)
            if value is not None and (not isinstance(value, kind) or len(value) > 4096):
                raise ModelFileError(f"{path}: history field {key!r} is not a short text")
        for key in ("train_config", "details"):
            if not isinstance(data.get(key, {}), dict):
                raise ModelFileError(f"{path}: history field {key!r} is not an object")
        iterations, seconds = data.get("iterations", 0), data.get("seconds", 0.0)
        if not isinstance(iterations, int) or isinstance(iterations, bool) or iterations < 0:
            raise ModelFileError(f"{path}: history field 'iterations' is {shown(iterations)}")
        if (
            not isinstance(seconds, (int, float))
            or isinstance(seconds, bool)
            or not (math.isfinite(seconds) and seconds >= 0)
        ):
            raise ModelFileError(f"{path}: history field 'seconds' is {shown(seconds)}")
        return cls(**{**data, **names, "seconds": float(seconds)})


def first_training_entry(meta: dict[str, Any], patterns: tuple[str, ...]) -> HistoryEntry:
    """The history a model has without a recorded one: its first training, as its training
    record says (a model just trained, or a file of format 1)."""
    training = meta.get("training")
    training = training if isinstance(training, dict) else {}
    config = meta.get("train_config")
    config = config if isinstance(config, dict) else {}
    iterations = training.get("iterations", 0)
    seconds = training.get("seconds", 0.0)
    fingerprint = training.get("data_fingerprint")
    return HistoryEntry(
        method="train",
        added=patterns,
        patterns=patterns,
        train_config=dict(config),
        data_fingerprint=fingerprint if isinstance(fingerprint, str) else None,
        added_data_fingerprint=fingerprint if isinstance(fingerprint, str) else None,
        iterations=iterations if isinstance(iterations, int) else 0,
        seconds=float(seconds) if isinstance(seconds, (int, float)) else 0.0,
    )


def model_dt(meta: dict[str, Any]) -> float:
    """The step time a model was learned at, seconds: ``meta["dt"]``, or :data:`DEFAULT_DT`
    for a file from before models recorded it."""
    dt = meta.get("dt")
    return DEFAULT_DT if dt is None else float(dt)


def model_framing(meta: dict[str, Any]) -> float:
    """Metres from the robot at which a person's body was framed when the model learned:
    ``meta["framing_m"]``, or :data:`DEFAULT_FRAMING` (the standard user's place, where the
    demonstrator stands) for a model that records none."""
    framing = meta.get("framing_m")
    return DEFAULT_FRAMING if framing is None else float(framing)


def framing_problem(framing: object) -> str | None:
    """Why ``framing`` is no framing (metres in [0.5, 3]), or None."""
    if isinstance(framing, bool) or not isinstance(framing, (int, float)):
        return f"is {type(framing).__name__}, not a distance in metres"
    if not math.isfinite(framing) or not 0.5 <= framing <= 3.0:
        return f"{framing!r} is not a distance from 0.5 to 3 m"
    return None


def dt_problem(dt: object) -> str | None:
    """Why ``dt`` is no model step time (a number of seconds in (0, :data:`MAX_DT`]), or
    None."""
    if isinstance(dt, bool) or not isinstance(dt, (int, float)):
        return f"is {type(dt).__name__}, not a number of seconds"
    if not math.isfinite(dt) or not 0 < dt <= MAX_DT:
        return f"{dt!r} is not a number of seconds in (0, {MAX_DT:g}]"
    return None


def learning_preset(meta: dict[str, Any]) -> tuple[str, int | None] | None:
    """The learning preset a model's meta.json records, and its version: ``meta["preset"]``
    (``{"name": ..., "version": ...}``, written since presets were recorded), else the preset
    the recorded learning's optimizer implies (Adam: ``fast``, else ``paper``; version None).
    None when the model records no learning. Never raises: the file is not trusted."""
    recorded = meta.get("preset")
    if isinstance(recorded, dict) and recorded.get("name") in PRESET_NAMES:
        version = recorded.get("version")
        valid = isinstance(version, int) and not isinstance(version, bool)
        return str(recorded["name"]), version if valid else None
    config = meta.get("train_config")
    if not isinstance(config, dict):
        return None
    return ("fast" if config.get("optimizer") == "adam" else "paper"), None


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
        Training config, results and provenance (JSON-serializable); ``meta["history"]``, a
        list of :meth:`HistoryEntry.to_json`, once the model has been consolidated or saved.
    taught_sensory : array, shape (S, T, 4), or None
        Each training sequence's hands as taught, normalized, NaN after a shorter sequence's
        end: what on-line recognition matches what it sees against
        (:func:`rnnpb.model.recognition.taught_stretches`). A rehearsed pattern keeps the
        hands it was first taught with. None for a model saved before they were kept (format
        1 or 2): recognition then goes by the network's evidence alone.
    """

    network: NetworkConfig
    params: Params
    lower: np.ndarray
    upper: np.ndarray
    sequence_pb: np.ndarray
    sequence_patterns: tuple[str, ...]
    initial_context: np.ndarray
    meta: dict[str, Any] = field(default_factory=dict)
    taught_sensory: np.ndarray | None = None

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
    def taught_hands(self) -> dict[str, list[np.ndarray]] | None:
        """Each pattern's taught sequences' hands, each (T_i, 4) normalized without the
        padding; None when the model has none."""
        if self.taught_sensory is None:
            return None
        out: dict[str, list[np.ndarray]] = {name: [] for name in self.patterns}
        for name, hands in zip(self.sequence_patterns, self.taught_sensory, strict=True):
            out[name].append(hands[~np.isnan(hands).any(axis=1)])
        return out

    @property
    def learning_preset(self) -> tuple[str, int | None] | None:
        """The learning preset the model was learned with and its version
        (:func:`learning_preset`)."""
        return learning_preset(self.meta)

    @property
    def dt(self) -> float:
        """Seconds per step the model was learned at, and plays at (:func:`model_dt`)."""
        return model_dt(self.meta)

    @property
    def framing(self) -> float:
        """Metres at which a person's body is framed for this model (:func:`model_framing`)."""
        return model_framing(self.meta)

    @property
    def mean_initial_context(self) -> np.ndarray:
        return self.initial_context.mean(axis=0)

    @property
    def history(self) -> tuple[HistoryEntry, ...]:
        """Which patterns were learned when, by which method, from which model (oldest first).

        A model without a recorded history (just trained, or read from a file of format 1) has
        one entry: its first training.
        """
        recorded = self.meta.get("history")
        if recorded is None:
            return (first_training_entry(self.meta, self.patterns),)
        return tuple(HistoryEntry.from_json("model", entry) for entry in recorded)

    def with_history(self, history: tuple[HistoryEntry, ...]) -> TrainedModel:
        """This model with ``history`` (oldest first) as its recorded history."""
        import dataclasses

        meta = {**self.meta, "history": [entry.to_json() for entry in history]}
        return dataclasses.replace(self, meta=meta)

    def renamed(self, pattern: str, name: str) -> TrainedModel:
        """This model with its pattern ``pattern`` called ``name``: the sequences' names and
        the history's last entry (its ``added`` and ``patterns``; ``details["renamed"]``
        records ``{"from", "to", "created"}``), so the file says what the pattern was learned
        as.

        Raises :class:`ConfigError` for a pattern the model does not hold, a name that is not
        a pattern name, or one the model already holds.
        """
        import dataclasses
        import datetime

        from rnnpb.errors import ConfigError

        if pattern not in self.patterns:
            raise ConfigError(f"the model has no pattern {pattern!r}")
        problem = pattern_name_problem(name)
        if problem:
            raise ConfigError(f"pattern name {name!r} {problem}")
        if name in self.patterns:
            raise ConfigError(f"the model already has a pattern {name!r}")

        def renamed(names: tuple[str, ...]) -> tuple[str, ...]:
            return tuple(name if n == pattern else n for n in names)

        *older, last = self.history
        record = {
            "from": pattern,
            "to": name,
            "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        }
        last = dataclasses.replace(
            last,
            added=renamed(last.added),
            patterns=renamed(last.patterns),
            details={**last.details, "renamed": [*last.details.get("renamed", []), record]},
        )
        model = dataclasses.replace(self, sequence_patterns=renamed(self.sequence_patterns))
        return model.with_history((*older, last))

    @property
    def fingerprint(self) -> str:
        """SHA-256 of what the model computes with: network sizes, weights, PBs, initial
        contexts, normalization and pattern names (not its meta.json, so the same model saved
        twice has the same fingerprint)."""
        digest = hashlib.sha256(json.dumps(asdict(self.network), sort_keys=True).encode())
        for name, value in sorted(params_to_numpy(self.params).items()):
            digest.update(name.encode())
            digest.update(np.ascontiguousarray(value, dtype=np.float32).tobytes())
        for array in (self.lower, self.upper, self.sequence_pb, self.initial_context):
            digest.update(np.ascontiguousarray(array, dtype=np.float64).tobytes())
        digest.update("\n".join(self.sequence_patterns).encode())
        if self.taught_sensory is not None:  # a model without them keeps its fingerprint
            digest.update(b"taught_sensory")
            digest.update(np.ascontiguousarray(self.taught_sensory, dtype=np.float64).tobytes())
        return digest.hexdigest()

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
            **{
                k: v
                for k, v in self.meta.items()
                if k not in ("format", "format_version", "taught_steps")
            },
            "history": [entry.to_json() for entry in self.history],
        }
        if self.taught_sensory is not None:
            meta["taught_steps"] = int(self.taught_sensory.shape[1])
        arrays = {f"params/{k}": v for k, v in params_to_numpy(self.params).items()}
        arrays.update(
            lower=np.asarray(self.lower),
            upper=np.asarray(self.upper),
            sequence_pb=np.asarray(self.sequence_pb),
            initial_context=np.asarray(self.initial_context),
        )
        if self.taught_sensory is not None:
            arrays["taught_sensory"] = np.asarray(self.taught_sensory)
        save_archive(path, meta, arrays)

    @classmethod
    def load(
        cls, path: str | os.PathLike[str], joint_limits: np.ndarray | None = None
    ) -> TrainedModel:
        """Read a model file; any problem raises :class:`ModelFileError` naming the file.

        Parameters
        ----------
        path : path of the ``.npz`` file
        joint_limits : array, shape (M, 2), optional
            The robot's joint limits (radians). Given, the model is refused unless its motor
            normalization lies within them (see :func:`check_joint_limits`); every command or
            loader that pairs a model with a robot passes them.
        """
        path = Path(path)
        meta, arrays = load_archive(
            path, MODEL_FORMAT, READABLE_MODEL_FORMAT_VERSIONS, _model_members
        )
        network, patterns, expected = _model_layout(path, meta)
        history = _checked_history(path, meta)
        if "dt" in meta and (problem := dt_problem(meta["dt"])):
            raise ModelFileError(f"{path}: meta.json's step time dt {problem}")
        if meta.get("framing_m") is not None and (problem := framing_problem(meta["framing_m"])):
            raise ModelFileError(f"{path}: meta.json's framing_m {problem}")
        for name in expected:
            if name != "taught_sensory":
                check_numeric(path, name, arrays[name])
        taught = arrays.get("taught_sensory")
        if taught is not None:
            # Hands in [0, 1], NaN only as the padding after a sequence's end.
            check_numeric(path, "taught_sensory", np.where(np.isnan(taught), 0.0, taught))
            rows: np.ndarray = np.asarray(np.isnan(taught).any(axis=2), dtype=bool)
            if (
                np.any(np.isnan(taught) != rows[..., None])
                or np.any(rows[:, 1:] < rows[:, :-1])
                or np.any((taught < 0) | (taught > 1))
            ):
                raise ModelFileError(
                    f"{path}: array 'taught_sensory' is not hands in [0, 1] padded with NaN "
                    "after each sequence's end"
                )
        if np.any(arrays["upper"] <= arrays["lower"]):
            raise ModelFileError(f"{path}: normalization has upper <= lower")
        for name in ("sequence_pb", "initial_context"):
            # Both are sigmoid outputs; anything outside [0, 1] was not written by training.
            if np.any((arrays[name] < 0) | (arrays[name] > 1)):
                raise ModelFileError(f"{path}: array {name!r} has values outside [0, 1]")
        params = params_from_numpy(
            {k[len("params/") :]: v for k, v in arrays.items() if k.startswith("params/")}
        )
        extra = {
            k: v
            for k, v in meta.items()
            if k
            not in (
                "format",
                "format_version",
                "network",
                "sequence_patterns",
                "history",
                "taught_steps",
            )
        }
        if history is not None:
            extra["history"] = [entry.to_json() for entry in history]
        model = cls(
            network=network,
            params=params,
            lower=arrays["lower"].astype(np.float64),
            upper=arrays["upper"].astype(np.float64),
            sequence_pb=arrays["sequence_pb"].astype(np.float64),
            sequence_patterns=patterns,
            initial_context=arrays["initial_context"].astype(np.float64),
            meta=extra,
            taught_sensory=None if taught is None else taught.astype(np.float64),
        )
        if joint_limits is not None:
            check_joint_limits(model, joint_limits, str(path))
        return model


def _model_layout(
    path: Path, meta: dict[str, Any]
) -> tuple[NetworkConfig, tuple[str, ...], dict[str, tuple[int, ...]]]:
    """The network, the pattern names and every array's shape a model's meta.json implies."""
    try:
        network = NetworkConfig(**meta["network"])
        patterns = meta["sequence_patterns"]
        if not isinstance(patterns, list):
            raise TypeError(f"sequence_patterns is {type(patterns).__name__}, not a list")
    except (KeyError, TypeError, ValueError) as error:
        raise ModelFileError(
            f"{path}: bad network config or pattern list in meta.json ({one_line(error)})"
        ) from None
    if not patterns:
        raise ModelFileError(
            f"{path}: holds no training sequences (its pattern list is empty); "
            "a model needs at least one learned pattern"
        )
    for name in patterns:
        problem = pattern_name_problem(name)
        if problem:
            text = repr(name) if len(repr(name)) <= 40 else repr(name)[:40] + "…"
            raise ModelFileError(f"{path}: pattern name {text} {problem}")
    shapes = {f"params/{k}": s for k, s in param_shapes(network).items()}
    n_seq = len(patterns)
    shapes.update(
        lower=(network.io_size,),
        upper=(network.io_size,),
        sequence_pb=(n_seq, network.pb_size),
        initial_context=(n_seq, network.context_size),
    )
    taught_steps = meta.get("taught_steps")
    if taught_steps is not None:
        if (
            not isinstance(taught_steps, int)
            or isinstance(taught_steps, bool)
            or not 1 <= taught_steps <= MAX_TAUGHT_STEPS
        ):
            raise ModelFileError(
                f"{path}: meta.json's taught_steps is not a whole number from 1 to "
                f"{MAX_TAUGHT_STEPS} ({shown(taught_steps)})"
            )
        shapes["taught_sensory"] = (n_seq, taught_steps, network.sensory_size)
    return network, tuple(patterns), shapes


def _model_members(path: Path, meta: dict[str, Any]) -> dict[str, tuple[int, ...] | None]:
    """The arrays a model archive holds, with their shapes (:data:`rnnpb.model.archive.Members`)."""
    return dict(_model_layout(path, meta)[2])


def _checked_history(path: Path, meta: dict[str, Any]) -> tuple[HistoryEntry, ...] | None:
    """The recorded history, each entry checked (None: none recorded, format 1)."""
    recorded = meta.get("history")
    if recorded is None and meta.get("format_version") == 1:
        return None
    if not isinstance(recorded, list) or not recorded or len(recorded) > MAX_HISTORY:
        raise ModelFileError(
            f"{path}: meta.json's history is not a list of 1 to {MAX_HISTORY} entries"
        )
    entries = tuple(HistoryEntry.from_json(path, entry) for entry in recorded)
    if entries[-1].patterns != tuple(dict.fromkeys(meta["sequence_patterns"])):
        raise ModelFileError(
            f"{path}: the history's last entry names other patterns than the model holds"
        )
    return entries


def check_joint_limits(model: TrainedModel, joint_limits: np.ndarray, where: str = "model") -> None:
    """Refuse a model whose motor normalization lies outside the robot's joint limits.

    :class:`~rnnpb.model.MirrorSystem` turns the network's motor output in [0, 1] into radians
    with the model's ``lower`` and ``upper``: bounds wider than the joints would command the
    robot past them. The model package knows no robot, so the caller passes the limits.

    Parameters
    ----------
    model : TrainedModel
    joint_limits : array, shape (M, 2)
        Lower and upper limit of each joint (radians), in the order of the motor values.
    where : str
        What to name in the message (the model file).
    """
    limits = np.asarray(joint_limits, dtype=np.float64)
    s = model.network.sensory_size
    lower, upper = np.asarray(model.lower)[s:], np.asarray(model.upper)[s:]
    if limits.shape != (lower.shape[0], 2):
        raise ModelFileError(
            f"{where}: the model has {lower.shape[0]} motor values but the "
            f"robot has joint limits of shape {limits.shape}"
        )
    outside = (lower < limits[:, 0] - JOINT_LIMIT_TOLERANCE) | (
        upper > limits[:, 1] + JOINT_LIMIT_TOLERANCE
    )
    if np.any(outside):
        j = int(np.argmax(outside))
        name = MOTOR_NAMES[j] if len(MOTOR_NAMES) == len(lower) else f"motor {j}"
        raise ModelFileError(
            f"{where}: normalization of joint {name} is [{lower[j]:.4g}, "
            f"{upper[j]:.4g}] rad, outside the robot's joint limits "
            f"[{limits[j, 0]:.4g}, {limits[j, 1]:.4g}]; refused, as it would "
            "command the robot past its joints"
        )
