"""Learning: the error goes down, patterns get distinct PBs, runs repeat, checkpoints resume."""

import dataclasses

import jax
import numpy as np
import pytest

from rnnpb.errors import ConfigError, DataFileError, ModelFileError
from rnnpb.model import TrainConfig, train, train_seeds
from rnnpb.sequences import Sequence

from .synthetic import LIMITS, make_sequences


def test_learning_three_patterns_reaches_small_error_and_distinct_pbs(trained):
    info = trained.meta["training"]
    history = [mse for _, mse in info["history"]]
    assert history[-1] < history[0] / 10
    # Every output's mean squared error below 1e-3 after 2,000 fast iterations (the synthetic
    # data has sensor noise of 0.01, i.e. a floor of 1e-4 on the sensory outputs).
    assert info["mse_max"] < 1e-3
    pbs = trained.pattern_pb
    assert set(pbs) == {"0", "1", "2"}
    names = list(pbs)
    between = min(
        np.linalg.norm(pbs[a] - pbs[b]) for i, a in enumerate(names) for b in names[i + 1 :]
    )
    assert between > 0.3
    # The two samples of a pattern get nearly the same PB, far closer than other patterns'.
    seq = trained.sequence_pb
    within = max(np.linalg.norm(seq[2 * k] - seq[2 * k + 1]) for k in range(3))
    assert within < between / 2


def test_paper_algorithm_descends():
    sequences = make_sequences(n_steps=30)
    model = train(
        sequences,
        LIMITS,
        config=TrainConfig.paper(iterations=600).with_tuning(chunk_iterations=200),
    )
    history = [mse for _, mse in model.meta["training"]["history"]]
    assert history[-1] < 0.6 * history[0]


def test_seeded_runs_repeat_exactly_and_seeds_differ():
    sequences = make_sequences(n_steps=20)
    config = TrainConfig.fast(iterations=150).with_tuning(chunk_iterations=50)
    a = train(sequences, LIMITS, config=config)
    b = train(sequences, LIMITS, config=config)
    c = train(
        sequences,
        LIMITS,
        config=TrainConfig.fast(iterations=150, seed=1).with_tuning(chunk_iterations=50),
    )
    for x, y in zip(
        jax.tree_util.tree_leaves(a.params), jax.tree_util.tree_leaves(b.params), strict=True
    ):
        np.testing.assert_array_equal(np.asarray(x), np.asarray(y))
    np.testing.assert_array_equal(a.sequence_pb, b.sequence_pb)
    assert not np.array_equal(np.asarray(a.params.w_in), np.asarray(c.params.w_in))


# The paper's gradient descent gives the same numbers; Adam's batched update rounds
# differently (about 5e-6 after 120 iterations).
@pytest.mark.parametrize(("preset", "atol"), [("fast", 1e-4), ("paper", 1e-6)])
def test_seeds_learned_together_are_the_models_each_seed_learns_alone(preset, atol):
    sequences = make_sequences(n_steps=20)
    config = TrainConfig.from_preset(preset, iterations=120).with_tuning(chunk_iterations=50)
    together = train_seeds(sequences, LIMITS, [3, 0], config=config)
    for seed, model in zip([3, 0], together, strict=True):
        alone = train(sequences, LIMITS, config=dataclasses.replace(config, seed=seed))
        for x, y in zip(
            jax.tree_util.tree_leaves(model.params),
            jax.tree_util.tree_leaves(alone.params),
            strict=True,
        ):
            np.testing.assert_allclose(np.asarray(x), np.asarray(y), rtol=0, atol=atol)
        np.testing.assert_allclose(model.sequence_pb, alone.sequence_pb, rtol=0, atol=atol)
        assert [i for i, _ in model.meta["training"]["history"]] == [0, 50, 100, 120]
        assert model.meta["train_config"]["seed"] == seed
    assert not np.allclose(np.asarray(together[0].params.w_in), np.asarray(together[1].params.w_in))
    with pytest.raises(ConfigError, match="distinct seeds"):
        train_seeds(sequences, LIMITS, [1, 1], config=config)


def test_checkpoint_resume_continues_where_it_stopped(tmp_path):
    sequences = make_sequences(n_steps=20)
    path = tmp_path / "run.checkpoint.npz"
    straight = train(
        sequences, LIMITS, config=TrainConfig.fast(iterations=200, checkpoint_every=100)
    )
    train(
        sequences,
        LIMITS,
        config=TrainConfig.fast(iterations=100, checkpoint_every=100),
        checkpoint_path=path,
    )
    assert path.exists()
    resumed = train(
        sequences,
        LIMITS,
        config=TrainConfig.fast(iterations=200, checkpoint_every=100),
        checkpoint_path=path,
        resume=True,
    )
    assert resumed.meta["training"]["iterations"] == 200
    np.testing.assert_array_equal(
        np.asarray(resumed.params.w_out), np.asarray(straight.params.w_out)
    )
    # Other data cannot resume from it.
    with pytest.raises(ModelFileError, match="other training data"):
        train(
            make_sequences(n_steps=20, seed=3),
            LIMITS,
            config=TrainConfig.fast(iterations=200),
            checkpoint_path=path,
            resume=True,
        )


def test_motor_values_outside_the_joint_limits_are_rejected():
    bad = make_sequences(n_steps=10)[:1]
    motor = bad[0].motor.copy()
    motor[3, 2] = 5.0
    # The column by its name, with its range.
    with pytest.raises(
        DataFileError,
        match=r"bad.csv: step 3, lshy = 5 is outside its range "
        r"\[-2, 2\] \(a joint angle",
    ):
        train(
            [Sequence(bad[0].sensory, motor, "x", "bad.csv")],
            LIMITS,
            config=TrainConfig.fast(iterations=1),
        )


@pytest.mark.parametrize(
    "kwargs",
    [dict(iterations=-1), dict(optimizer="sgd"), dict(learning_rate=0), dict(input_noise=-0.1)],
)
def test_bad_training_config_is_rejected(kwargs):
    settings = {f.name for f in dataclasses.fields(TrainConfig) if f.init}
    with pytest.raises(ConfigError):
        TrainConfig(**{k: v for k, v in kwargs.items() if k in settings}).with_tuning(
            **{k: v for k, v in kwargs.items() if k not in settings}
        )
