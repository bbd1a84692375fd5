"""The test suite makes the process-wide choices a library leaves to its user (importing rnnpb
sets none): XLA's loop setting, before the first JAX computation of the test process, and the
compiled programs kept on disk for the next test process (rnnpb._xla.compilation_cache).

It also shares the one small model most tests of the world around the network need: learning
set 1 learned with the fast preset. That is the model shipped with the package
(``rnnpb.models.SHIPPED_MODEL``, ``scripts/train_shipped_model.py``), so no test process
learns it again."""

import os
import shutil
from pathlib import Path

import pytest

import rnnpb
from rnnpb import _xla

rnnpb.configure_xla()
_xla.compilation_cache()


@pytest.fixture(autouse=True)
def _no_models_from_the_checkout(monkeypatch, tmp_path_factory):
    """A command given no model looks in the working directory first (``models/``,
    ``results/demo/models/``: rnnpb.models.default_model); the suite runs in the checkout,
    where ``make demo`` leaves its models. Here it looks in an empty folder instead, so that a
    test gets the shipped model whatever was run in the checkout before."""
    from rnnpb import models

    empty = tmp_path_factory.getbasetemp() / "no-models-here"
    empty.mkdir(exist_ok=True)
    search = models.default_model
    monkeypatch.setattr(
        models, "default_model", lambda base=None: search(empty if base is None else base)
    )


# The real motion-capture takes: test data under a non-commercial licence, read where they are
# (RNNPB_MOCAP_DIR, else ../shared/data/mocap beside the checkout), never copied into the project.
MOCAP = Path(
    os.environ.get(
        "RNNPB_MOCAP_DIR", Path(__file__).resolve().parents[1].parent / "shared/data/mocap"
    )
)


@pytest.fixture(scope="session")
def mocap_dir() -> Path:
    """The folder of real motion-capture takes; the test skips where there is none."""
    if not MOCAP.is_dir():
        pytest.skip(f"no real motion-capture takes at {MOCAP} (set RNNPB_MOCAP_DIR)")
    return MOCAP


@pytest.fixture(scope="session")
def set1_model_dir(tmp_path_factory):
    """A folder holding learning set 1's fast-preset model as ``set1.npz``: a copy of the
    shipped model, so that what a test writes beside it (versions, memory, safety map) stays
    in the test's folder."""
    from rnnpb.models import SHIPPED_MODEL

    folder = tmp_path_factory.mktemp("set1-model")
    shutil.copy(SHIPPED_MODEL, folder / "set1.npz")
    return folder


@pytest.fixture(scope="session")
def set1_model(set1_model_dir):
    """Learning set 1 (patterns 1, 2, 3) learned with the fast preset, seed 0."""
    from rnnpb.model import TrainedModel

    return TrainedModel.load(set1_model_dir / "set1.npz")


# `make test` hands whole files to its two workers, one at a time in collection order
# (`--dist loadfile --no-loadscope-reorder`), so that a file's shared fixtures (a learned
# model, a running server, a demo run) are made once. The files that take longest go first, so
# that the workers end together rather than one waiting on a long file begun last.
STARTED_FIRST = (
    "experiments/test_demo.py",
    "sweeps/test_sweep.py",
    "experiments/test_incremental_study.py",
    "experiments/test_jobs.py",
    "model/test_online.py",
    "safety/test_safety.py",
    "safety/test_online.py",
    "model/test_cli.py",
    "robustness/test_interrupted_runs.py",
    "web/test_teaching.py",
    "web/test_browser.py",
    "test_import.py",
    "experiments/test_novelty_study.py",
)


def pytest_collection_modifyitems(items):
    def rank(item):
        path = item.nodeid.split("::")[0].removeprefix("tests/")
        return STARTED_FIRST.index(path) if path in STARTED_FIRST else len(STARTED_FIRST)

    items.sort(key=rank)
