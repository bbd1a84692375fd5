"""The one XLA setting rnnpb makes, applied when the package is imported.

The on-line step (:func:`rnnpb.model.online.online_step`) runs 100 iterations of a forward and a
backward pass through a 30-step window every step: some 12,000 tiny matrix-vector products in
sequence. XLA's CPU runtime launches every operation of a loop body as a separate task, and at
these sizes the launches cost more than the arithmetic. XLA compiles a *small* while loop into
one function instead when the loop touches fewer bytes than a threshold (1 KiB by default) and
holds nothing it must hand to a library (a matrix library call, a custom call). The window's
loops are written to hold no such operation, and rnnpb raises the threshold to 1 MiB, so the
whole regression compiles into one function: this halves the on-line step's time
(``rnnpb bench``, docs/model.md). Loops that move more data — learning, with six sequences at
once — keep their library calls and are not affected.

XLA reads its flags once, when JAX starts its CPU backend, so the setting takes effect only if
rnnpb is imported before the first JAX computation of the process. Set ``XLA_FLAGS`` yourself
with an ``--xla_backend_extra_options`` of your own (it then wins), or ``RNNPB_XLA_DEFAULTS=0``
to leave XLA's defaults untouched.
"""

from __future__ import annotations

import os
import sys
import warnings
from collections.abc import MutableMapping

SMALL_LOOP_OPTION = "xla_cpu_small_while_loop_byte_threshold"
SMALL_LOOP_BYTES = 1 << 20
FLAG = f"--xla_backend_extra_options={SMALL_LOOP_OPTION}={SMALL_LOOP_BYTES}"


def configure(environ: MutableMapping[str, str] | None = None) -> bool:
    """Add :data:`FLAG` to ``XLA_FLAGS`` unless the user decided otherwise.

    Returns whether the flag was added. Warns when JAX's backend has already started in this
    process (the flag can no longer take effect there).
    """
    environ = os.environ if environ is None else environ
    if environ.get("RNNPB_XLA_DEFAULTS", "1").strip() == "0":
        return False
    flags = environ.get("XLA_FLAGS", "")
    if "xla_backend_extra_options" in flags:
        return False
    # First: XLA stops reading flags at the first word that is not one ("--name=value").
    environ["XLA_FLAGS"] = f"{FLAG} {flags}".strip()
    if environ is os.environ and backend_started():
        warnings.warn(
            "JAX started before rnnpb was imported, so rnnpb's XLA setting does not apply in "
            "this process and the on-line step runs about twice as slow; import rnnpb before "
            f"the first JAX computation, or set XLA_FLAGS={FLAG}", RuntimeWarning, stacklevel=3)
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
