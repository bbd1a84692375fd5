"""One learning-set job of ``rnnpb demo`` with more demonstrations than the paper's two: every
demonstration is learned and kept under ``data/``; a bad count is refused up front."""

from rnnpb.cli import main
from rnnpb.experiments import ExperimentConfig
from rnnpb.experiments.paper import learning_set_job
from rnnpb.model import OnlineConfig, TrainConfig, TrainedModel
from rnnpb.sequences import read_sequences


def test_every_demonstration_is_learned_and_kept(tmp_path):
    config = ExperimentConfig(samples_per_pattern=3, extra_scenario_seeds=())
    data = tmp_path / "data"
    data.mkdir()
    result = learning_set_job("1", TrainConfig.fast(iterations=20), OnlineConfig(), config,
                              str(tmp_path / "set1.npz"), str(data), "default", full=False)
    names = sorted(p.name for p in data.glob("*.csv"))
    assert names == [f"{p}_{k}.csv" for p in "123" for k in (1, 2, 3)]
    assert [s.pattern for s in read_sequences(data / "2_3.csv")] == ["2"]
    model = TrainedModel.load(tmp_path / "set1.npz")
    assert model.patterns == ("1", "2", "3")
    assert len(result["synchronization"]) == 3
    assert len(result["switching"]["pairs"]) == 6


def test_demo_refuses_a_bad_number_of_demonstrations(tmp_path, capsys):
    out = tmp_path / "demo"
    assert main(["demo", "--samples-per-pattern", "0", "--out", str(out)]) == 2
    assert "samples_per_pattern must be >= 1" in capsys.readouterr().err
    assert not out.exists()
