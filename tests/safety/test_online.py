"""Safety in on-line runs: the map beside the model, the filter-only fallback, safety off,
the risk grids of the dashboard's PB views, and `rnnpb interact` with the filter."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rnnpb.demonstrator import learning_set
from rnnpb.errors import ModelFileError
from rnnpb.model import OnlineConfig, TrainConfig, train
from rnnpb.robot import JOINT_LIMITS
from rnnpb.safety import (
    online_safety,
    risk_views,
    safety_map_path,
)

from .maps import ball_map


@pytest.fixture(scope="module")
def model_path(tmp_path_factory):
    model = train(
        learning_set("1", seed=0), JOINT_LIMITS, config=TrainConfig.fast(iterations=100, seed=0)
    )
    path = tmp_path_factory.mktemp("models") / "m.npz"
    model.save(path)
    return path


def _map_around(model, centre, radius=0.35):
    pbs = np.random.default_rng(1).uniform(size=(1500, model.network.pb_size))
    return ball_map(model, pbs, centre, radius, 0.08, 800, {})


def test_without_a_map_the_filter_alone_guards_and_off_means_neither(model_path):
    from rnnpb.model import TrainedModel

    model = TrainedModel.load(model_path)
    online = OnlineConfig(safety_guard="barrier")
    fallback = online_safety(model_path, model, online)
    assert fallback.command_filter is not None and fallback.meta is None
    assert fallback.guard == "off" and "filter alone" in fallback.note
    off = online_safety(model_path, model, online, enabled=False)
    assert off.command_filter is None and off.meta is None and off.config.safety_guard == "off"


def test_a_map_beside_the_model_guards_the_pb_and_a_damaged_one_is_an_error(model_path, tmp_path):
    from rnnpb.model import TrainedModel

    model = TrainedModel.load(model_path)
    path = tmp_path / "m.npz"
    model.save(path)
    # The learned mean of the PBs given below is (0.4, 0.4, 0.3, 0.4): the risky region sits
    # in the PB0 × PB1 view's corner near (0.8, 0.8).
    centre = np.array([0.8, 0.8, 0.3, 0.4])
    _map_around(model, centre).save(safety_map_path(path))
    safety = online_safety(path, model, OnlineConfig(safety_guard="projection"))
    assert safety.meta is not None and safety.guard == "projection"
    assert safety.command_filter is not None and "m.safety.npz" in safety.note
    views = risk_views(
        safety.safety_map,
        {"a": np.full(4, 0.2), "b": np.full(4, 0.5), "c": np.array([0.8, 0.8, 0.2, 0.5])},
    )
    assert set(views) == {"01", "23", "plane"}
    for view in views.values():
        risk = np.array(view["risk"])
        assert risk.shape == (view["grid"], view["grid"]) and 0 <= risk.min() <= risk.max() <= 1
    grid = np.array(views["01"]["risk"])  # rows along PB1, columns along PB0
    assert grid[-5, -5] > 0.5 > grid[2, 2]
    # Cell 19 of 24 along both axes: its centre is PB0 = PB1 = 19.5 / 24.
    np.testing.assert_allclose(
        grid[-5, -5], safety.safety_map.risk(np.array([19.5 / 24, 19.5 / 24, 0.3, 0.4])), atol=1e-3
    )
    safety_map_path(path).write_bytes(b"not a map")
    with pytest.raises(ModelFileError, match="m.safety.npz"):
        online_safety(path, model, OnlineConfig())


def test_interact_filters_every_command_and_says_what_guards(model_path, tmp_path, capsys):
    from rnnpb.cli import main
    from rnnpb.interaction import read_session

    out = tmp_path / "run"
    assert (
        main(
            [
                "interact",
                "--model",
                str(model_path),
                "--source",
                "scenario:held:1",
                "--steps",
                "12",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    printed = capsys.readouterr().out
    assert "command filter alone" in printed
    session = read_session(out / "session.csv")
    assert len(session["filtered"]) == 12
    summary = json.loads((out / "summary.json").read_text())
    assert summary["safety"]["filter"] and not summary["safety"]["map"]
    assert (
        main(
            [
                "interact",
                "--model",
                str(model_path),
                "--source",
                "scenario:held:1",
                "--steps",
                "3",
                "--out",
                str(out),
                "--no-safety",
            ]
        )
        == 0
    )
    assert "safety: off" in capsys.readouterr().out
    assert json.loads((out / "summary.json").read_text())["safety"]["filter"] is False


def test_a_study_run_counts_what_was_generated_and_what_reached_the_robot(model_path):
    from rnnpb.experiments.scenarios.safety import USERS, measure, session_job, user_stream
    from rnnpb.model import TrainedModel

    model = TrainedModel.load(model_path)
    for user in USERS[:-1]:  # the unsafe pattern needs a model that generates unsafe movement
        stream = user_stream(user, 40, 3, "1", model.patterns)
        assert stream.shape == (40, 4)
        seen = stream[np.isfinite(stream)]
        assert 0 <= seen.min() <= seen.max() <= 1
    assert np.isnan(user_stream("lost_hands", 80, 3, "1", model.patterns)).any()
    maps = _map_around(model, np.array([0.8, 0.8, 0.3, 0.4]))
    stream = user_stream("full_swing", 8, 0, "1")
    runs = {
        ("full_swing", arm): session_job(
            str(model_path), maps.meta, OnlineConfig(), arm, stream, "x"
        )
        for arm in ("unguarded", "everything")
    }
    everything = runs[("full_swing", "everything")]
    assert len(everything["regime"]) == 8
    assert not any(everything["sent_unsafe"])  # the filter let none through
    assert len(everything["sent_judged"]) == 8
    generated = everything["generated_unsafe"] != ""
    assert set(everything["cause"][generated]) <= {"seen movement", "generation"}
    assert not any(everything["cause"][~generated])
    totals = measure(runs, maps, 0.2)["totals"]
    assert totals["sent_unsafe"] == 0
    assert totals["sent_judged_unsafe"] == int((everything["sent_judged"] != "").sum())
    assert totals["steer_unguarded"] == int(
        np.isin(
            runs[("full_swing", "unguarded")]["regime"], ["lost", "still", "novel", "unstructured"]
        )
        @ (runs[("full_swing", "unguarded")]["generated_unsafe"] != "")
    )
