"""Compiled programs are kept on disk for the next process (rnnpb._xla.compilation_cache)."""

from pathlib import Path

from rnnpb import _xla


def test_the_cache_folder_follows_the_environment(tmp_path):
    assert _xla.cache_folder({"RNNPB_XLA_CACHE": "0"}) is None
    assert _xla.cache_folder({"RNNPB_XLA_CACHE": str(tmp_path)}) == tmp_path
    assert _xla.cache_folder({"XDG_CACHE_HOME": str(tmp_path)}) == tmp_path / "rnnpb" / "xla"
    assert _xla.cache_folder({"RNNPB_XLA_CACHE": "1", "XDG_CACHE_HOME": str(tmp_path)}) == (
        tmp_path / "rnnpb" / "xla"
    )
    assert _xla.cache_folder({}) == Path.home() / ".cache" / "rnnpb" / "xla"


def test_compilation_cache_sets_jax_through_the_environment_and_respects_the_user(tmp_path):
    env = {"RNNPB_XLA_CACHE": str(tmp_path / "xla")}
    assert _xla.compilation_cache(env) == tmp_path / "xla"
    assert (tmp_path / "xla").is_dir()
    assert env["JAX_COMPILATION_CACHE_DIR"] == str(tmp_path / "xla")
    # A size bound: JAX then locks the files, so that processes never read half an entry.
    assert int(env["JAX_COMPILATION_CACHE_MAX_SIZE"]) == _xla.CACHE_MAX_BYTES > 0
    assert float(env["JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS"]) == _xla.CACHE_MIN_COMPILE_S
    own = {"JAX_COMPILATION_CACHE_DIR": "/somewhere/of/mine", "RNNPB_XLA_CACHE": str(tmp_path)}
    assert _xla.compilation_cache(own) == Path("/somewhere/of/mine")
    assert "JAX_COMPILATION_CACHE_MAX_SIZE" not in own
    blank = {"JAX_COMPILATION_CACHE_DIR": " ", "RNNPB_XLA_CACHE": str(tmp_path / "b")}
    assert _xla.compilation_cache(blank) == tmp_path / "b"
    assert blank["JAX_COMPILATION_CACHE_DIR"] == str(tmp_path / "b")
    off = {"RNNPB_XLA_CACHE": "0"}
    assert _xla.compilation_cache(off) is None and off == {"RNNPB_XLA_CACHE": "0"}
    # A folder that cannot be made: compiling as before, nothing set.
    blocked = tmp_path / "a-file"
    blocked.write_text("")
    cannot = {"RNNPB_XLA_CACHE": str(blocked / "xla")}
    assert _xla.compilation_cache(cannot) is None and "JAX_COMPILATION_CACHE_DIR" not in cannot
