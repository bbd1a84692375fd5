"""A teaching consolidation's own process: forked from a server that imported JAX ahead, with
the settings of the process that starts it."""

from __future__ import annotations

import math
import multiprocessing

import pytest

from rnnpb.demonstrator import make_scenario
from rnnpb.interaction.background import (
    BackgroundConsolidation,
    process_context,
    start_process_server,
)
from rnnpb.memory import MemoryStore
from rnnpb.model import TrainedModel


def _kept_shape(model, folder) -> tuple[str, list[int]]:
    """The model copied into ``folder`` with a new shape kept twice in its memory."""
    path = folder / "m.npz"
    model.save(path)
    with MemoryStore(path) as memory:
        ids = [
            memory.add_episode(
                scenario.sensory,
                scenario.motor,
                source="scenario",
                model=str(path),
                pattern="new-1",
                n_cycles=3,
            )
            for scenario in (make_scenario([("figure-eight", 36)], seed=s) for s in (1, 2))
        ]
    return str(path), ids


@pytest.mark.skipif(
    "forkserver" not in multiprocessing.get_all_start_methods(), reason="no forkserver here"
)
def test_consolidations_fork_from_a_server_where_the_platform_has_one():
    assert process_context().get_start_method() == "forkserver"


@pytest.mark.parametrize("native", ["0", "1"])
def test_a_consolidation_takes_the_settings_of_the_process_that_starts_it(
    set1_model, tmp_path, monkeypatch, native
):
    # The server starts (and imports JAX) before the setting changes here: the consolidation
    # must still learn the way this process now says.
    start_process_server()
    monkeypatch.setenv("RNNPB_NATIVE", native)
    path, ids = _kept_shape(set1_model, tmp_path)
    out = tmp_path / "m.v2.npz"
    job = BackgroundConsolidation(path, path, ids, out, iterations=20)
    state = job.wait(120.0)
    assert state.state == "done", state.message
    assert math.isfinite(state.cpu_s) and 0 < state.cpu_s
    code = TrainedModel.load(out).meta["training"]["code"]
    assert code.startswith("native") if native == "1" else code == "jax"
    assert job.ended or job.wait(5.0).state == "done"


def test_a_failed_consolidation_says_why_and_how_much_cpu_it_took(set1_model, tmp_path):
    path, ids = _kept_shape(set1_model, tmp_path)
    state = BackgroundConsolidation(path, path, [*ids, 999], tmp_path / "v2.npz").wait(120.0)
    assert state.state == "failed" and "999" in state.message
    assert math.isfinite(state.cpu_s)


def test_a_script_that_starts_a_consolidation_unguarded_is_told_why_it_failed(set1_model, tmp_path):
    """The process starts by importing the main script; one that teaches at its top level
    fails there, and the failure says what to change."""
    import subprocess
    import sys

    path, ids = _kept_shape(set1_model, tmp_path)
    script = tmp_path / "teach.py"
    script.write_text(
        "from rnnpb.interaction.background import BackgroundConsolidation\n"
        f"job = BackgroundConsolidation({path!r}, {path!r}, {ids!r}, {path!r} + '.v2.npz', "
        "iterations=5)\n"
        "print('STATE', job.wait(120.0).state, job.state.message)\n"
    )
    run = subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, timeout=300, check=False
    )
    said = [line for line in run.stdout.splitlines() if line.startswith("STATE")]
    assert said and said[0].startswith("STATE failed"), run.stdout + run.stderr
    assert 'if __name__ == "__main__":' in said[0]


def test_a_process_that_ended_after_it_began_is_not_blamed_on_the_script():
    from rnnpb.interaction.background import ended_message

    assert "__main__" not in ended_message(1, heard=True)
    assert "__main__" not in ended_message(-9, heard=False)
    assert "exit code -9" in ended_message(-9, heard=False)
