"""The dashboard's models: the files ``--model`` offers, a model made ready to run (loaded,
its safety, its mirror system compiled), and the shelf of models and versions the session
runs one of.

A model is made ready wherever it is needed — on the session thread when the person picks
one, in a thread of its own when teaching has learned a new version — by one function,
:func:`make_ready`, so that both run a model exactly alike.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb.errors import ConfigError, RnnpbError
from rnnpb.presets import Overrides

log = logging.getLogger("rnnpb.web")


def offered_models(model_or_dir: str | Path) -> tuple[dict[str, Path], dict[str, str]]:
    """The models ``--model`` offers, each loaded once to check it, and those it refuses.

    A ``.npz`` file is offered if it loads; otherwise its one-line error is raised. A folder
    offers every ``*.npz`` under it that loads, except training checkpoints
    (``*.checkpoint.npz``) and hidden files (``.name``: unfinished writes); the others are
    refused with their reason. A folder with nothing to offer is an error.

    Returns
    -------
    models : dict of name → path
        Names are paths relative to the folder (the file's name for a file).
    refused : dict of name → reason
    """
    from rnnpb.model import TrainedModel

    path = Path(model_or_dir)
    if path.is_file():
        TrainedModel.load(path)  # a bad model is its one-line error, before serving
        return {path.name: path}, {}
    if not path.is_dir():
        raise ConfigError(f"{path}: no such model file or folder")
    models: dict[str, Path] = {}
    refused: dict[str, str] = {}
    for found in sorted(path.rglob("*.npz")):
        name = str(found.relative_to(path))
        # A checkpoint, or a model's safety map (M.safety.npz, docs/safety.md): not models.
        if found.name.endswith((".checkpoint.npz", ".safety.npz")) or any(
            part.startswith(".") for part in found.relative_to(path).parts
        ):
            continue
        try:
            TrainedModel.load(found)
        except RnnpbError as error:
            refused[name] = str(error)
            continue
        models[name] = found
    if not models:
        reasons = "; ".join(f"{reason}" for reason in refused.values())
        raise ConfigError(
            f"{path}: no usable model files (*.npz) in this folder"
            + (f" ({reasons})" if reasons else "; train one with `rnnpb train`")
        )
    return models, refused


def find_models(model_or_dir: str | Path) -> dict[str, Path]:
    """The models ``--model`` offers (:func:`offered_models`); each refused model is logged
    as a warning with its reason."""
    models, refused = offered_models(model_or_dir)
    for name, reason in refused.items():
        log.warning("not offering %s: %s", name, reason)
    return models


@dataclass(frozen=True)
class ReadyModel:
    """A model made ready to run: the file, the model, its mirror system (step compiled), its
    safety (:class:`rnnpb.safety.OnlineSafety`, or None) and the risk the PB plot shades
    (one grid per view; empty without a safety map)."""

    path: Path
    model: Any
    mirror: Any
    safety: Any = None
    risk: dict[str, Any] = field(default_factory=dict)

    def safety_state(self) -> dict[str, Any]:
        """The ``safety`` part of the state message: what guards the robot, and the risk
        grids of the PB plot (empty without a map)."""
        if self.safety is None:
            return ReadyModel.no_safety()
        return {**self.safety.to_dict(), "risk": self.risk}

    @staticmethod
    def no_safety() -> dict[str, Any]:
        """The ``safety`` part of the state message while nothing guards the robot."""
        return {"map": False, "guard": "off", "filter": False, "note": "", "risk": {}}


def make_ready(path: str | Path, overrides: Overrides | None, safety_enabled: bool) -> ReadyModel:
    """Load the model at ``path`` with the on-line regression that suits it (as ``rnnpb
    interact`` picks it, with a ``--config`` file's values: ``overrides``), its safety (the
    command filter, and the map beside it; neither without ``safety_enabled``) and its
    mirror system, and compile the mirror's step (seconds; never between two steps)."""
    from rnnpb.model import MirrorSystem, OnlineConfig, TrainedModel
    from rnnpb.robot import JOINT_LIMITS
    from rnnpb.safety import online_safety, risk_views

    path = Path(path)
    model = TrainedModel.load(path, joint_limits=JOINT_LIMITS)
    choice = OnlineConfig.for_model(model, overrides)
    safety = online_safety(path, model, choice.config, enabled=safety_enabled)
    log.info("%s", safety.note)
    risk = {} if safety.safety_map is None else risk_views(safety.safety_map, model.pattern_pb)
    mirror = MirrorSystem(
        model, safety.config, recognition=choice.recognition, **safety.mirror_options
    )
    started = time.perf_counter()
    mirror.step(np.full(model.network.sensory_size, 0.5))  # compiles the step
    mirror.reset()
    log.info(
        "model %s ready with the %s on-line regression (%s; step compiled in %.1f s)",
        path.name,
        choice.name,
        choice.reason,
        time.perf_counter() - started,
    )
    return ReadyModel(path, model, mirror, safety, risk)


class ModelShelf:
    """The models the session offers (``offered``: name → file; versions teaching learns
    join it), the one that runs (``running``) and its name, and what is loading.

    Parameters
    ----------
    models : dict of name → path
    """

    def __init__(self, models: dict[str, Path]) -> None:
        if not models:
            raise ConfigError("the dashboard needs at least one model")
        self.offered = dict(models)
        self.running: ReadyModel | None = None
        self.name: str | None = None
        self.loading: str | None = None  # the name being loaded
        self.error: str | None = None  # why the last model chosen cannot be used
        # ``rnnpb serve --no-safety`` and ``--config`` set these before the first model loads.
        self.safety_enabled = True
        self.overrides: Overrides | None = None

    @property
    def first(self) -> str:
        return next(iter(self.offered))

    def load(self, name: str, announce: Callable[[], None] = lambda: None) -> ReadyModel:
        """Make model ``name`` ready (not yet running: :meth:`run` it); ``announce()`` is
        called once ``loading`` names it, before the seconds of compilation. A model that
        cannot be used raises a :class:`ConfigError` that says so and which model stays."""
        if name not in self.offered:
            raise ConfigError(f"no model {name!r} (this server offers: {', '.join(self.offered)})")
        self.loading = name
        try:
            announce()
            return make_ready(self.offered[name], self.overrides, self.safety_enabled)
        except Exception as error:
            kept = f"; still using {self.name}" if self.name else ""
            self.error = f"model {name} cannot be used: {error}{kept}"
            raise ConfigError(self.error) from None
        finally:
            self.loading = None

    def run(self, ready: ReadyModel, name: str | None = None) -> None:
        """``ready`` runs from now on (under ``name``; by default the name it runs under)."""
        self.running = ready
        if name is not None:
            self.name = name
        self.error = None

    def offer(self, path: str | Path) -> str:
        """Offer a version teaching learned (``set1.v2.npz``, as the list names files; another
        folder's file of the same name with its folder) and return its name."""
        path = Path(path)
        name = path.name
        known = self.offered.get(name)
        if known is not None and Path(known).resolve() != path.resolve():
            name = f"{name} ({path.parent.name})"
        self.offered[name] = path
        return name
