"""The consolidate and info commands on a user's own files."""

import numpy as np
import pytest

from rnnpb import _interrupt
from rnnpb.cli import main
from rnnpb.model import TrainConfig, TrainedModel, train
from rnnpb.sequences import write_sequence

from .synthetic import LIMITS, make_sequences


@pytest.fixture(scope="module")
def two_kinds():
    """The synthetic set's first two kinds and the model learned on them (once per file)."""
    old = make_sequences(n_steps=24, kinds=(0, 1))
    return old, train(old, LIMITS, config=TrainConfig.fast(iterations=100))


@pytest.fixture()
def files(two_kinds, tmp_path, monkeypatch):
    """A two-pattern model of the synthetic set, its data and a third pattern's files."""
    monkeypatch.setattr("rnnpb.robot.JOINT_LIMITS", LIMITS)
    old, model = two_kinds
    model.save(tmp_path / "m.npz")
    for directory, sequences in (("old", old), ("new", make_sequences(n_steps=24, kinds=(2,)))):
        for i, seq in enumerate(sequences):
            write_sequence(tmp_path / directory / f"p{seq.pattern}_{i % 2 + 1}.csv", seq)
    return tmp_path


def test_consolidate_then_info(files, capsys):
    out = files / "m2.npz"
    assert (
        main(
            [
                "consolidate",
                "--model",
                str(files / "m.npz"),
                "--add",
                str(files / "new"),
                "--out",
                str(out),
                "--iterations",
                "60",
                "--no-progress",
            ]
        )
        == 0
    )
    assert "patterns 0, 1, 2" in capsys.readouterr().out
    grown = TrainedModel.load(out)
    assert grown.patterns == ("0", "1", "2")
    # The consolidation policy's choices for adding patterns, recorded.
    details = grown.history[-1].details
    assert (details["hold_old_pb"], details["new_pb_start"]) == ("first-half", "farthest")
    assert (
        main(
            [
                "consolidate",
                "--model",
                str(out),
                "--add",
                str(files / "new"),
                "--out",
                str(files / "m3.npz"),
                "--no-progress",
            ]
        )
        == 2
    )  # pattern 2 is learned now
    assert "'2' already learned" in capsys.readouterr().err
    assert main(["info", str(out)]) == 0
    text = capsys.readouterr().out
    assert "learning: fast preset in its first training; last step, adam" in text
    assert "on-line regression: ungated (the model was learned with Adam" in text
    assert "0. train: learned 0, 1" in text and "1. rehearsal: learned 2 from m.npz" in text
    assert "4 PB, 40 hidden, 30 context" in text
    # The consolidated model keeps the old patterns' taught hands and adds the new one's.
    assert "recognition: with the hands as taught (6 sequence(s)" in text


def test_the_command_shows_no_ablation_switch_and_names_its_methods(files, capsys):
    with pytest.raises(SystemExit):
        main(["consolidate", "--help"])
    text = capsys.readouterr().out
    for switch in ("--hold-old-pb", "--new-pb-start", "--rehearsal-target"):
        assert switch not in text
    assert "--config FILE" in text and "[consolidation]" in text
    for method in ("rehearsal", "finetune", "replay", "scratch"):
        assert f"  {method}  " in text
    args = ["consolidate", "--model", str(files / "m.npz"), "--add", str(files / "new")]
    assert main([*args, "--out", str(files / "x.npz"), "--method", "forget"]) == 2
    error = capsys.readouterr().err
    assert "method must be one of rehearsal, finetune, replay, scratch, got 'forget'" in error
    with pytest.raises(SystemExit):
        main([*args, "--out", str(files / "x.npz"), "--hold-old-pb", "all"])
    assert "unrecognized arguments: --hold-old-pb" in capsys.readouterr().err


def test_a_config_file_sets_what_the_switches_did(files, capsys):
    config = files / "ablation.toml"
    config.write_text('[consolidation]\nhold_old_pb = "off"\nnew_pb_start = "centre"\n')
    args = ["consolidate", "--model", str(files / "m.npz"), "--add", str(files / "new")]
    out = files / "c.npz"
    assert main([*args, "--out", str(out), "--iterations", "20", "--no-progress",
                 "--config", str(config)]) == 0  # fmt: skip
    details = TrainedModel.load(out).history[-1].details
    assert (details["hold_old_pb"], details["new_pb_start"]) == ("off", "centre")
    capsys.readouterr()
    config.write_text("[teaching]\niterations = 5\n")
    assert main([*args, "--out", str(files / "t.npz"), "--config", str(config)]) == 2
    assert "does not apply to rnnpb consolidate" in capsys.readouterr().err
    config.write_text("[consolidation]\nhold = 1\n")
    assert main([*args, "--out", str(files / "t.npz"), "--config", str(config)]) == 2
    assert "ablation.toml: unknown setting 'hold'" in capsys.readouterr().err
    assert not (files / "t.npz").exists()


def test_replay_takes_the_original_data(files, capsys):
    args = [
        "consolidate",
        "--model",
        str(files / "m.npz"),
        "--add",
        str(files / "new"),
        "--out",
        str(files / "r.npz"),
        "--method",
        "replay",
        "--iterations",
        "20",
        "--no-progress",
    ]
    assert main(args) == 2
    assert "needs the original training data" in capsys.readouterr().err
    assert main([*args, "--replay-data", str(files / "old")]) == 0
    # Written to CSV with six decimals, the data differ from those learned: recorded, said.
    assert "the original data differ" in capsys.readouterr().out
    entry = TrainedModel.load(files / "r.npz").history[-1]
    assert entry.method == "replay" and entry.details["replay_data_matches_record"] is False


def test_bad_files_are_refused_in_one_line(files, capsys):
    bad = files / "bad.csv"
    bad.write_text("step,lhy,lhz\n0,0.5,0.5\n1,0.5,0.5\n")
    assert (
        main(
            [
                "consolidate",
                "--model",
                str(files / "m.npz"),
                "--add",
                str(bad),
                "--out",
                str(files / "x.npz"),
            ]
        )
        == 2
    )
    assert "missing column(s)" in capsys.readouterr().err
    assert (
        main(
            [
                "consolidate",
                "--model",
                str(files / "old" / "p0_1.csv"),
                "--add",
                str(files / "new"),
                "--out",
                str(files / "x.npz"),
            ]
        )
        == 2
    )
    assert capsys.readouterr().err.startswith("rnnpb: error:")
    assert main(["info", str(bad)]) == 2
    assert not (files / "x.npz").exists()


def test_an_interrupted_consolidation_leaves_the_model_and_resumes(files, capsys, monkeypatch):
    before = (files / "m.npz").read_bytes()
    args = [
        "consolidate",
        "--model",
        str(files / "m.npz"),
        "--add",
        str(files / "new"),
        "--out",
        str(files / "m.npz"),
        "--iterations",
        "300",
        "--checkpoint-every",
        "100",
        "--no-progress",
    ]
    calls = []
    real_check = _interrupt.check

    def ctrl_c_at_the_second_chunk() -> None:
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt
        real_check()

    monkeypatch.setattr(_interrupt, "check", ctrl_c_at_the_second_chunk)
    assert main(args) == 130
    assert (files / "m.npz").read_bytes() == before  # the old model untouched
    assert (files / "m.checkpoint.npz").exists()
    monkeypatch.setattr(_interrupt, "check", real_check)
    assert main([*args, "--resume"]) == 0
    grown = TrainedModel.load(files / "m.npz")
    assert grown.patterns == ("0", "1", "2")
    # Resumed from the checkpoint at 100: chunks end at the old PBs' release (150, the first
    # half's end by default) and at the checkpoints (200), and the run at 300.
    assert [i for i, _ in grown.meta["training"]["history"]] == [150, 200, 300]
    assert np.all(np.isfinite(grown.sequence_pb))


def _recognised(model, segments, seed=3):
    """What the mirror system recognises over the last half of each segment of a user's
    stream (the most frequent answer)."""
    from rnnpb.demonstrator import make_scenario
    from rnnpb.model import MirrorSystem

    scenario = make_scenario(segments, seed=seed)
    mirror = MirrorSystem(model)
    answers = [mirror.step(row).recognised for row in scenario.sensory]
    out, start = [], 0
    for _, n in segments:
        late = answers[start + n // 2 : start + n]
        out.append(max(set(late), key=late.count))
        start += n
    return out


def test_add_to_grows_a_pattern_without_forgetting_the_others(set1_model, tmp_path, capsys):
    from rnnpb.demonstrator import demonstration

    set1_model.save(tmp_path / "set1.npz")
    # another draw of pattern 2, in a file that names it otherwise: --add-to says whose it is
    take = demonstration("2", np.random.default_rng(11), 48)
    write_sequence(tmp_path / "take.csv", take.__class__(take.sensory, take.motor, "again"))
    out = tmp_path / "grown.npz"
    arguments = ["consolidate", "--model", str(tmp_path / "set1.npz"), "--out", str(out)]
    assert main([*arguments, "--add-to", "2", str(tmp_path / "take.csv"), "--iterations", "60",
                 "--no-progress"]) == 0  # fmt: skip
    assert "growing 1 sequence(s) of pattern(s) 2 in" in capsys.readouterr().out
    grown = TrainedModel.load(out)
    assert grown.patterns == set1_model.patterns
    assert grown.sequence_patterns.count("2") == set1_model.sequence_patterns.count("2") + 1
    entry = grown.history[-1]
    assert entry.method == "rehearsal" and entry.details["grown"] == ["2"]
    # the new sequence started where pattern 2 is, and stays near it
    new_pb = grown.sequence_pb[-1]
    others = [p for p in grown.patterns if p != "2"]
    assert np.linalg.norm(new_pb - grown.pattern_pb["2"]) < min(
        np.linalg.norm(new_pb - grown.pattern_pb[p]) for p in others
    )
    # every pattern is still recognised as itself on a user's stream
    segments = [(p, 30) for p in grown.patterns]
    assert _recognised(grown, segments) == list(grown.patterns)
    # a name the model does not hold, or no file: one line, exit 2
    assert main([*arguments, "--add-to", "9", str(tmp_path / "take.csv")]) == 2
    assert "holds no pattern '9'" in capsys.readouterr().err
    assert main([*arguments, "--add-to", "2"]) == 2
    assert "--add-to needs a pattern name and at least one file" in capsys.readouterr().err
