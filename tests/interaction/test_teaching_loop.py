"""The keeper in a real interaction loop, with the novelty detector of the on-line step."""

from __future__ import annotations

import pytest

from rnnpb.interaction import InteractionLoop, LoopConfig, open_source
from rnnpb.interaction.teaching import EpisodeKeeper, episode_steps, shown_as
from rnnpb.memory import MemoryStore
from rnnpb.model import MirrorSystem


@pytest.fixture(scope="module")
def model(set1_model):
    """Learning set 1 with the fast preset: the session's shared model (tests/conftest.py)."""
    return set1_model


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
    steps = episode_steps(episodes[0].note)
    assert steps is not None, episodes[0].note
    first, last = steps
    assert shown_as(episodes[0].note) == "figure-eight"  # what the scenario said it performed
    # whole cycles of the new shape only: nothing of the learned pattern before it, nothing
    # of the random walk after it
    assert set(truth[first : last + 1]) == {"figure-eight"}
    # kept at three cycles, then grown by the cycles shown after that until the shape ended
    assert episodes[0].n_cycles > 3 and episodes[0].pattern == "new-1"


def test_teaching_consolidates_in_the_background_and_swaps_the_new_version_in(model, tmp_path):
    from rnnpb.interaction.teaching import Teacher, version_path
    from rnnpb.model import TrainedModel

    path = tmp_path / "m.npz"
    model.save(path)
    # the new shape in two performances, another pattern between them
    spec = "scenario:steps:1*30,figure-eight*60,2*30,figure-eight*70"
    with open_source(spec, seed=2) as source, MemoryStore(path) as memory:
        loop = InteractionLoop(MirrorSystem(model), source, config=LoopConfig(max_steps=190))
        # run as fast as possible: the loop waits for the consolidation, so the run repeats
        teacher = Teacher(loop, path, memory, make_mirror=MirrorSystem, source=spec, iterations=20)
        loop.run(between_steps=teacher.between_steps)
        kinds = [e.kind for e in teacher.events]
        assert kinds.count("kept") == 2 and "learned" in kinds, teacher.events
        # seen once, the teacher waits for the next performance (no consolidation yet)
        waiting = kinds.index("waiting")
        assert kinds.index("consolidating") > waiting > kinds.index("kept")
        assert "new-1 seen once: show it again" in teacher.events[waiting].text
        # the second performance is merged with the first and both are learned as one pattern
        first, second = memory.episodes()
        assert first.pattern == second.pattern == "new-1"
        assert teacher.versions == [str(path), str(version_path(path, 2))]
        assert "new-1" in loop.mirror.model.patterns
        assert loop.mirror.model.sequence_patterns.count("new-1") == 2
        assert first.status == second.status == "learned"
        (consolidation,) = memory.consolidations()
        # every learned sequence rehearsed, and both performances
        assert consolidation.status == "done"
        assert consolidation.episode_ids == (first.id, second.id)
        assert consolidation.n_rehearsed == len(model.sequence_patterns) + 2
        assert "learned as pattern new-1 (seen twice" in teacher.events[kinds.index("learned")].text
        # The scenario said what it performed: the episode's note keeps it, for the person.
        assert shown_as(memory.episodes()[0].note) == "figure-eight"
        teacher.undo()
        assert "new-1" not in loop.mirror.model.patterns
        # What the undone version learned is kept again (a Confirm learns it again), and it is
        # not learned again at once: the person has just said no to it.
        assert [e.status for e in memory.episodes()] == ["kept", "kept"]
        assert teacher.pending == [] and teacher.job is None
        assert "episodes 1, 2 kept again" in teacher.events[-1].text
    assert "new-1" in TrainedModel.load(version_path(path, 2)).patterns  # kept on disk


def test_interact_learn_keeps_a_new_shape_writes_a_version_and_nothing_from_random(
    model, tmp_path, capsys
):
    import json

    from rnnpb.cli import main
    from rnnpb.interaction.teaching import version_path
    from rnnpb.memory import memory_path_for

    path = tmp_path / "m.npz"
    model.save(path)
    out = tmp_path / "run"
    assert (
        main(
            [
                "interact",
                "--model",
                str(path),
                "--source",
                "scenario:steps:1*30,figure-eight*90",
                "--seed",
                "2",
                "--learn",
                "--learn-from-one",  # the person insists: one performance is enough
                "--consolidation-iterations",
                "20",
                "--no-progress",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    printed = capsys.readouterr().out
    teaching = json.loads((out / "summary.json").read_text())["teaching"]
    # kept at two cycles and learned; the cycles shown after that, followed loosely by the
    # freshly learned pattern, are more data for it
    episodes = teaching["episodes"]
    assert {(e["pattern"], e["status"]) for e in episodes} == {("new-1", "learned")}
    assert "grows" not in episodes[0]["note"]
    assert all("grows new-1" in e["note"] for e in episodes[1:])
    assert teaching["versions_written"][0] == str(version_path(path, 2))
    assert len(teaching["versions_written"]) == len(episodes)
    assert version_path(path, 2).exists() and teaching["memory"] == str(memory_path_for(path))
    for words in (
        "kept a new movement as new-1",
        "into m.v2.npz (pattern new-1)",
        "learned as pattern new-1",
    ):
        assert words in printed, printed

    # unstructured movement: nothing kept, no version written, the memory untouched
    out = tmp_path / "walk"
    assert (
        main(
            [
                "interact",
                "--model",
                str(path),
                "--source",
                "scenario:steps:random-walk*150",
                "--learn",
                "--no-progress",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    teaching = json.loads((out / "summary.json").read_text())["teaching"]
    assert teaching["episodes"] == [] and teaching["versions_written"] == []
    assert len(list(tmp_path.glob("m.v*.npz"))) == len(episodes)


def test_consolidation_iterations_need_learn_and_a_positive_count(tmp_path, capsys):
    from rnnpb.cli import main

    for extra, named in (
        (["--consolidation-iterations", "20"], "--consolidation-iterations"),
        (["--learn", "--consolidation-iterations", "0"], "--consolidation-iterations"),
        (["--learn-from-one"], "--learn-from-one"),
    ):
        assert (
            main(["interact", "--source", "scenario:held:1", "--out", str(tmp_path), *extra]) == 2
        )
        assert named in capsys.readouterr().err


def test_learning_from_the_shipped_model_works_on_a_copy_in_the_run_folder(tmp_path, monkeypatch):
    from pathlib import Path

    import rnnpb.models
    from rnnpb.cli import main

    monkeypatch.chdir(tmp_path)  # no ./models or ./results here: the shipped model is used
    shipped = Path(rnnpb.models.__file__).parent
    before = sorted(p.name for p in shipped.iterdir())
    out = tmp_path / "run"
    assert (
        main(
            [
                "interact",
                "--source",
                "scenario:steps:random-walk*12",
                "--learn",
                "--out",
                str(out),
                "--no-progress",
            ]
        )
        == 0
    )
    assert sorted(p.name for p in shipped.iterdir()) == before
    assert any(p.suffix == ".npz" for p in out.iterdir())
    assert any(p.name.endswith(".memory.sqlite") for p in out.iterdir())


def _waves_between_learned_patterns(mocap_dir):
    """Pattern 1, a real person's first wave take, pattern 2, the second take, pattern 3, the
    third take (sensory arrays): each take slowed to a 12-step period, the person framed 1.5 m
    from the robot (hands out of view not seen)."""
    import numpy as np

    from rnnpb.demonstrator import make_scenario
    from rnnpb.learning_phase import from_capture, projected, resampled

    def take(name: str) -> np.ndarray:
        steps = resampled(from_capture([str(mocap_dir / name)]), 0.4, 4.0)
        sensory = projected(steps.hands, 1.5)
        sensory[~((sensory >= 0) & (sensory <= 1)).all(axis=1)] = np.nan
        return sensory

    waves = sorted(p.name for p in mocap_dir.glob("*wave-both-hands*.bvh"))[:3]
    learned = [
        np.asarray(make_scenario([(p, n)], seed=k).sensory)
        for k, (p, n) in enumerate([("1", 40), ("2", 60), ("3", 60)])
    ]
    takes = [take(name) for name in waves]
    return [learned[0], takes[0], learned[1], takes[1], learned[2], takes[2]]


def test_a_person_s_wave_shown_for_a_few_cycles_is_kept_merged_and_learned_once(
    model, tmp_path, mocap_dir
):
    """Three takes of a real person waving (about five cycles each, slowed to a 12-step
    period), learned patterns between them: the first two are kept as each ends, the second
    merged with the first, and both learned as one pattern; the third is recognised as it and,
    followed loosely, is more data for it; nothing else is kept. (Without the cycles the novel
    call rests on, none of these takes holds enough steps called novel to keep.)"""
    import numpy as np

    from rnnpb.interaction.teaching import Teacher
    from rnnpb.sources import ArraySensorySource

    parts = _waves_between_learned_patterns(mocap_dir)
    stream = np.concatenate(parts)
    path = tmp_path / "m.npz"
    model.save(path)
    with ArraySensorySource(stream) as source, MemoryStore(path) as memory:
        loop = InteractionLoop(MirrorSystem(model), source, config=LoopConfig())
        teacher = Teacher(
            loop, path, memory, make_mirror=MirrorSystem, source="waves", iterations=20
        )
        loop.run(between_steps=teacher.between_steps)
        teacher.finish()  # as `rnnpb interact` does when its source ends
        teacher.between_steps(0.0)
        episodes = memory.episodes()
    assert [e.pattern for e in episodes] == ["new-1"] * 3, [e.note for e in episodes]
    assert [e.status for e in episodes] == ["learned"] * 3
    assert "merged with episode 1" in episodes[1].note
    assert "grows new-1" in episodes[2].note and "grows" not in episodes[1].note
    assert "new-1" in loop.mirror.model.patterns
    # each kept performance lies within one take: nothing of the learned patterns around them
    ends = np.cumsum([len(part) for part in parts])
    within = [(ends[k] - len(parts[k]), ends[k]) for k in (1, 3, 5)]  # the takes' steps
    for episode in episodes:
        first, last = episode_steps(episode.note)
        assert any(a <= first and last < b for a, b in within), episode.note


def test_interact_learn_learns_a_wave_shown_twice_and_grows_it_with_the_third(
    model, tmp_path, mocap_dir, capsys
):
    """`rnnpb interact --learn` on a recording of three waves between learned patterns: the
    second wave is kept, merged with the first and learned; the third is recognised as it and
    is more data for it."""
    import json

    import numpy as np

    from rnnpb.cli import main

    stream = np.concatenate(_waves_between_learned_patterns(mocap_dir))
    csv = tmp_path / "waves.csv"
    rows = [f"{t}," + ",".join(f"{v:.6f}" for v in row) for t, row in enumerate(stream)]
    csv.write_text("step,lhy,lhz,rhy,rhz\n" + "\n".join(rows) + "\n")
    path = tmp_path / "m.npz"
    model.save(path)
    arguments = ["interact", "--model", str(path), "--source", f"csv:{csv}", "--learn"]
    arguments += ["--consolidation-iterations", "20", "--no-progress", "--out", str(tmp_path)]
    assert main(arguments) == 0
    printed = capsys.readouterr().out
    teaching = json.loads((tmp_path / "summary.json").read_text())["teaching"]
    assert [e["pattern"] for e in teaching["episodes"]] == ["new-1"] * 3
    assert [e["status"] for e in teaching["episodes"]] == ["learned"] * 3
    assert "kept another performance of new-1" in printed, printed
    assert "learned as pattern new-1 (seen twice" in printed, printed
    assert "kept a performance of new-1 the robot did not follow closely" in printed, printed
