"""Safety in an on-line run (``rnnpb interact``, ``rnnpb serve``): the model's map when there
is one beside it, the command filter always (it needs no map), or neither when switched off.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from rnnpb.model import OnlineConfig, TrainedModel
from rnnpb.model.meta import MetaParams
from rnnpb.safety._filter import CommandFilter
from rnnpb.safety._map import SafetyMap, find_safety_map, safety_map_path


@dataclass(frozen=True)
class OnlineSafety:
    """What an on-line run uses: ``config`` for the mirror system (its ``safety_guard`` acts
    only with ``meta``), ``meta`` the risk network of ``safety_map`` (None without a map),
    ``command_filter`` (None only when safety is off), and ``note``: one line saying which.
    ``steering`` and ``inhibition``: the meta-level's part of each step
    (:class:`rnnpb.model.meta.MetaLevel`): the guard acts only where the PB drives the motion,
    and a recognised unsafe PB's command is held while following; :attr:`mirror_options` are
    the mirror system's arguments for all of it."""

    config: OnlineConfig
    meta: MetaParams | None
    command_filter: CommandFilter | None
    safety_map: SafetyMap | None
    note: str
    steering: str = "pb_driven"
    inhibition: bool = True

    @property
    def mirror_options(self) -> dict[str, Any]:
        """``meta``, ``steering`` and ``inhibition`` for :class:`rnnpb.model.MirrorSystem`."""
        return {"meta": self.meta, "steering": self.steering, "inhibition": self.inhibition}

    def to_dict(self) -> dict[str, object]:
        return {
            "map": self.safety_map is not None,
            "guard": self.guard,
            "filter": self.command_filter is not None,
            "steering": self.steering if self.meta is not None else "off",
            "inhibition": self.inhibition and self.meta is not None,
            "note": self.note,
        }

    @property
    def guard(self) -> str:
        """The guard that acts in the regression ("off" without a map)."""
        return self.config.safety_guard if self.meta is not None else "off"


def online_safety(
    model_path: str | os.PathLike[str],
    model: TrainedModel,
    online: OnlineConfig,
    enabled: bool = True,
) -> OnlineSafety:
    """The safety of an on-line run with the model at ``model_path``.

    With ``enabled``: the map beside the model (:func:`find_safety_map`; a damaged or
    foreign map raises :class:`rnnpb.errors.ModelFileError`) guards the PB as
    ``online.safety_guard`` says, and the command filter checks every command; without a map
    the filter alone guards (the documented fallback). Without ``enabled`` neither runs.
    """
    if not enabled:
        return OnlineSafety(
            replace(online, safety_guard="off"),
            None,
            None,
            None,
            "safety: off (no PB guard, no command filter)",
        )
    safety_map = find_safety_map(model_path, model)
    command_filter = CommandFilter()
    if safety_map is None:
        return OnlineSafety(
            online,
            None,
            command_filter,
            None,
            f"safety: no map beside the model ({safety_map_path(model_path).name}"
            "; `rnnpb safety learn` makes one): the command filter alone "
            "guards the robot",
        )
    guard = online.safety_guard
    return OnlineSafety(
        online,
        safety_map.meta,
        command_filter,
        safety_map,
        f"safety: map {safety_map_path(model_path).name}, PB guard {guard}"
        + (" (OnlineConfig.safety_guard)" if guard == "off" else " where the PB drives")
        + ", inhibition while following, command filter on",
    )


def risk_plane(
    safety_map: SafetyMap,
    origin: np.ndarray,
    axes: np.ndarray,
    extent: tuple[float, float, float, float],
    grid: int = 24,
) -> dict[str, object]:
    """The learned risk on a plane of PB space, for a plot: the PBs ``origin + a·axes[0] +
    b·axes[1]`` for ``a`` in ``extent[0:2]`` and ``b`` in ``extent[2:4]`` on a ``grid`` ×
    ``grid`` lattice of cell centres (clipped to [0, 1]). Returns the plane (``origin``,
    ``axes``, ``extent``, ``grid``) and ``risk``: grid rows along ``b``, each ``grid`` values
    along ``a``, rounded to 3 decimals."""
    origin = np.asarray(origin, dtype=np.float64)
    axes = np.asarray(axes, dtype=np.float64)
    a = extent[0] + (np.arange(grid) + 0.5) * (extent[1] - extent[0]) / grid
    b = extent[2] + (np.arange(grid) + 0.5) * (extent[3] - extent[2]) / grid
    points = origin + a[None, :, None] * axes[0] + b[:, None, None] * axes[1]
    values = safety_map.risk(np.clip(points, 0.0, 1.0))
    return {
        "origin": np.round(origin, 5).tolist(),
        "axes": np.round(axes, 5).tolist(),
        "extent": [float(v) for v in extent],
        "grid": grid,
        "risk": np.round(values, 3).tolist(),
    }


def risk_views(
    safety_map: SafetyMap, learned: dict[str, np.ndarray], grid: int = 24
) -> dict[str, dict[str, object]]:
    """The risk on the dashboard's PB views: ``"01"`` (PB0 × PB1) and ``"23"`` (PB2 × PB3),
    the other two PB values at the learned PBs' mean, each over [0, 1]²; and ``"plane"``, the
    plane through the learned PBs (their mean and two main directions), 0.8 either way."""
    pbs = np.array(list(learned.values()), dtype=np.float64)
    mean = pbs.mean(axis=0)
    p = len(mean)
    views = {}
    for name, (i, j) in {"01": (0, 1), "23": (2, 3)}.items():
        if j >= p:
            continue
        origin = mean.copy()
        origin[[i, j]] = 0.0
        axes = np.zeros((2, p))
        axes[0, i] = axes[1, j] = 1.0
        views[name] = risk_plane(safety_map, origin, axes, (0.0, 1.0, 0.0, 1.0), grid)
    if len(pbs) >= 2:
        _, _, directions = np.linalg.svd(pbs - mean, full_matrices=False)
        views["plane"] = risk_plane(safety_map, mean, directions[:2], (-0.8, 0.8, -0.8, 0.8), grid)
    return views
