"""From experience to a stored map: explore, fit the meta-level, keep what was experienced."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, replace

import numpy as np

from rnnpb.model import TrainedModel
from rnnpb.safety._check import SafetyChecker, SafetyLimits
from rnnpb.safety._explore import Experience, ExplorationConfig, explore
from rnnpb.safety._map import SafetyMap, new_map
from rnnpb.safety._meta import MetaConfig, fit_meta


def learn_safety_map(
    model: TrainedModel,
    exploration: ExplorationConfig | None = None,
    meta: MetaConfig | None = None,
    limits: SafetyLimits | None = None,
    also: Experience | None = None,
    progress: Callable[[int, int], None] | None = None,
    lived: np.ndarray | None = None,
) -> SafetyMap:
    """Explore the model's PB space, and the PBs ``lived`` (n, P) in sessions the robot lived
    through, each by its own generation from many starts; join ``also`` (PBs labelled
    elsewhere); fit the risk network; the map to save beside the model. Every PB of the
    experience counts for familiarity."""
    exploration = exploration or ExplorationConfig()
    meta = meta or MetaConfig()
    limits = limits or SafetyLimits()
    checker = SafetyChecker(limits)
    experience = explore(model, exploration, checker, progress)
    if lived is not None and len(lived):
        own = explore(model, replace(exploration, seed=exploration.seed + 1), checker, pbs=lived)
        experience = experience.joined(
            replace(
                own,
                source=np.array(["lived"] * len(own.pb)),
                counts={"lived": len(own.pb), "lived_unsafe": int(own.unsafe.sum())},
            )
        )
    if also is not None:
        experience = experience.joined(also)
    params = fit_meta(experience, meta)
    info = {
        "exploration": asdict(exploration),
        "meta": asdict(meta),
        "limits": asdict(limits),
        "step_limit_rad": limits.step_limit,
        "counts": experience.counts,
        "visited": int((experience.source == "visited").sum()),
        "lived": int((experience.source == "lived").sum()),
    }
    return new_map(model, params, experience.pb, experience.unsafe, meta.familiarity_width, info)
