"""Fixtures of the dashboard tests: one small learned model (the shipped one) and one running
server."""

from __future__ import annotations

import pytest

TEST_DT = 0.05
"""The tests run the loop eight times faster than the paper's 0.4 s step."""


@pytest.fixture(scope="session")
def model_dir(set1_model_dir, tmp_path_factory):
    """Learning set 1 learned with the fast preset (``TrainConfig.fast()``, seed 0), in a
    folder of the dashboard tests' own: they put files beside it."""
    import shutil

    folder = tmp_path_factory.mktemp("models")
    shutil.copy(set1_model_dir / "set1.npz", folder / "set1.npz")
    return folder


@pytest.fixture(scope="session")
def model(model_dir):
    from rnnpb.model import TrainedModel

    return TrainedModel.load(model_dir / "set1.npz")


@pytest.fixture(scope="session")
def server(model_dir, tmp_path_factory):
    """The dashboard on a free loopback port, its model compiled; shut down at the end."""
    import time

    from rnnpb.web import DashboardServer, find_models

    dashboard = DashboardServer(
        find_models(model_dir),
        host="127.0.0.1",
        port=0,
        dt=TEST_DT,
        workdir=tmp_path_factory.mktemp("sessions"),
        games_dir=tmp_path_factory.mktemp("games"),
    )
    dashboard.start()
    try:
        deadline = time.monotonic() + 90
        while dashboard.session.mirror is None or dashboard.session.loading:
            assert time.monotonic() < deadline, "the model did not load within 90 s"
            time.sleep(0.05)
        yield dashboard
    finally:
        dashboard.stop()
