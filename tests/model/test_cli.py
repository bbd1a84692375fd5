"""The train, generate and bench commands on a user's own files."""

import json
import subprocess
import sys

import numpy as np
import pytest

from rnnpb.cli import main
from rnnpb.model import TrainedModel
from rnnpb.sequences import read_sequences, write_sequence

from .synthetic import make_sequences


@pytest.fixture()
def data_dir(tmp_path):
    directory = tmp_path / "data"
    for i, seq in enumerate(make_sequences(n_steps=30)):
        # No pattern column: the file name names the pattern.
        write_sequence(
            directory / f"pat{seq.pattern}_{i % 2 + 1}.csv", seq, with_pattern_column=False
        )
    return directory


def test_train_then_generate(data_dir, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("rnnpb.robot.JOINT_LIMITS", np.array([[-2.0, 2.0]] * 8))
    model_path = tmp_path / "model.npz"
    assert (
        main(
            [
                "train",
                "--data",
                str(data_dir),
                "--out",
                str(model_path),
                "--preset",
                "fast",
                "--iterations",
                "300",
                "--no-progress",
                "--allow-unsafe",  # made-up joint angles, not robot postures
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert "pattern pat0" in out and "mean squared error" in out
    model = TrainedModel.load(model_path)
    assert model.patterns == ("pat0", "pat1", "pat2")
    # The finished model holds what the checkpoint did: it is removed unless asked for.
    assert not (tmp_path / "model.checkpoint.npz").exists()
    kept = tmp_path / "kept.npz"
    assert (
        main(
            [
                "train",
                "--data",
                str(data_dir),
                "--out",
                str(kept),
                "--preset",
                "fast",
                "--iterations",
                "100",
                "--no-progress",
                "--keep-checkpoint",
                "--allow-unsafe",
            ]
        )
        == 0
    )
    assert (tmp_path / "kept.checkpoint.npz").exists()

    gen_path = tmp_path / "gen.csv"
    assert (
        main(
            [
                "generate",
                "--model",
                str(model_path),
                "--pattern",
                "pat1",
                "--steps",
                "40",
                "--out",
                str(gen_path),
            ]
        )
        == 0
    )
    generated = read_sequences(gen_path)[0]
    assert generated.n_steps == 40 and generated.pattern == "pat1"
    assert (
        main(
            [
                "generate",
                "--model",
                str(model_path),
                "--pb",
                "0.1,0.2,0.3,0.4",
                "--steps",
                "10",
                "--out",
                str(tmp_path / "pb.csv"),
            ]
        )
        == 0
    )


def test_errors_are_one_line_and_nonzero(tmp_path, capsys):
    assert (
        main(
            [
                "generate",
                "--model",
                str(tmp_path / "none.npz"),
                "--pattern",
                "x",
                "--out",
                str(tmp_path / "o.csv"),
            ]
        )
        == 2
    )
    err = capsys.readouterr().err
    assert err.startswith("rnnpb: error:") and "no such file" in err
    assert "Traceback" not in err
    bad = tmp_path / "bad.csv"
    bad.write_text("step,lhy\n0,0.5\n")
    assert main(["train", "--data", str(bad), "--out", str(tmp_path / "m.npz")]) == 2
    assert "missing column(s)" in capsys.readouterr().err


def test_help_names_every_command(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    out = capsys.readouterr().out
    for command in ("train", "generate", "bench", "data"):
        assert command in out


def test_bench_prints_and_writes_its_figures(tmp_path):
    path = tmp_path / "bench.json"
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "rnnpb.cli",
            "bench",
            "--steps",
            "20",
            "--reference-steps",
            "1",
            "--no-tracking",
            "--json",
            str(path),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    figures = json.loads(path.read_text())
    for key in (
        "train_iteration_ms_median",
        "train_iteration_jax_ms_median",
        "online_step_ms_median",
        "online_step_ms_p99",
        "online_step_without_phase_restarts_ms_median",
        "online_step_reference_ms_median",
        "dyad_step_ms_median",
        "dyad_step_side_by_side_ms_median",
        "dyad_step_one_agent_ms_median",
        "online_step_paper_ms_p99",
        "online_step_default_guarded_ms_median",
        "online_step_batched_per_session_ms_median",
        "online_batched_step_vs_default",
        "online_step_two_level_ms_median",
        "online_step_two_level_ms_p99",
        "online_step_two_level_follower_ms_median",
        "online_step_two_level_follower_ms_p99",
    ):
        assert figures[key] > 0
    # The routine level's part is a part of the two-level step, which stays within dt.
    assert 0 < figures["online_step_two_level_follower_share"] < 1
    assert figures["online_step_budget_ms"] == 400.0
    assert figures["online_step_two_level_ms_p99"] < figures["online_step_budget_ms"]
    assert "two levels (routines, with the prior)" in result.stdout
    assert "budget: the step period dt, 400 ms" in result.stdout
    assert figures["online_step_paper_vs_paper"] == 1.0
    assert "sessions in one call" in result.stdout
    # Two agents are timed in a process of their own, which may use two cores.
    assert 1 <= figures["dyad_cores"] <= 2
    assert "two coupled agents" in result.stdout and "side by side" in result.stdout
    # The float32 step with its native loop is faster than the float64 reference.
    assert figures["online_step_ms_median"] < figures["online_step_reference_ms_median"]
    assert "on-line step" in result.stdout


def test_train_refuses_data_that_would_teach_a_collision(tmp_path, capsys):
    from rnnpb.demonstrator import learning_set
    from rnnpb.robot import inverse_kinematics
    from rnnpb.sequences import Sequence

    data = tmp_path / "data"
    sequences = learning_set(1, samples_per_pattern=1, n_steps=20)
    for seq in sequences:
        write_sequence(data / f"{seq.pattern}_1.csv", seq)
    # Step 7 of pattern 2 puts both hands inside the robot's chest.
    chest = inverse_kinematics(np.array([[[0.02, 0.03, 0.33], [0.02, -0.03, 0.33]]])).joints[0]
    bad = sequences[1]
    motor = bad.motor.copy()
    motor[7] = chest
    write_sequence(data / f"{bad.pattern}_1.csv", Sequence(bad.sensory, motor, bad.pattern))
    out = tmp_path / "m.npz"
    assert main(["train", "--data", str(data), "--out", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert f"{data / (bad.pattern + '_1.csv')} (lines 2-21), step 7: collision:" in err
    assert "--allow-unsafe" in err and not out.exists()
    args = ["--preset", "fast", "--iterations", "20", "--no-progress", "--allow-unsafe"]
    assert main(["train", "--data", str(data), "--out", str(out), *args]) == 0
    assert "1 colliding" in capsys.readouterr().out  # at the pose (the way back is clear)
    assert TrainedModel.load(out).meta["data_safety"]["collision"] >= 1
