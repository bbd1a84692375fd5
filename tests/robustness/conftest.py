"""Shared fixtures: one small trained model, learned from sequence files as `rnnpb train` would."""

import pytest

from rnnpb.demonstrator import learning_set
from rnnpb.model import TrainConfig, train
from rnnpb.robot import JOINT_LIMITS
from rnnpb.sequences import read_sequence_files, write_sequence

# The interrupted-and-resumed `rnnpb train` in test_interrupted_runs.py uses these settings, so
# that this model is also its uninterrupted reference.
TRAIN_ITERATIONS = 400
CHECKPOINT_EVERY = 40


@pytest.fixture(scope="session")
def data_dir(tmp_path_factory):
    directory = tmp_path_factory.mktemp("robustness-data")
    for i, sequence in enumerate(learning_set("1")):
        write_sequence(directory / f"p{sequence.pattern}_{i % 2 + 1}.csv", sequence)
    return directory


@pytest.fixture(scope="session")
def model(data_dir):
    config = TrainConfig.fast(
        iterations=TRAIN_ITERATIONS, checkpoint_every=CHECKPOINT_EVERY, seed=0
    )
    return train(read_sequence_files([data_dir]), JOINT_LIMITS, config=config)


@pytest.fixture(scope="session")
def model_file(model, tmp_path_factory):
    path = tmp_path_factory.mktemp("robustness-model") / "model.npz"
    model.save(path)
    return path
