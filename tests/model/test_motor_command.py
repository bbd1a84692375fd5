"""The motor command is finite and within the model's motor bounds for every model and every
input, in both twins; hostile numbers are one ConfigError; on-line settings refuse NaN."""

import dataclasses
import math

import numpy as np
import pytest

from rnnpb.errors import ConfigError
from rnnpb.model import MIRROR_SYSTEMS, OnlineConfig, TrainConfig
from rnnpb.model.mirror import motor_command
from rnnpb.model.online_config import ONLINE_PRESETS, suggested_online_config

SHORT = OnlineConfig(window=8, iterations=5)


def _with_motor_bounds(model, lower, upper):
    s = model.network.sensory_size
    lo, hi = np.array(model.lower, float), np.array(model.upper, float)
    lo[s:], hi[s:] = lower, upper
    return dataclasses.replace(model, lower=lo, upper=hi)


@pytest.mark.parametrize("twin", MIRROR_SYSTEMS)
@pytest.mark.parametrize("bounds", [(-20.0, 20.0), (-1e308, 1e308)])
def test_motor_is_finite_and_within_the_bounds_for_any_bounds(trained, twin, bounds):
    model = _with_motor_bounds(trained, *bounds)
    mirror = MIRROR_SYSTEMS[twin](model, SHORT)
    rng = np.random.default_rng(1)
    for u in rng.uniform(-0.5, 1.5, (6, 4)):
        motor = mirror.step(u).motor
        assert np.all(np.isfinite(motor))
        assert np.all(motor >= bounds[0]) and np.all(motor <= bounds[1])


def test_motor_command_of_non_finite_outputs_is_finite_and_within_bounds(trained):
    model = _with_motor_bounds(trained, -1e308, 1e308)
    out = motor_command(model, np.array([np.nan, np.inf, -np.inf, 2.0, -1.0, 0.5, 0.0, 1.0]))
    np.testing.assert_array_equal(out, [0.0, 0.0, 0.0, 1e308, -1e308, 0.0, -1e308, 1e308])
    infinite = _with_motor_bounds(trained, -np.inf, np.inf)
    assert np.all(np.isfinite(motor_command(infinite, np.array([0.0, 1.0, 0.3] + [0.5] * 5))))
    # Ordinary bounds: the same linear map as before.
    np.testing.assert_allclose(
        motor_command(trained, np.full(8, 0.25)),
        trained.lower[4:] + 0.25 * (trained.upper[4:] - trained.lower[4:]),
    )


@pytest.mark.parametrize("twin", MIRROR_SYSTEMS)
def test_an_integer_beyond_float_range_is_a_config_error(trained, twin):
    mirror = MIRROR_SYSTEMS[twin](trained, SHORT)
    with pytest.raises(ConfigError, match="must be 4 numbers"):
        mirror.step([10**309, 0.5, 0.5, 0.5])


@pytest.mark.parametrize(
    "name",
    [
        "onset_learning_rate",
        "surprise_gate",
        "gate_power",
        "gate_floor",
        "phase_restart_ratio",
        "phase_restart_level",
    ],
)
@pytest.mark.parametrize("value", [math.nan, math.inf, 10**309])
def test_on_line_settings_refuse_non_finite_numbers(name, value):
    with pytest.raises(ConfigError, match=name):
        _online(**{name: value})


@pytest.mark.parametrize(
    "change", [{"window": 8.5}, {"iterations": True}, {"window": "30"}, {"optimize_onset": 1}]
)
def test_on_line_settings_refuse_wrong_types(change):
    with pytest.raises(ConfigError, match=next(iter(change))):
        _online(**change)


def _online(**values):
    """An OnlineConfig with ``values``: settings by the constructor, tuned ones by
    with_tuning."""
    settings = {f.name for f in dataclasses.fields(OnlineConfig) if f.init}
    config = OnlineConfig(**{k: v for k, v in values.items() if k in settings})
    return config.with_tuning(**{k: v for k, v in values.items() if k not in settings})


def test_the_suggested_regression_follows_the_recorded_learning(trained):
    fast = dataclasses.replace(trained, meta={"train_config": TrainConfig.fast().to_dict()})
    paper = dataclasses.replace(trained, meta={"train_config": TrainConfig.paper().to_dict()})
    unknown = dataclasses.replace(trained, meta={})
    assert suggested_online_config(fast).name == "ungated"
    assert suggested_online_config(fast).config == OnlineConfig.ungated()
    assert OnlineConfig.for_model(paper).config == OnlineConfig()
    assert "paper" in OnlineConfig.for_model(paper).reason
    assert OnlineConfig.for_model(unknown).name == "default"
    assert "does not record" in OnlineConfig.for_model(unknown).reason
    assert [OnlineConfig.preset(name) for name in ONLINE_PRESETS] == [
        OnlineConfig(),
        OnlineConfig.paper(),
        OnlineConfig.ungated(),
    ]
    with pytest.raises(ConfigError, match="unknown on-line regression"):
        OnlineConfig.preset("gated")
