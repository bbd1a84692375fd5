"""The short-term memory file: episodes whole or not at all, its own files only, kill -9 safe."""

from __future__ import annotations

import os
import signal
import sqlite3
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

from rnnpb.errors import DataFileError, RnnpbError
from rnnpb.memory import MemoryFileError, MemoryStore, memory_path_for
from rnnpb.sequences import Sequence


def _movement(n=24, seed=0):
    rng = np.random.default_rng(seed)
    return rng.uniform(0.2, 0.8, (n, 4)), rng.uniform(-0.5, 0.5, (n, 8))


def test_the_memory_file_sits_beside_the_model(tmp_path):
    assert memory_path_for(tmp_path / "m.npz") == tmp_path / "m.memory.sqlite"
    assert memory_path_for(tmp_path / "m.memory.sqlite") == tmp_path / "m.memory.sqlite"


def test_an_episode_comes_back_as_it_went_in(tmp_path):
    sensory, motor = _movement()
    with MemoryStore(tmp_path / "m.npz") as memory:
        first = memory.add_episode(
            sensory, motor, source="synthetic:3", model="m.npz", pattern="new-1", n_cycles=2
        )
        second = memory.add_episode(
            *_movement(30, 1), source="webcam:0", model="m.npz", pattern="new-2", n_cycles=2
        )
    with MemoryStore(tmp_path / "m.memory.sqlite", create=False) as memory:
        episode = memory.episode(first)
        assert np.array_equal(episode.sensory, sensory) and np.array_equal(episode.motor, motor)
        assert episode.summary.source == "synthetic:3" and episode.summary.status == "kept"
        memory.rename(first, "wave")
        assert memory.episode(first).sequence().pattern == "wave"
        memory.set_status(second, "discarded")
        assert [e.id for e in memory.episodes("kept")] == [first]
        memory.forget(second)
        assert [e.id for e in memory.episodes()] == [first]
        with pytest.raises(MemoryFileError, match="no episode"):
            memory.episode(second)


def test_an_undone_version_gives_its_episodes_back_as_kept(tmp_path):
    with MemoryStore(tmp_path / "m.npz") as memory:
        first, second, third = (
            memory.add_episode(
                *_movement(seed=k), source="s", model="v1.npz", pattern=f"new-{k}", n_cycles=2
            )
            for k in range(3)
        )
        for ids, after in (([first], "v2.npz"), ([second, third], "v3.npz")):
            memory.add_consolidation(
                model_before="v1.npz", model_after=tmp_path / after, episode_ids=ids, rehearsed=[]
            )
        memory.set_status(third, "discarded")  # since then: left as it is
        assert memory.unlearn(tmp_path / "v3.npz") == [second]
        assert [e.status for e in memory.episodes()] == ["learned", "kept", "discarded"]
        assert memory.unlearn(tmp_path / "v3.npz") == []  # twice: nothing more
        assert memory.unlearn(tmp_path / "elsewhere.npz") == []


def test_a_consolidation_keeps_its_rehearsals_and_marks_its_episodes_learned(tmp_path):
    with MemoryStore(tmp_path / "m.npz") as memory:
        episode = memory.add_episode(
            *_movement(), source="s", model="v1.npz", pattern="new-1", n_cycles=2
        )
        rehearsed = [Sequence(*_movement(20, k), pattern=str(k)) for k in (1, 2, 3)]
        consolidation = memory.add_consolidation(
            model_before="v1.npz",
            model_after="v2.npz",
            episode_ids=[episode],
            rehearsed=rehearsed,
            seconds=12.5,
        )
        assert memory.episode(episode).summary.status == "learned"
        (summary,) = memory.consolidations()
        assert summary.episode_ids == (episode,) and summary.n_rehearsed == 3
        back = memory.rehearsed(consolidation)
        assert [s.pattern for s in back] == ["1", "2", "3"]
        assert np.array_equal(back[1].motor, rehearsed[1].motor)
        # a consolidation naming an episode that is not there is refused as a whole
        with pytest.raises(MemoryFileError, match="no episode 99"):
            memory.add_consolidation(
                model_before="v2.npz", model_after="v3.npz", episode_ids=[99], rehearsed=rehearsed
            )
        assert len(memory.consolidations()) == 1


def test_a_kept_episode_regrows_in_place_and_a_learned_one_never(tmp_path):
    with MemoryStore(tmp_path / "m.npz") as memory:
        first = memory.add_episode(
            *_movement(24), source="s", model="v1.npz", pattern="new-1", n_cycles=2, note="a"
        )
        longer = _movement(48, seed=1)
        assert memory.regrow(first, *longer, n_cycles=4, note="steps 0-47")
        back = memory.episode(first)
        assert back.summary.n_cycles == 4 and back.summary.note == "steps 0-47"
        assert np.array_equal(back.sensory, longer[0]) and np.array_equal(back.motor, longer[1])
        assert back.summary.pattern == "new-1" and back.summary.status == "kept"
        memory.set_status(first, "learned")
        assert not memory.regrow(first, *_movement(60, seed=2), n_cycles=5, note="b")
        assert memory.episode(first).summary.n_steps == 48
        with pytest.raises(RnnpbError):  # a bad movement is refused before anything is written
            memory.regrow(first, np.full((10, 4), np.nan), np.zeros((10, 8)), 1, "c")


def test_a_merge_joins_an_episode_to_a_movement_and_a_split_undoes_it(tmp_path):
    with MemoryStore(tmp_path / "m.npz") as memory:
        ids = [
            memory.add_episode(
                *_movement(24, seed),
                source="webcam:0",
                model="m.npz",
                pattern=name,
                n_cycles=2,
                note=f"steps {10 * seed}-{10 * seed + 23}",
            )
            for seed, name in enumerate(("new-1", "new-2", "new-3"))
        ]
        assert memory.merge(ids[1], ids[0], "shape distance 0.12") == "new-1"
        assert memory.group("new-1") == ids[:2]
        merged = memory.episode_summary(ids[1])
        # the note keeps where the episode was cut from and says what it was merged with
        assert merged.note == f"steps 10-33; merged with episode {ids[0]} (shape distance 0.12)"
        assert memory.episode(ids[1]).sequence().pattern == "new-1"
        memory.split(ids[1], "new-2")
        assert memory.group("new-1") == ids[:1] and memory.group("new-2") == [ids[1]]
        assert memory.episode_summary(ids[1]).note.endswith("; split from new-1")
        with pytest.raises(DataFileError, match="taken"):
            memory.split(ids[1], "new-3")  # another episode's movement
        # a learned episode belongs to a model version: neither merged nor split
        memory.set_status(ids[2], "learned")
        with pytest.raises(DataFileError, match="learned"):
            memory.merge(ids[2], ids[0])
        with pytest.raises(DataFileError, match="learned"):
            memory.split(ids[2], "new-9")
        # but a kept episode may join a learned movement (more data for it)
        assert memory.merge(ids[0], ids[2]) == "new-3"
        assert memory.group("new-3") == [ids[0], ids[2]]
        assert memory.group("new-3", ("learned",)) == [ids[2]]
        with pytest.raises(MemoryFileError, match="no episode 99"):
            memory.merge(99, ids[0])


def test_bad_movements_and_names_are_refused_before_anything_is_written(tmp_path):
    sensory, motor = _movement()
    with MemoryStore(tmp_path / "m.npz") as memory:
        bad = sensory.copy()
        bad[3, 1] = np.nan
        with pytest.raises(DataFileError, match="NaN"):
            memory.add_episode(bad, motor, source="s", model="m", pattern="p", n_cycles=1)
        with pytest.raises(DataFileError, match="pattern name"):
            memory.add_episode(sensory, motor, source="s", model="m", pattern="<b>", n_cycles=1)
        with pytest.raises(DataFileError, match="status"):
            memory.add_episode(
                sensory, motor, source="s", model="m", pattern="p", n_cycles=1, status="maybe"
            )
        assert memory.episodes() == []


def test_foreign_damaged_and_newer_files_are_refused_clearly(tmp_path):
    text = tmp_path / "text.memory.sqlite"
    text.write_text("hello\n")
    with pytest.raises(MemoryFileError, match="not an SQLite database"):
        MemoryStore(text).open()
    foreign = tmp_path / "foreign.memory.sqlite"
    with sqlite3.connect(foreign) as db:
        db.execute("CREATE TABLE t (x)")
    with pytest.raises(MemoryFileError, match="another program's SQLite database"):
        MemoryStore(foreign).open()
    newer = tmp_path / "newer.memory.sqlite"
    MemoryStore(newer).open().close()
    with sqlite3.connect(newer) as db:
        db.execute("PRAGMA user_version = 99")
    with pytest.raises(MemoryFileError, match="newer than this rnnpb reads"):
        MemoryStore(newer).open()
    damaged = tmp_path / "damaged.memory.sqlite"
    with MemoryStore(damaged) as memory:
        for k in range(20):
            memory.add_episode(*_movement(200, k), source="s", model="m", pattern="p", n_cycles=4)
    data = bytearray(damaged.read_bytes())
    data[len(data) // 2 : len(data) // 2 + 4096] = os.urandom(4096)
    damaged.write_bytes(bytes(data))
    with pytest.raises(MemoryFileError, match="damaged"):
        with MemoryStore(damaged) as memory:
            for summary in memory.episodes():
                memory.episode(summary.id)
    with pytest.raises(MemoryFileError, match="no such memory file"):
        MemoryStore(tmp_path / "missing.memory.sqlite", create=False).open()
    assert issubclass(MemoryFileError, RnnpbError)


_WRITER = textwrap.dedent("""
    import sys
    import numpy as np
    from rnnpb.memory import MemoryStore
    rng = np.random.default_rng(int(sys.argv[2]))
    with MemoryStore(sys.argv[1]) as memory:
        print("ready", flush=True)
        while True:
            n = int(rng.integers(12, 400))
            sensory, motor = rng.uniform(0, 1, (n, 4)), rng.uniform(-1, 1, (n, 8))
            episode = memory.add_episode(sensory, motor, source="kill test", model="m",
                                         pattern="p", n_cycles=3)
            print(episode, n, flush=True)
""")


def test_kill_9_mid_write_loses_no_committed_episode_and_never_half_of_one(tmp_path):
    path = tmp_path / "m.memory.sqlite"
    committed: dict[int, int] = {}
    rng = np.random.default_rng(0)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    for run in range(10):
        writer = subprocess.Popen(
            [sys.executable, "-c", _WRITER, str(path), str(run)],
            stdout=subprocess.PIPE,
            text=True,
            env=env,
        )
        assert writer.stdout is not None
        assert writer.stdout.readline().strip() == "ready"
        time.sleep(float(rng.uniform(0.01, 0.15)))
        writer.send_signal(signal.SIGKILL)
        out, _ = writer.communicate()
        # A line the kill cut short is an episode committed but not reported (checked below
        # as any other unreported one): only whole lines count.
        for line in out.split("\n")[:-1]:
            episode, n = line.split()
            committed[int(episode)] = int(n)
    assert len(committed) > 10  # the writer got some episodes in before each kill
    with sqlite3.connect(path) as db:
        assert db.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
    with MemoryStore(path, create=False) as memory:
        stored = {e.id: e.n_steps for e in memory.episodes()}
        # every episode reported committed is there, with its length; any other one (committed
        # in the instant before the kill, not yet reported) is whole too
        assert committed.items() <= stored.items()
        for episode_id in stored:
            episode = memory.episode(episode_id)
            assert episode.sensory.shape == (stored[episode_id], 4)
