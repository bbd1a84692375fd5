"""One learning-set job of ``rnnpb demo`` with more demonstrations than the paper's two: every
demonstration is learned and kept under ``data/``; a bad count is refused up front."""

import math
import pickle

import numpy as np
import pytest

from rnnpb.cli import main
from rnnpb.errors import ConfigError
from rnnpb.experiments import (
    ExperimentConfig,
    NovelResponse,
    describe_configuration,
    learning_set_job,
    missing_cases_explanation,
)
from rnnpb.model import OnlineConfig, TrainConfig, TrainedModel
from rnnpb.sequences import read_sequences

# A short regression: these tests are about what a job keeps and compares, not how well the
# robot follows (the demo's targets), and it keeps the compiled step and the runs cheap.
SHORT = {"window": 8, "iterations": 5}


def test_every_demonstration_is_learned_and_kept(tmp_path):
    config = ExperimentConfig(samples_per_pattern=3, extra_scenario_seeds=())
    data = tmp_path / "data"
    data.mkdir()
    result = learning_set_job(
        "1",
        TrainConfig.fast(iterations=20),
        OnlineConfig(**SHORT),
        config,
        str(tmp_path / "set1.npz"),
        str(data),
        "default",
        full=False,
    )
    names = sorted(p.name for p in data.glob("*.csv"))
    assert names == [f"{p}_{k}.csv" for p in "123" for k in (1, 2, 3)]
    assert [s.pattern for s in read_sequences(data / "2_3.csv")] == ["2"]
    model = TrainedModel.load(tmp_path / "set1.npz")
    assert model.patterns == ("1", "2", "3")
    assert len(result.synchronization) == 3
    assert len(result.switching.pairs) == 6
    # The job's result goes back from a worker process whole.
    again = pickle.loads(pickle.dumps(result))
    assert again.switching == result.switching
    np.testing.assert_array_equal(again.synchronization[0].run.pb, result.synchronization[0].run.pb)


def test_demo_refuses_a_bad_number_of_demonstrations(tmp_path, capsys):
    out = tmp_path / "demo"
    assert main(["demo", "--samples-per-pattern", "0", "--out", str(out)]) == 2
    assert "samples_per_pattern must be >= 1" in capsys.readouterr().err
    assert not out.exists()


def test_the_comparison_runs_the_papers_regression_on_the_same_model(tmp_path):
    config = ExperimentConfig(extra_scenario_seeds=())
    result = learning_set_job(
        "1",
        TrainConfig.fast(iterations=20),
        OnlineConfig(**SHORT),
        config,
        str(tmp_path / "set1.npz"),
        None,
        "default",
        full=False,
        compare=OnlineConfig.paper(**SHORT),
    )
    compared = result.compared("paper")
    assert compared.label == "paper" and compared.model == result.model
    assert [s.pattern for s in compared.synchronization] == ["1", "2", "3"]
    assert set(compared.switching.pairs) == set(result.switching.pairs)
    # Same scenario, same model, another regression: the PB takes another course.
    ours, theirs = result.synchronization[0].run, compared.synchronization[0].run
    assert ours.pb.shape == theirs.pb.shape
    assert abs(ours.pb - theirs.pb).max() > 1e-3


def test_the_report_says_which_learning_and_regression_it_ran():
    full = describe_configuration(ExperimentConfig())
    assert "gradient descent with momentum, 50,000 iterations" in full
    assert "the larger set: 30,000 iterations" in full
    assert "surprise gate at 0.035" in full
    assert "phase restarts from the learned cycles (scored on the last 3 steps)" in full
    assert "**paper's regression**" in full
    quick = describe_configuration(ExperimentConfig.quick_run())
    assert "fast preset" in quick and "no surprise gate" in quick
    assert "paper's regression" not in quick


def _novel(case, period, return_error):
    return NovelResponse(
        learning_set="1",
        novel_pattern="4",
        amplitude=1.0,
        case=case,
        description="",
        period=period,
        nearest_pattern=None,
        distance=math.nan,
        return_error=return_error,
        motor=np.zeros((1, 8)),
        pb=np.zeros((1, 4)),
        context=np.zeros((1, 30)),
    )


def test_the_missing_case_explanation_counts_the_closed_loop_cycles():
    runs = [_novel(case, 12, 0.05) for case in (1, 2, 2)]
    periodic = {"1": {"1": 12, "2": 12, "3": 23}}
    text = " ".join(missing_cases_explanation(runs, periodic))
    assert "Why case 3 did not occur" in text
    assert "are limit cycles too (periods 12.0, 23.0)" in text
    assert "counts as unsteady above 0.1" in text
    text = " ".join(missing_cases_explanation(runs, {"1": {"1": 12, "2": None, "3": 37}}))
    assert "2 of 3 are limit cycles (periods 12.0, 37.0)" in text
    assert missing_cases_explanation(runs + [_novel(3, None, 0.4)], periodic) == []


def test_the_larger_sets_seeds_learn_together_one_group_per_worker_first(tmp_path):
    from rnnpb.experiments.jobs import run_jobs

    seen = []

    def runner(jobs):
        seen.extend((function.__name__, args) for _, function, args in jobs)
        return iter(())

    config = ExperimentConfig(training_seeds=(0,), larger_set_seeds=5, workers=2)
    run_jobs(tmp_path, config, log=lambda _: None, runner=runner)
    assert [args[0] for _, args in seen[:2]] == [(0, 2, 4), (1, 3)]
    assert [name for name, _ in seen[:2]] == ["larger_set_job"] * 2
    assert seen[0][1][4] == [str(tmp_path / "models" / f"full_seed{s}.npz") for s in (0, 2, 4)]
    assert all(name == "learning_set_job" for name, _ in seen[2:])


def test_the_papers_regression_runs_only_on_the_first_seeds_networks(tmp_path):
    from rnnpb.experiments.jobs import run_jobs

    seen = []

    def runner(jobs):
        # Record what each job was asked to run instead of running it.
        for key, function, args in jobs:
            seen.append((key, function.__name__, args))
        return iter(())

    config = ExperimentConfig(training_seeds=(0, 1, 2), compare_seeds=1, larger_set_seeds=1)
    run_jobs(tmp_path, config, log=lambda _: None, runner=runner)
    compared = {
        (key[1], key[2]): args[8] is not None
        for key, name, args in seen
        if name == "learning_set_job"
    }
    assert compared == {(s, seed): seed == 0 for s in "1234" for seed in (0, 1, 2)}
    assert [args[0] for _, name, args in seen if name == "larger_set_job"] == [(0,)]
    # Every network is still measured in full (draws, attractors and novel patterns).
    assert all(args[7] for _, name, args in seen if name == "learning_set_job")
    with pytest.raises(ConfigError, match="compare_seeds must be >= 1"):
        ExperimentConfig(compare_seeds=0)
