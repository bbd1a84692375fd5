"""Interrupted commands lose nothing: `rnnpb train` resumes from its last checkpoint to the same
model; `rnnpb interact` stopped by Ctrl-C or killed keeps every flushed step, readable; Ctrl-C
during the first seconds (imports, the first XLA compilation) ends either command cleanly."""

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from rnnpb.interaction import read_session
from rnnpb.model import TrainedModel

from .conftest import CHECKPOINT_EVERY, TRAIN_ITERATIONS


def _rnnpb(*args):
    # Unbuffered: a test waits for a line of output before it interrupts.
    env = {**os.environ, "MUJOCO_GL": "egl", "MPLBACKEND": "Agg", "PYTHONUNBUFFERED": "1"}
    return subprocess.Popen(
        [sys.executable, "-m", "rnnpb.cli", *map(str, args)],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _wait_for(condition, process, timeout=120.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if condition():
            return True
        if process.poll() is not None:
            return condition()
        time.sleep(0.01)
    return False


def _session_rows(path):
    try:
        return max(path.read_bytes().count(b"\n") - 1, 0)
    except FileNotFoundError:
        return 0


@pytest.mark.slow
def test_train_interrupted_then_resumed_matches_uninterrupted(data_dir, model, tmp_path):
    out = tmp_path / "model.npz"
    checkpoint = tmp_path / "model.checkpoint.npz"
    command = [
        "train",
        "--data",
        data_dir,
        "--out",
        out,
        "--preset",
        "fast",
        "--iterations",
        TRAIN_ITERATIONS,
        "--checkpoint-every",
        CHECKPOINT_EVERY,
        "--seed",
        0,
        "--no-progress",
    ]
    first = _rnnpb(*command)
    assert _wait_for(checkpoint.exists, first), first.communicate()
    first.send_signal(signal.SIGINT)
    stdout, stderr = first.communicate(timeout=120)
    assert first.returncode == 130, stderr
    assert stderr.strip().splitlines()[-1] == "rnnpb: interrupted"
    assert "Traceback" not in stderr
    assert not out.exists()  # no half-finished model
    # The checkpoint is a complete archive, not a half-written one.
    assert not list(tmp_path.glob(".*.tmp"))

    second = _rnnpb(*command, "--resume")
    stdout, stderr = second.communicate(timeout=300)
    assert second.returncode == 0, stderr
    resumed = TrainedModel.load(out)
    assert resumed.meta["training"]["iterations"] == TRAIN_ITERATIONS
    # Resuming continues the same computation: the result is the uninterrupted run's.
    for name, value in resumed.params._asdict().items():
        np.testing.assert_allclose(
            value, getattr(model.params, name), rtol=1e-5, atol=1e-6, err_msg=name
        )
    np.testing.assert_allclose(resumed.sequence_pb, model.sequence_pb, atol=1e-5)


@pytest.mark.slow
@pytest.mark.parametrize("how", ["SIGINT", "SIGKILL"])
def test_interact_interrupted_keeps_every_flushed_step(model_file, tmp_path, how):
    out = tmp_path / "run"
    session = out / "session.csv"
    process = _rnnpb(
        "interact",
        "--model",
        _with_step_time(model_file, tmp_path / "fast.npz", 0.02),
        "--source",
        "scenario:held:1",
        "--out",
        out,
        "--paced",
        "--dt",
        "0.02",
    )
    assert _wait_for(lambda: _session_rows(session) >= 15, process), process.communicate()
    before = _session_rows(session)
    process.send_signal(getattr(signal, how))
    stdout, stderr = process.communicate(timeout=120)
    recorded = read_session(session)
    steps = recorded["step"].tolist()
    assert steps == list(range(len(steps))) and len(steps) >= before
    assert np.all(np.isfinite(recorded["lshp"]))
    if how == "SIGINT":
        assert process.returncode == 0, stderr
        assert "interrupted: the recording keeps every step so far" in stdout
        assert (out / "summary.json").exists() and (out / "session.png").exists()
        import json

        summary = json.loads((out / "summary.json").read_text())
        assert summary["loop"]["steps"] == len(steps)
    else:
        assert process.returncode == -signal.SIGKILL
        assert len(steps) < 150  # it really was stopped part-way


def _interrupt_during_startup(command, marker, delays, tmp_path):
    """Start each run, send SIGINT ``delay`` seconds after ``marker`` appears on stdout (None:
    after the start), and return what each run left."""
    runs = []
    for i, delay in enumerate(delays):
        out = tmp_path / f"run-{marker}-{i}"
        out.mkdir()
        process = _rnnpb(*command(out))
        if marker is not None:
            # The banner is printed just before the first XLA compilation begins.
            line = process.stdout.readline()
            assert marker in line, (line, process.communicate())
        time.sleep(delay)
        process.send_signal(signal.SIGINT)
        stdout, stderr = process.communicate(timeout=120)
        assert "Fatal Python error" not in stderr and "Exception ignored" not in stderr, stderr
        assert "Traceback" not in stderr, stderr
        runs.append((process.returncode, stdout, stderr, out))
    return runs


@pytest.mark.slow
def test_ctrl_c_during_the_first_compile_stops_training_cleanly(data_dir, tmp_path):
    # Before SIGINT was held to safe points, 13 of 32 such runs crashed with a segmentation
    # fault (in jaxlib's import, or at exit with an XLA thread still compiling) and 2 ran on.
    def command(out):
        return [
            "train",
            "--data",
            data_dir,
            "--out",
            out / "model.npz",
            "--preset",
            "fast",
            "--iterations",
            100_000,
            "--no-progress",
        ]

    runs = _interrupt_during_startup(command, None, [0.5], tmp_path)
    runs += _interrupt_during_startup(command, "training on", [0.0, 0.3], tmp_path)
    for status, stdout, stderr, out in runs:
        assert status == 130, stderr
        assert stderr.strip().splitlines()[-1] == "rnnpb: interrupted"
        assert "wrote" not in stdout  # it stopped at the first chunk, not at the end
        assert not any(out.iterdir())  # no model, no checkpoint, no temporary file


@pytest.mark.slow
def test_ctrl_c_during_the_first_compile_stops_interact_cleanly(model_file, tmp_path):
    def command(out):
        return ["interact", "--model", model_file, "--source", "scenario:held:1", "--out", out]

    runs = _interrupt_during_startup(command, None, [0.5], tmp_path)
    runs += _interrupt_during_startup(command, "interacting:", [0.0], tmp_path)
    for status, stdout, stderr, out in runs:
        if status == 130 and "interacting:" not in stdout:
            # The signal came before the command began its work (a busy machine still
            # starting Python): the plain Ctrl-C exit, and nothing left half-written.
            assert stderr.strip().splitlines()[-1] == "rnnpb: interrupted", stderr
            assert not list(out.glob(".*"))
            continue
        assert status == 0, stderr
        assert "interrupted: the recording keeps every step so far" in stdout
        recorded = read_session(out / "session.csv")
        steps = recorded["step"].tolist()
        # Stopped after the step in progress: at least that one, not the whole scenario.
        assert 1 <= len(steps) < 150 and steps == list(range(len(steps)))
        import json

        summary = json.loads((out / "summary.json").read_text())
        assert summary["loop"]["steps"] == len(steps)
        assert (out / "session.png").exists()
        assert not list(out.glob(".*"))  # no temporary file left


def _with_step_time(model_file, path, dt):
    """A copy of the model learned, as far as its file says, at ``dt`` (a paced run that fast
    plays only a model of that step)."""
    from dataclasses import replace

    model = TrainedModel.load(model_file)
    replace(model, meta={**model.meta, "dt": dt}).save(path)
    return path
