"""The test suite makes the process-wide choices a library leaves to its user (importing rnnpb
sets none): XLA's loop setting, before the first JAX computation of the test process, and the
compiled programs kept on disk for the next test process (rnnpb._xla.compilation_cache).

It also shares the one small model most tests of the world around the network need: learning
set 1 learned with the fast preset. That is the model shipped with the package
(``rnnpb.models.SHIPPED_MODEL``, ``scripts/train_shipped_model.py``), so no test process
learns it again."""

import shutil

import pytest

import rnnpb
from rnnpb import _xla

rnnpb.configure_xla()
_xla.compilation_cache()


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
