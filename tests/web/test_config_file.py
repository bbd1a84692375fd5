"""``rnnpb serve --config FILE``: the file's tables reach the dashboard's session."""

from __future__ import annotations

import shutil
import time

import pytest

from rnnpb.model import OnlineConfig

from .conftest import TEST_DT

RESEARCH = """\
[online]
surprise_gate = 0.02
[recognition]
switch_steps = 3
[teaching.cutter]
episode_cycles = 5
"""


@pytest.fixture()
def research(tmp_path):
    path = tmp_path / "research.toml"
    path.write_text(RESEARCH)
    return path


def test_a_config_file_s_values_reach_the_session_s_mirror_and_teaching(
    model_dir, model, research, tmp_path
):
    from rnnpb.presets import Overrides
    from rnnpb.web import Session

    folder = tmp_path / "models"
    folder.mkdir()
    shutil.copy(model_dir / "set1.npz", folder / "set1.npz")  # its memory is made beside it
    overrides = Overrides(
        {
            "online": {"surprise_gate": 0.02},
            "recognition": {"switch_steps": 3},
            "teaching.cutter": {"episode_cycles": 5},
        },
        str(research),
    )
    session = Session(
        {"set1.npz": folder / "set1.npz"},
        dt=TEST_DT,
        workdir=tmp_path / "sessions",
        overrides=overrides,
    )
    try:
        session.start()
        deadline = time.monotonic() + 90
        while session.mirror is None or session.loading:
            assert time.monotonic() < deadline, "the model did not load within 90 s"
            time.sleep(0.05)
        chosen = OnlineConfig.for_model(model)
        # The preset's choice for the model, with the file's values over it.
        assert session.mirror.config == chosen.config.with_tuning(surprise_gate=0.02)
        assert session.mirror.recognition == chosen.recognition.with_tuning(switch_steps=3)
        teacher = session.teaching.teacher
        assert teacher is not None and teacher.keeper.cutter.config.episode_cycles == 5
    finally:
        session.close()


def test_serve_reads_the_config_file_before_it_serves(model_dir, research, monkeypatch, capsys):
    import rnnpb.web
    from rnnpb.cli import main

    started = []

    class Server:
        """What `rnnpb serve` does with the dashboard, without serving."""

        def __init__(self, models, **kwargs):
            self.session = type("SessionSettings", (), {})()
            self.url = "http://127.0.0.1:0"

        def start(self):
            started.append(self.session)

        def wait(self):
            pass

        def stop(self):
            pass

    monkeypatch.setattr(rnnpb.web, "DashboardServer", Server)
    args = ["serve", "--model", str(model_dir), "--port", "0", "--config", str(research)]
    assert main(args) == 0
    (session,) = started
    assert session.overrides.origin == str(research)
    assert session.overrides.tables["online"] == {"surprise_gate": 0.02}
    assert f"values from {research}" in capsys.readouterr().out
    # A table the dashboard does not read is one line, before anything is served.
    research.write_text("[learning]\nlearning_rate = 0.02\n")
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "[learning] does not apply to rnnpb serve" in err and err.count("\n") == 1
    assert len(started) == 1
