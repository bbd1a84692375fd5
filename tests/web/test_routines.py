"""The dashboard's routine level: the routine file learned over the running model follows the
interaction and the step messages say the routine and the movement it expects next; a file
over another model is named in the state, not used, and `rnnpb serve` refuses a file learned
over none of the models it offers."""

from __future__ import annotations

import json
import threading
import time

import pytest

from rnnpb.demonstrator import routine_scenario
from rnnpb.model.routines import RoutineLearning, learn_routines

FAST_DT = 0.02
"""The shortest step the dashboard allows: the routine runs take a hundred steps."""
DANCE = [("1", 3), ("3", 2), ("2", 4)]
WAVE = [("2", 2), ("3", 3), ("1", 3)]


@pytest.fixture(scope="module")
def routine_file(model, tmp_path_factory):
    recordings = {
        "dance": [routine_scenario(DANCE, seed=201).sensory],
        "wave": [routine_scenario(WAVE, seed=201).sensory],
    }
    path = tmp_path_factory.mktemp("routines") / "dance.routines.npz"
    learn_routines(model, recordings, RoutineLearning(iterations=1500)).save(path)
    return path


def _perform(models, routines, parts, timeout=60.0):
    """A session that performs ``parts`` ([(pattern, steps)...]) with the demonstrator; its
    state and step messages."""
    from rnnpb.web import Session

    session = Session(models, dt=FAST_DT, routines=routines)
    steps, done = [], threading.Event()
    bounds = [sum(n for _, n in parts[: i + 1]) for i in range(len(parts))]

    def on_message(text: str) -> None:
        message = json.loads(text)
        if message["type"] != "step" or done.is_set():
            return
        steps.append(message)
        n = len(steps)
        if n >= bounds[-1]:
            done.set()
        elif n in bounds:
            session.submit({"type": "pattern", "pattern": parts[bounds.index(n) + 1][0]})

    session.subscribe(on_message)
    session.start()
    try:
        deadline = time.monotonic() + timeout
        while session.mirror is None or session.loading:
            assert time.monotonic() < deadline, "the model did not load"
            time.sleep(0.05)
        session.submit({"type": "pattern", "pattern": parts[0][0]})
        session.submit({"type": "control", "action": "start"})
        assert done.wait(timeout), f"{len(steps)} steps in {timeout} s"
        return session.state(), steps
    finally:
        session.close()


def test_the_routine_is_recognised_and_the_next_movement_said(model_dir, routine_file):
    parts = [("1", 36), ("3", 24), ("2", 30)]
    state, steps = _perform({"set1": model_dir / "set1.npz"}, [routine_file], parts)
    assert state["routines"]["on"]
    assert "dance.routines.npz" in state["routines"]["note"]
    assert all("routine" in s for s in steps)
    said = [(s["routine"], s["anticipated"]) for s in steps]
    # In the second movement the routine is known and the third is expected next.
    second = said[40:58]
    assert sum(r == "dance" and a == "2" for r, a in second) >= len(second) // 2, second
    assert not any(r == "wave" for r, _ in said[40:])


def test_a_routine_file_over_another_model_is_named_and_not_used(
    model_dir, routine_file, tmp_path, capsys
):
    from dataclasses import replace

    import numpy as np

    from rnnpb.cli import main
    from rnnpb.model import TrainedModel

    lower = TrainedModel.load(model_dir / "set1.npz")
    params = lower.params._replace(b_h=np.asarray(lower.params.b_h) + 0.01)
    replace(lower, params=params).save(tmp_path / "other.npz")
    state, steps = _perform({"other": tmp_path / "other.npz"}, [routine_file], [("1", 5)])
    assert not state["routines"]["on"]
    assert "dance.routines.npz" in state["routines"]["note"]
    assert not any("routine" in s for s in steps)
    # The server refuses it at once, in one line.
    assert main(["serve", "--model", str(tmp_path / "other.npz"), "--port", "0",
                 "--routines", str(routine_file)]) == 2  # fmt: skip
    err = capsys.readouterr().err.strip()
    assert "learned over none of the models offered" in err
    assert len(err.splitlines()) == 1
