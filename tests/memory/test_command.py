"""``rnnpb memory list|show|forget|export`` through the command line."""

from __future__ import annotations

import numpy as np

from rnnpb.cli import main
from rnnpb.memory import MemoryStore
from rnnpb.sequences import read_sequence_files


def test_list_show_forget_export(tmp_path, capsys):
    model = tmp_path / "m.npz"
    rng = np.random.default_rng(0)
    with MemoryStore(model) as memory:
        ids = [
            memory.add_episode(
                rng.uniform(0, 1, (24, 4)),
                rng.uniform(-1, 1, (24, 8)),
                source="synthetic:4",
                model=str(model),
                pattern=f"new-{k}",
                n_cycles=2,
            )
            for k in (1, 2)
        ]
    assert main(["memory", "list", str(model)]) == 0
    printed = capsys.readouterr().out
    assert "2 episodes" in printed and "new-1" in printed and "synthetic:4" in printed
    assert main(["memory", "show", str(model), str(ids[0])]) == 0
    assert "24 steps, 2 whole cycles" in capsys.readouterr().out
    assert main(["memory", "export", str(model), "--out", str(tmp_path / "out")]) == 0
    sequences = read_sequence_files([tmp_path / "out"])
    assert sorted(s.pattern for s in sequences) == ["new-1", "new-2"]
    assert main(["memory", "forget", str(tmp_path / "m.memory.sqlite"), str(ids[1])]) == 0
    capsys.readouterr()
    assert main(["memory", "list", str(model)]) == 0
    assert "1 episode\n" in capsys.readouterr().out
    # an episode that is not there, a file that is not one: one line, exit 2
    assert main(["memory", "show", str(model), "99"]) == 2
    assert "no episode 99" in capsys.readouterr().err
    (tmp_path / "x.memory.sqlite").write_text("not a database")
    assert main(["memory", "list", str(tmp_path / "x.memory.sqlite")]) == 2
    assert "not an SQLite database" in capsys.readouterr().err


def test_merge_and_split_through_the_command_line(tmp_path, capsys):
    from rnnpb.demonstrator import demonstration

    model = tmp_path / "m.npz"
    with MemoryStore(model) as memory:
        ids = [
            memory.add_episode(
                shown.sensory,
                shown.motor,
                source="synthetic",
                model=str(model),
                pattern=f"new-{k}",
                n_cycles=3,
            )
            for k, shown in enumerate(
                (demonstration("2", np.random.default_rng(seed), 36) for seed in (1, 2)), 1
            )
        ]
    assert main(["memory", "merge", str(model), str(ids[1]), str(ids[0])]) == 0
    printed = capsys.readouterr().out
    # two draws of one shape: near in shape (the keeper merges below 0.43)
    distance = float(printed.split("shape distance ")[1].rstrip(")\n"))
    assert distance < 0.3 and "pattern new-1, 2 performances" in printed
    assert main(["memory", "list", str(model)]) == 0
    listed = capsys.readouterr().out
    assert "new-1: 2 performances" in listed and f"merged with episode {ids[0]}" in listed
    assert main(["memory", "split", str(model), str(ids[1])]) == 0
    assert f"episode {ids[1]} split from new-1: now pattern new-2" in capsys.readouterr().out
    assert main(["memory", "list", str(model)]) == 0
    listed = capsys.readouterr().out
    assert "new-1: 1 performance\n" in listed and "split from new-1" in listed
