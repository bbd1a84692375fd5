"""The on-line regression compiles into one function (rnnpb._xla): the speed depends on it."""

import os
import re

import jax
import numpy as np
import pytest

from rnnpb import _xla
from rnnpb.model import OnlineConfig
from rnnpb.model.online import initial_state, online_step


def test_configure_adds_the_flag_once_and_respects_the_user():
    env = {}
    assert _xla.configure(env) and env["XLA_FLAGS"] == _xla.FLAG
    env = {"XLA_FLAGS": "--xla_cpu_multi_thread_eigen=false"}
    assert _xla.configure(env)
    assert env["XLA_FLAGS"] == f"{_xla.FLAG} --xla_cpu_multi_thread_eigen=false"
    own = {"XLA_FLAGS": "--xla_backend_extra_options=xla_cpu_fold_all_constants"}
    assert not _xla.configure(own)
    assert own["XLA_FLAGS"] == "--xla_backend_extra_options=xla_cpu_fold_all_constants"
    off = {"RNNPB_XLA_DEFAULTS": "0"}
    assert not _xla.configure(off) and "XLA_FLAGS" not in off
    twice = {}
    assert _xla.configure(twice) and not _xla.configure(twice)
    assert twice["XLA_FLAGS"] == _xla.FLAG


def test_the_user_decided_when_the_setting_is_off_or_flags_carry_other_backend_options():
    assert not _xla.user_decided({})
    assert not _xla.user_decided({"XLA_FLAGS": _xla.FLAG})
    assert _xla.user_decided({"RNNPB_XLA_DEFAULTS": "0"})
    own = "--xla_backend_extra_options=xla_cpu_fold_all_constants"
    assert _xla.user_decided({"XLA_FLAGS": f"--xla_cpu_multi_thread_eigen=false {own}"})


def test_single_threaded_adds_only_real_flags_once():
    env = {"XLA_FLAGS": _xla.FLAG}
    _xla.single_threaded(env)
    _xla.single_threaded(env)
    assert env["XLA_FLAGS"] == f"{_xla.FLAG} --xla_cpu_multi_thread_eigen=false"
    assert all(word.startswith("--") for word in env["XLA_FLAGS"].split())


@pytest.mark.skipif(
    "xla_backend_extra_options" in os.environ.get("XLA_FLAGS", "") and not _xla.active(),
    reason="XLA_FLAGS sets its own backend options",
)
@pytest.mark.parametrize("config", [OnlineConfig(), OnlineConfig.paper()], ids=["default", "paper"])
def test_the_regression_loop_is_compiled_as_one_function(trained, config):
    # tests/conftest.py configured XLA before its backend started (before any computation).
    assert _xla.active()
    params = jax.tree_util.tree_map(lambda a: np.asarray(a, np.float32), trained.params)
    state = initial_state(trained, config)
    candidates = np.zeros((len(trained.pattern_pb), trained.network.pb_size), np.float32)
    hlo = (
        online_step.lower(
            params, state, np.full(4, 0.5, np.float32), np.ones(4, bool), config, candidates
        )
        .compile()
        .as_text()
    )
    # The iteration loop: the while loop that runs `iterations` times.
    trip = f'"known_trip_count":{{"n":"{config.iterations}"}}'
    loops = [line for line in hlo.splitlines() if " while(" in line and trip in line]
    assert loops, "no loop of the regression's iteration count in the compiled step"
    computations = {}
    name = None
    for line in hlo.splitlines():
        header = re.match(r"^%?([\w.\-]+) \(", line)
        if header and not line.startswith(" "):
            name = header.group(1)
        computations.setdefault(name, []).append(line)
    for loop in loops:
        owner = next(n for n, lines in computations.items() if loop in lines)
        # Hoisted loops live alone in a computation called with the "small call" attribute:
        # XLA then compiles the whole loop, all 100 iterations, into one function.
        callers = [
            line for line in hlo.splitlines() if f"to_apply=%{owner}" in line and " call(" in line
        ]
        assert callers and all('xla_cpu_small_call="true"' in c for c in callers), (
            "the on-line regression loop is not compiled as one function: an operation in it "
            "is handed to a library (see rnnpb._xla)"
        )
