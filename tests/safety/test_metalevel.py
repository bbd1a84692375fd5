"""The meta-level as the paper means it (docs/safety.md): labels by the robot's own
generation, familiarity, steering only where the PB drives the motion, inhibition while
following, and the attribution of unsafe commands."""

from __future__ import annotations

import numpy as np
import pytest

from rnnpb.demonstrator import held_scenario, learning_set
from rnnpb.errors import ModelFileError
from rnnpb.model import MirrorSystem, OnlineConfig
from rnnpb.model.archive import load_archive, save_archive
from rnnpb.model.meta import PB_DRIVEN, regime_of
from rnnpb.model.mirror import ReferenceMirrorSystem
from rnnpb.safety import (
    GENERATION,
    SEEN,
    Attribution,
    ExplorationConfig,
    asked_posture,
    explore,
    load_safety_map,
    new_map,
    safety_map_path,
)
from rnnpb.safety._map import SAFETY_FORMAT

from .maps import constructed_map


@pytest.fixture(scope="module")
def model(set1_model):
    return set1_model


def test_regimes_name_what_drives_the_motion():
    assert regime_of(np.zeros(4, bool), "familiar") == "lost"
    assert regime_of(np.ones(4, bool), "familiar") == "following"
    assert regime_of(np.ones(4, bool), "") == "following"
    for novelty in ("still", "novel", "unstructured"):
        assert regime_of(np.ones(4, bool), novelty) == novelty in PB_DRIVEN


def test_an_unsafe_region_is_inhibited_while_following_and_steered_out_when_the_pb_drives(
    model,
):
    pattern = model.patterns[1]
    centre = model.pattern_pb[pattern]
    maps = constructed_map(model, centre)
    assert maps.risk(centre) > 0.9
    performed = held_scenario(pattern, n_steps=40, seed=3).sensory
    stream = np.concatenate([performed, np.full((40, 4), np.nan)])  # then the hands are lost
    online = OnlineConfig(safety_guard="barrier")
    guarded = MirrorSystem(model, online, steering="pb_driven", inhibition=True, meta=maps.meta)
    results = [guarded.step(u) for u in stream]
    following = [r for r in results[:40] if r.regime == "following"]
    # Recognise but suppress: the pattern is recognised, its commands are held.
    assert sum(r.recognised == pattern for r in results[20:40]) >= 15
    inhibited = [r for r in following if r.inhibited]
    assert len(inhibited) >= 10
    for r in inhibited:
        assert "while following" in r.inhibited and r.generated is not None
        assert not np.array_equal(r.generated, r.motor)
    # The hands lost: the robot generates from its PB, and the guard keeps it out.
    assert all(r.regime == "lost" for r in results[40:])
    assert maps.risk(np.array([r.pb for r in results[60:]])).max() < 0.5
    unguarded = MirrorSystem(model, online)
    pbs = np.array([unguarded.step(u).pb for u in stream])
    assert maps.risk(pbs[60:]).min() > 0.5  # unguarded, the PB stays in the region
    # The NumPy twin holds the same commands.
    twin = ReferenceMirrorSystem(
        model, online, steering="pb_driven", inhibition=True, meta=maps.meta
    )
    twin_results = [twin.step(u) for u in stream[:25]]
    assert [bool(r.inhibited) for r in twin_results] == [bool(r.inhibited) for r in results[:25]]


def test_a_learned_safe_pattern_is_never_inhibited(model):
    far = np.array([0.05, 0.95, 0.05, 0.95])
    maps = constructed_map(model, far, radius=0.25)
    learned = np.array(list(model.pattern_pb.values()))
    assert maps.risk(learned).max() < 0.1
    for pattern in model.patterns:
        mirror = MirrorSystem(
            model,
            OnlineConfig(safety_guard="barrier"),
            meta=maps.meta,
            steering="pb_driven",
            inhibition=True,
        )
        results = [mirror.step(u) for u in held_scenario(pattern, n_steps=60, seed=5).sensory]
        assert not any(r.inhibited for r in results)


def test_without_a_map_the_step_is_as_before(model):
    sensory = held_scenario(model.patterns[0], n_steps=12, seed=1).sensory
    plain = MirrorSystem(model)
    results = [plain.step(u) for u in sensory]
    assert all(not r.inhibited and r.generated is None for r in results)
    assert results[-1].regime == "following"


def test_a_command_whose_own_target_collides_is_the_seen_movements():
    attribution = Attribution()
    # The left hand low across the body, the right hand at the bottom edge: the arm asked
    # for swings the forearm into the chest.
    crossing = np.array([0.64, 0.27, 0.04, 0.02])
    assert np.isfinite(asked_posture(crossing)).all()
    assert "collision:" in attribution.asks_unsafe(crossing)
    attribution.reset()
    assert attribution.attribute(crossing, "collision:rforearm_geom-chest") == SEEN
    attribution.reset()
    ordinary = learning_set("1", seed=0)[0].sensory[0]  # a taught pattern's hands
    assert attribution.asks_unsafe(ordinary) == ""
    attribution.reset()
    assert attribution.attribute(ordinary, "collision:lforearm_geom-chest") == GENERATION
    assert attribution.attribute(ordinary, "") == ""
    assert attribution.asks_unsafe(np.full(4, np.nan)) == ""  # nothing seen: nothing asked
    attribution.reset()
    causes = attribution.attribute_sequence(
        np.array([ordinary, crossing, ordinary]), ["", "collision:x-chest", "speed:lshp"]
    )
    assert causes[:2] == ["", SEEN]


def test_exploration_labels_by_the_generation_after_its_transient(model):
    config = ExplorationConfig(samples=40, steps=40, starts=3, transient=10, batch=120)
    experience = explore(model, config)
    assert experience.pb.shape == (40, 4) and experience.share.shape == (40,)
    assert set(np.unique(experience.share)) <= {0.0, 1 / 3, 2 / 3, 1.0}
    assert np.array_equal(experience.unsafe, experience.share >= 0.5)
    learned = np.array(list(model.pattern_pb.values()))
    own = explore(model, config, pbs=learned)
    assert not own.unsafe.any()  # learned patterns were taught safe


def test_familiarity_separates_experienced_from_never_experienced(model):
    centre = model.pattern_pb[model.patterns[0]]
    maps = constructed_map(model, centre)
    rng = np.random.default_rng(2)
    near = np.clip(centre + rng.normal(0, 0.03, (50, 4)), 0, 1)
    assert maps.familiarity(near).min() > 0.9
    lonely = new_map(model, maps.meta, near, np.zeros(50, bool), 0.05, {})
    assert lonely.familiarity(np.array([0.95, 0.05, 0.95, 0.05])) < 0.01


def test_a_version_1_map_is_refused(model, tmp_path):
    maps = constructed_map(model, model.pattern_pb[model.patterns[0]])
    path = safety_map_path(tmp_path / "m.npz")
    maps.save(path)
    meta, arrays = load_archive(path, SAFETY_FORMAT, 2)
    save_archive(path, {**meta, "format_version": 1}, arrays)
    with pytest.raises(ModelFileError, match="version-1 safety map.*rnnpb safety learn"):
        load_safety_map(path, model)
