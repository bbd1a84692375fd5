"""Safety maps made by construction for the safety tests."""

from __future__ import annotations

import numpy as np

from rnnpb.safety import Experience, MetaConfig, fit_meta, new_map


def constructed_map(model, centre, radius=0.2, familiarity_width=0.05):
    """A map of ``model`` whose unsafe region is the ball of ``radius`` around ``centre``: the
    risk network learned from 3,000 uniform PBs and 1,000 around the centre."""
    rng = np.random.default_rng(0)
    pbs = np.concatenate(
        [rng.uniform(size=(3000, 4)), np.clip(centre + rng.normal(0, 0.2, (1000, 4)), 0, 1)]
    )
    return ball_map(model, pbs, centre, radius, familiarity_width, 2000, {"constructed": True})


def ball_map(model, pbs, centre, radius, familiarity_width, iterations, note):
    """A map of ``model`` learned from ``pbs``, explored, unsafe within ``radius`` of
    ``centre``: the risk network fitted for ``iterations``."""
    unsafe = np.linalg.norm(pbs - centre, axis=1) < radius
    experience = Experience(
        pbs,
        unsafe,
        unsafe.astype(float),
        np.zeros(len(pbs), bool),
        np.array(["explored"] * len(pbs)),
        {},
    )
    meta = fit_meta(experience, MetaConfig(iterations=iterations))
    return new_map(model, meta, pbs, unsafe, familiarity_width, note)
