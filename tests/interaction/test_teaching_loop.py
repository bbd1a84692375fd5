"""The keeper in a real interaction loop, with the novelty detector of the on-line step."""

from __future__ import annotations

import pytest

from rnnpb.demonstrator import learning_set
from rnnpb.interaction import InteractionLoop, LoopConfig, open_source
from rnnpb.interaction.teaching import EpisodeKeeper
from rnnpb.memory import MemoryStore
from rnnpb.model import MirrorSystem, TrainConfig, train
from rnnpb.robot import JOINT_LIMITS


@pytest.fixture(scope="module")
def model(tmp_path_factory):
    return train(learning_set("1"), JOINT_LIMITS, config=TrainConfig.fast(iterations=1500))


def test_a_new_shape_is_kept_and_random_movement_is_not(model, tmp_path):
    spec = "scenario:steps:1*30,figure-eight*90,random-walk*90"
    records = []
    with open_source(spec, seed=2) as source, MemoryStore(tmp_path / "m.npz") as memory:
        loop = InteractionLoop(MirrorSystem(model), source, config=LoopConfig(max_steps=210))
        keeper = EpisodeKeeper(memory, "m.npz", spec)
        loop.subscribe(keeper)
        loop.subscribe(records.append)
        loop.run()
        episodes = memory.episodes()
    truth = [r.truth.get("pattern", "") for r in records]
    assert len(episodes) == 1, [e.note for e in episodes]
    first, last = (int(v) for v in episodes[0].note.removeprefix("steps ").split("-"))
    # whole cycles of the new shape only: nothing of the learned pattern before it, nothing
    # of the random walk after it
    assert set(truth[first:last + 1]) == {"figure-eight"}
    assert episodes[0].n_cycles == 4 and episodes[0].pattern == "new-1"


def test_teaching_consolidates_in_the_background_and_swaps_the_new_version_in(model, tmp_path):
    from rnnpb.interaction.teaching import Teacher, version_path
    from rnnpb.model import TrainedModel

    path = tmp_path / "m.npz"
    model.save(path)
    spec = "scenario:steps:1*30,figure-eight*90"
    with open_source(spec, seed=2) as source, MemoryStore(path) as memory:
        loop = InteractionLoop(MirrorSystem(model), source, config=LoopConfig(max_steps=120))
        # run as fast as possible: the loop waits for the consolidation, so the run repeats
        teacher = Teacher(loop, path, memory, make_mirror=MirrorSystem, source=spec,
                          iterations=20)
        loop.run(between_steps=teacher.between_steps)
        kinds = [e.kind for e in teacher.events]
        assert "kept" in kinds and "learned" in kinds, teacher.events
        assert teacher.versions == [str(path), str(version_path(path, 2))]
        assert "new-1" in loop.mirror.model.patterns
        assert memory.episodes()[0].status == "learned"
        (consolidation,) = memory.consolidations()
        # every learned sequence rehearsed, and the new one
        assert consolidation.status == "done"
        assert consolidation.n_rehearsed == len(model.sequence_patterns) + 1
        teacher.undo()
        assert "new-1" not in loop.mirror.model.patterns
    assert "new-1" in TrainedModel.load(version_path(path, 2)).patterns  # kept on disk
