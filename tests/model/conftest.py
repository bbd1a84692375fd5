import pytest

from rnnpb.model import TrainConfig, train

from .synthetic import LIMITS, make_sequences


@pytest.fixture(scope="session")
def sequences():
    return make_sequences()


@pytest.fixture(scope="session")
def trained(sequences):
    """The synthetic set learned with the fast preset (about 10 s)."""
    return train(sequences, LIMITS, config=TrainConfig.fast(iterations=2000, seed=0))
