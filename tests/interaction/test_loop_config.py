"""LoopConfig refuses what would stall, never pace or overflow the loop."""

import math

import numpy as np
import pytest

from rnnpb.errors import ConfigError
from rnnpb.interaction import LoopConfig


@pytest.mark.parametrize("dt", [math.inf, -math.inf, math.nan, 10**309, 0, -0.1, True, "0.4", None])
def test_bad_dt_is_refused(dt):
    with pytest.raises(ConfigError, match="dt must be"):
        LoopConfig(dt=dt)


@pytest.mark.parametrize("steps", [True, 2.5, "10", -1])
def test_bad_max_steps_is_refused(steps):
    with pytest.raises(ConfigError, match="max_steps must be"):
        LoopConfig(max_steps=steps)


def test_numpy_numbers_are_accepted_as_plain_ones():
    config = LoopConfig(dt=np.float32(0.25), max_steps=np.int64(7))
    assert config.dt == 0.25 and type(config.dt) is float
    assert config.max_steps == 7 and type(config.max_steps) is int
    assert LoopConfig(dt=1).dt == 1.0
