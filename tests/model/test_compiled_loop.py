"""rnnpb._xla: the XLA setting rnnpb recommends, and who applies it."""

from rnnpb import _xla


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
