"""Nothing happens at import: importing rnnpb sets no environment variable and imports no
MuJoCo; the command line makes XLA's loop choice; a library user who did not is told once."""

import os
import subprocess
import sys
import textwrap

import rnnpb
from rnnpb import _xla

PACKAGES = (
    "rnnpb",
    "rnnpb.cli",
    "rnnpb.model",
    "rnnpb.robot",
    "rnnpb.bridge",
    "rnnpb.interaction",
    "rnnpb.perception",
    "rnnpb.demonstrator",
    "rnnpb.sequences",
    "rnnpb.experiments",
)


def _python(code, drop: tuple[str, ...] = (), **env_changes):
    """Run ``code`` in a new interpreter, without the process-wide choices of this one (and
    without the variables starting with a prefix in ``drop``)."""
    env = {
        k: v
        for k, v in os.environ.items()
        if k not in ("XLA_FLAGS", "RNNPB_XLA_DEFAULTS", "MUJOCO_GL") and not k.startswith(drop)
    }
    env.update(env_changes)
    result = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    return result


def test_importing_rnnpb_leaves_the_environment_alone():
    result = _python(f"""
        import os, sys
        # What the libraries rnnpb builds on change when imported is theirs, not rnnpb's.
        import jax, optax, numpy, cv2
        before = dict(os.environ)
        for name in {PACKAGES!r}:
            __import__(name)
            changed = sorted(k for k in set(before) | set(os.environ)
                             if before.get(k) != os.environ.get(k))
            assert not changed, (name, changed)
        # MuJoCo reads MUJOCO_GL when it is imported: that must still be the program's choice.
        assert "mujoco" not in sys.modules
        print("unchanged")
    """)
    assert result.stdout.strip() == "unchanged"


def test_mujoco_gets_a_headless_gl_when_first_needed_unless_the_user_chose():
    code = """
        import os, sys
        from rnnpb.robot import load_model
        assert "MUJOCO_GL" not in os.environ or os.environ["MUJOCO_GL"] == "osmesa"
        load_model()
        import mujoco
        print(os.environ["MUJOCO_GL"])
    """
    assert _python(code).stdout.strip() in ("egl", "osmesa")
    assert _python(code, MUJOCO_GL="osmesa").stdout.strip() == "osmesa"


MIRROR = """
    import warnings
    warnings.simplefilter("always")
    import jax, numpy as np
    import rnnpb
    from rnnpb.model import MirrorSystem, NetworkConfig, TrainedModel, init_params
    {before}
    network = NetworkConfig()
    model = TrainedModel(network, init_params(network, jax.random.PRNGKey(0)),
                         np.zeros(network.io_size), np.ones(network.io_size),
                         np.full((1, network.pb_size), 0.5), ("1",),
                         np.zeros((1, network.context_size)))
    with warnings.catch_warnings(record=True) as caught:
        MirrorSystem(model)
        MirrorSystem(model)
    for warning in caught:
        print(warning.category.__name__, warning.filename.endswith("<string>"), warning.message)
"""


def test_a_library_user_who_did_not_choose_xla_settings_builds_a_mirror_system_unwarned():
    # The on-line step is compiled by numba, not XLA: nothing to warn about, configured or not.
    assert _python(MIRROR.format(before="")).stdout == ""
    assert _python(MIRROR.format(before="assert rnnpb.configure_xla()")).stdout == ""


def test_the_command_line_makes_the_xla_choice_before_jax_starts():
    result = _python("""
        import os
        from rnnpb import cli, _xla
        try:
            cli.main(["--version"])
        except SystemExit:
            pass
        print(_xla.active(), _xla.backend_started())
    """)
    assert result.stdout.split()[-2:] == ["True", "False"]


def test_the_test_suite_made_the_choice_itself():
    # tests/conftest.py, before any computation: the suite runs as the command line does.
    assert _xla.active() and rnnpb.configure_xla is _xla.configure


def test_the_command_line_lists_its_commands_without_loading_jax():
    # `rnnpb --help` and every command's options are built before any command runs: the heavy
    # libraries are imported by the command that needs them, when it runs.
    result = _python("""
        import sys
        from rnnpb.cli import build_parser
        build_parser()
        heavy = ("jax", "mujoco", "cv2", "ray", "pyarrow", "zenoh")
        print(sorted(m for m in heavy if m in sys.modules))
    """)
    assert result.stdout.strip().splitlines()[-1] == "[]"


CACHED_PROGRAM = """
    from rnnpb import _xla
    _xla.configure()
    _xla.compilation_cache()
    import jax, jax.numpy as jnp
    def f(x):
        for k in range(60):
            x = jnp.sin(x @ x.T + k)
        return x
    print(float(jax.jit(f)(jnp.ones((8, 8))).sum()))
"""


def test_a_second_process_reads_what_the_first_compiled(tmp_path):
    # rnnpb._xla.compilation_cache: programs kept on disk for the next process.
    def run():
        return _python(
            CACHED_PROGRAM,
            drop=("JAX_",),  # this test process's own cache settings
            RNNPB_XLA_CACHE=str(tmp_path),
            JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS="0",
        ).stdout.strip()

    first = run()
    entries = sorted(p.name for p in tmp_path.iterdir() if p.name.endswith("-cache"))
    assert entries, "the first process kept nothing"
    assert run() == first  # the same result from the kept program
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.endswith("-cache")) == entries
