"""The one XLA setting rnnpb recommends, and who applies it.

XLA's CPU runtime launches every operation of a loop body as a separate task, unless the loop is
*small*: it touches fewer bytes than a threshold (1 KiB by default) and holds nothing XLA hands
to a library; then XLA compiles the whole loop into one function. :data:`FLAG` raises the
threshold to 1 MiB for rnnpb's JAX loops that are small: generation's closed loop (the phase
restarts' candidates), the routine level's regression and the input noise's generator of the
JAX learning chunk. The on-line step itself is compiled by numba (:mod:`rnnpb.model.online`)
and does not depend on it; loops that move more data — learning — keep their library calls.

Importing rnnpb changes nothing: the setting is a process-wide environment variable, so the
program decides. The ``rnnpb`` command, the demo's worker processes and the test suite call
:func:`configure` before their first JAX computation; a library user calls
``rnnpb.configure_xla()`` the same way, or sets ``XLA_FLAGS`` themselves. XLA reads its flags
once, when JAX starts its CPU backend, so the setting takes effect only before the first JAX
computation of the process. ``RNNPB_XLA_DEFAULTS=0`` (or an ``--xla_backend_extra_options`` of
one's own in ``XLA_FLAGS``) keeps XLA's defaults.

The compiled programs are kept on disk (:func:`compilation_cache`): XLA compiles the learning
iteration and each on-line configuration's step in a few seconds each, in every new process. The
``rnnpb`` command, the test suite and every worker process they start (the demo's, the studies',
a sweep's Ray tasks) keep them in JAX's persistent compilation cache, so that a process compiles
only what no earlier process did: ``~/.cache/rnnpb/xla`` (``$XDG_CACHE_HOME/rnnpb/xla``), or the
folder ``RNNPB_XLA_CACHE`` names; ``RNNPB_XLA_CACHE=0`` turns it off, and a
``JAX_COMPILATION_CACHE_DIR`` of one's own is used as it is.
"""

from __future__ import annotations

import os
import sys
import warnings
from collections.abc import Mapping, MutableMapping
from pathlib import Path

SMALL_LOOP_OPTION = "xla_cpu_small_while_loop_byte_threshold"
SMALL_LOOP_BYTES = 1 << 20
FLAG = f"--xla_backend_extra_options={SMALL_LOOP_OPTION}={SMALL_LOOP_BYTES}"


def user_decided(environ: Mapping[str, str] | None = None) -> bool:
    """Whether the environment already says what XLA should do with small loops: rnnpb's
    setting is off (``RNNPB_XLA_DEFAULTS=0``) or ``XLA_FLAGS`` sets backend options of its own."""
    environ = os.environ if environ is None else environ
    if environ.get("RNNPB_XLA_DEFAULTS", "1").strip() == "0":
        return True
    flags = environ.get("XLA_FLAGS", "")
    return "xla_backend_extra_options" in flags and FLAG not in flags


def configure(environ: MutableMapping[str, str] | None = None) -> bool:
    """Compile rnnpb's small JAX loops whole: add :data:`FLAG` to ``XLA_FLAGS``.

    Call it before the first JAX computation of the process (XLA reads its flags once). It
    leaves the environment alone when the user decided otherwise (:func:`user_decided`) or the
    flag is already there.

    Parameters
    ----------
    environ : mapping, optional
        The environment to change; default ``os.environ``.

    Returns
    -------
    bool
        Whether the flag was added. Warns when JAX's backend has already started in this
        process, because the flag can then no longer take effect there.
    """
    environ = os.environ if environ is None else environ
    flags = environ.get("XLA_FLAGS", "")
    if user_decided(environ) or FLAG in flags:
        return False
    # First: XLA stops reading flags at the first word that is not one ("--name=value").
    environ["XLA_FLAGS"] = f"{FLAG} {flags}".strip()
    if environ is os.environ and backend_started():
        warnings.warn(
            "JAX started before rnnpb.configure_xla() was called, so the setting does not "
            "apply in this process; call it before the first JAX computation, or set "
            f"XLA_FLAGS={FLAG}",
            RuntimeWarning,
            stacklevel=2,
        )
    return True


def single_threaded(environ: MutableMapping[str, str] | None = None) -> None:
    """Ask XLA for single-threaded matrix products (``rnnpb bench``, the demo's workers).

    Only real flags go into ``XLA_FLAGS``: XLA stops reading at the first word that is not one.
    """
    environ = os.environ if environ is None else environ
    flags = environ.get("XLA_FLAGS", "")
    if "--xla_cpu_multi_thread_eigen=false" not in flags:
        environ["XLA_FLAGS"] = f"{flags} --xla_cpu_multi_thread_eigen=false".strip()


def backend_started() -> bool:
    """Whether JAX has already created its backends (and so read ``XLA_FLAGS``)."""
    if "jax" not in sys.modules:
        return False
    try:
        from jax._src import xla_bridge
    except ImportError:  # pragma: no cover - a JAX without this module: assume not started
        return False
    return bool(getattr(xla_bridge, "_backends", None))


def active() -> bool:
    """Whether this process's ``XLA_FLAGS`` carries rnnpb's setting (as bench reports it)."""
    return FLAG in os.environ.get("XLA_FLAGS", "")


CACHE_ENV = "RNNPB_XLA_CACHE"
CACHE_MAX_BYTES = 1 << 30  # JAX's cache evicts the least recently used entries beyond this
CACHE_MIN_COMPILE_S = 0.2  # programs that compile faster are not worth a file


def cache_folder(environ: Mapping[str, str] | None = None) -> Path | None:
    """Where compiled programs are kept (:func:`compilation_cache`), or None when off."""
    environ = os.environ if environ is None else environ
    chosen = environ.get(CACHE_ENV, "").strip()
    if chosen == "0":
        return None
    if chosen and chosen != "1":
        return Path(chosen).expanduser()
    base = environ.get("XDG_CACHE_HOME", "").strip()
    return (Path(base) if base else Path.home() / ".cache") / "rnnpb" / "xla"


def compilation_cache(environ: MutableMapping[str, str] | None = None) -> Path | None:
    """Keep compiled programs on disk, for this process and the processes it starts.

    Sets JAX's persistent compilation cache through the environment (which JAX reads when it
    is imported, and worker processes inherit), and in this process's JAX when it is already
    imported. The cache has a size bound, which also makes JAX take a file lock around every
    read and write, so that processes sharing it never read a half-written entry; an entry a
    killed process left unreadable is reported by JAX once and compiled again.

    Returns the folder, or None: turned off (``RNNPB_XLA_CACHE=0``), or the folder cannot be
    made (a read-only home: compiling as before, silently). A ``JAX_COMPILATION_CACHE_DIR`` the
    user set is left as it is and returned.
    """
    environ = os.environ if environ is None else environ
    own = environ.get("JAX_COMPILATION_CACHE_DIR", "").strip()
    if own:
        return Path(own)
    folder = cache_folder(environ)
    if folder is None:
        return None
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    settings = {
        "JAX_COMPILATION_CACHE_DIR": str(folder),
        "JAX_COMPILATION_CACHE_MAX_SIZE": str(CACHE_MAX_BYTES),
        "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS": str(CACHE_MIN_COMPILE_S),
    }
    for name, value in settings.items():
        if not environ.get(name, "").strip():  # unset or blank; a value of the user's stays
            environ[name] = value
    if environ is os.environ:
        follow_cache_settings()
    return folder


def follow_cache_settings() -> None:
    """JAX, when imported, takes its persistent cache's settings from this process's
    environment as it is now (a process forked from one that imported JAX before its
    environment was set: :mod:`rnnpb.interaction.background`)."""
    if "jax" not in sys.modules:
        return
    import jax

    folder = os.environ.get("JAX_COMPILATION_CACHE_DIR", "").strip() or None
    jax.config.update("jax_compilation_cache_dir", folder)
    numbers = {
        "JAX_COMPILATION_CACHE_MAX_SIZE": ("jax_compilation_cache_max_size", int),
        "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS": (
            "jax_persistent_cache_min_compile_time_secs",
            float,
        ),
    }
    for name, (option, kind) in numbers.items():
        value = os.environ.get(name, "").strip()
        if value:
            jax.config.update(option, kind(value))
