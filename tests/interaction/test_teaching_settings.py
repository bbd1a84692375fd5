"""A --config file's teaching tables reach the episode cutter and teaching's consolidations."""

from __future__ import annotations

import os
import pickle

import pytest

from rnnpb.cli import main
from rnnpb.interaction.background import teaching_consolidation
from rnnpb.interaction.episodes import TeachingConfig
from rnnpb.model import TrainedModel
from rnnpb.models import SHIPPED_MODEL

RESEARCH = """\
[teaching.cutter]
episode_cycles = 5
[teaching]
hold_old_pb = "all"
[consolidation]
rehearsal_steps = 40
"""


@pytest.fixture()
def research(tmp_path):
    path = tmp_path / "research.toml"
    path.write_text(RESEARCH)
    return path


def test_interact_learn_gives_teaching_the_config_file_s_tables(research, tmp_path, monkeypatch):
    import rnnpb.interaction.teaching as teaching

    teachers = []
    jobs = []

    class Recorded(teaching.Teacher):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            teachers.append(self)

    monkeypatch.setattr(teaching, "Teacher", Recorded)
    monkeypatch.setattr(teaching, "BackgroundConsolidation", lambda *a: jobs.append(a))
    out = tmp_path / "run"
    args = ["interact", "--model", str(SHIPPED_MODEL), "--source", "scenario:held:1"]
    assert (
        main(
            [
                *args,
                "--learn",
                "--steps",
                "4",
                "--out",
                str(out),
                "--no-progress",
                "--config",
                str(research),
            ]
        )
        == 0
    )
    (teacher,) = teachers
    # [teaching.cutter]: the cutter's tuned value; the rest stays the preset's.
    cutter = teacher.keeper.cutter.config
    assert cutter == TeachingConfig().with_tuning(episode_cycles=5)
    # [teaching] and [consolidation]: the consolidation a confirmed episode runs...
    model = TrainedModel.load(SHIPPED_MODEL)
    config = teacher.consolidation(model)
    policy = teaching_consolidation(model)
    assert (config.hold_old_pb, config.rehearsal_steps) == ("all", 40)
    assert (policy.hold_old_pb, policy.rehearsal_steps) != ("all", 40)
    assert config.new_pb_start == policy.new_pb_start and config.train == policy.train
    # ...which is what the worker process is given to run.
    teacher.pending = [1]
    teacher.confirm()
    (job,) = jobs
    assert teaching_consolidation(model, *job[4:]) == config
    overrides = job[5]  # the file as it was read, pickled for the process as it is
    assert overrides.origin == str(research) and pickle.loads(pickle.dumps(overrides)) == overrides
    assert overrides.tables["teaching"] == {"hold_old_pb": "all"}
    assert overrides.tables["consolidation"] == {"rehearsal_steps": 40}


def test_teaching_tables_need_learn(research, tmp_path, capsys):
    args = ["interact", "--model", str(SHIPPED_MODEL), "--source", "scenario:held:1"]
    assert main([*args, "--out", str(tmp_path / "run"), "--config", str(research)]) == 2
    err = capsys.readouterr().err
    assert "apply with --learn" in err and str(research) in err


@pytest.mark.skipif(not hasattr(os, "sched_setaffinity"), reason="no CPU affinity here")
def test_a_consolidation_starts_its_backend_on_one_core_then_may_move(monkeypatch):
    """XLA sizes its thread pools when the backend starts: one core then, and every core the
    process may use afterwards, so that two consolidations started on one core do not share
    it to their end."""
    import jax

    from rnnpb.interaction import background

    allowed = os.sched_getaffinity(0)
    during: list[set[int]] = []
    monkeypatch.setattr(jax, "devices", lambda: during.append(os.sched_getaffinity(0)))
    try:
        background._backend_on_one_core()
        assert len(during) == 1 and during[0] <= allowed
        assert len(during[0]) == 1 or len(allowed) == 1
        assert os.sched_getaffinity(0) == allowed
    finally:
        os.sched_setaffinity(0, allowed)
