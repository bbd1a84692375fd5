"""Bad sweep specs and an unreachable cluster get one clear line."""

import socket
from pathlib import Path

import pytest

from rnnpb import cli
from rnnpb.errors import ConfigError
from rnnpb.model import OnlineConfig, TrainConfig
from rnnpb.sweeps import ClusterError, RunSpec, Setting, check_address, execute_run, load_spec

GOOD = """
name = "grid"
learning_sets = ["1", "full"]
seeds = 3
user_draws = [100, 200]
[training.fast]
preset = "fast"
iterations = 500
[training.fast.pb]
integration_length = 10
[online.default]
[online.paper]
preset = "paper"
window = 20
"""


def _spec(tmp_path, text):
    path = tmp_path / "spec.toml"
    path.write_text(text)
    return path


def test_a_good_spec_is_the_whole_grid(tmp_path):
    spec = load_spec(_spec(tmp_path, GOOD))
    runs = spec.runs()
    assert len(runs) == 2 * 3 * 2 * 1 * 2
    assert len({r.run_id for r in runs}) == 24
    fast = spec.training[0].config
    assert fast.iterations == 500 and fast.pb.integration_length == 10
    assert spec.online[1].config.window == 20 and spec.online[1].config.surprise_gate == 0.0
    full = [r for r in runs if r.learning_set == "full"][0]
    assert full.experiments == ("follows",)
    # the same data, training and seed share one cached model, whatever the on-line setting
    keys = {(r.learning_set, r.seed): r.model_key for r in runs}
    assert all(r.model_key == keys[(r.learning_set, r.seed)] for r in runs)
    assert len(set(keys.values())) == 6


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (GOOD + "colour = 1\n", "unknown key 'colour'"),
        (GOOD.replace("seeds = 3", "seeds = []"), "the grid is empty: 'seeds' has no values"),
        (
            GOOD.replace('learning_sets = ["1", "full"]', "learning_sets = []"),
            "the grid is empty: 'learning_sets'",
        ),
        ('learning_sets = ["1"]\nseeds = 1\n', "the grid is empty: 'training'"),
        (
            GOOD.replace("iterations = 500", "iteration = 500"),
            "[training.fast]: unknown key 'iteration'",
        ),
        (GOOD.replace('preset = "paper"', 'preset = "fastest"'), "preset 'fastest' is not one of"),
        (GOOD.replace('"full"]', '"7"]'), "learning set '7' is not one of"),
        ("seeds = [", "not TOML"),
    ],
)
def test_bad_specs_get_one_line(tmp_path, capsys, text, message):
    path = _spec(tmp_path, text)
    with pytest.raises(ConfigError, match="sweep spec .*spec.toml: ") as caught:
        load_spec(path)
    assert message in str(caught.value) and "\n" not in str(caught.value)
    assert cli.main(["sweep", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("rnnpb: error: sweep spec") and message in err and "\n" not in err
    assert not (tmp_path / "out").exists()


def test_an_unreachable_address_is_one_line_and_quick(tmp_path, capsys):
    with socket.socket() as free:  # a port nothing listens on
        free.bind(("127.0.0.1", 0))
        port = free.getsockname()[1]
    with pytest.raises(ClusterError, match=f"cannot reach a Ray cluster at 127.0.0.1:{port}"):
        check_address(f"127.0.0.1:{port}")
    with pytest.raises(ClusterError, match="is not HOST:PORT"):
        check_address("nowhere")
    path = _spec(tmp_path, GOOD)
    assert (
        cli.main(
            [
                "sweep",
                str(path),
                "--out",
                str(tmp_path / "out"),
                "--address",
                f"ray://127.0.0.1:{port}",
            ]
        )
        == 2
    )
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"rnnpb: error: cannot reach a Ray cluster at ray://127.0.0.1:{port}")
    assert "\n" not in err and not (tmp_path / "out").exists()


def test_a_run_that_raises_is_recorded_with_its_error(tmp_path):
    run = RunSpec(
        "s",
        "9",
        Setting("t", TrainConfig.fast(iterations=5)),
        0,
        Setting("o", OnlineConfig()),
        100,
        ("synchronization",),
        0,
        2,
        100,
        10,
        (1.0,),
    )
    record = execute_run(run, str(tmp_path))
    assert record.status == "failed" and record.measures == []
    assert "9" in record.error and record.error.split(":")[0].endswith("Error")


def test_the_specs_shipped_in_the_repository_load():
    shipped = sorted((Path(__file__).parents[2] / "sweeps").glob("*.toml"))
    assert shipped
    specs = {path.stem: load_spec(path) for path in shipped}
    larger = specs["larger_set_paper"]
    assert larger.learning_sets == ("full",) and len(larger.seeds) == 10
    assert larger.training[0].config.iterations == 100_000
    assert larger.training[0].config.optimizer == "momentum"
    scaling = specs["scaling"].runs()
    assert len(scaling) == 2 * 5 * 2 and len({r.model_key for r in scaling}) == 10
