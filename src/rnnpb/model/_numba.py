"""How the model's kernels are compiled: :func:`kernel`, numba's ``njit`` with rnnpb's options.

Every function of :data:`KERNEL_MODULES` that the fast paths run is decorated with
:func:`kernel`: compiled on its first call for the types it is given (float32 for the fast
paths, float64 for the reference), for this machine's processor, with the floating-point
freedoms that let the compiler use vector instructions — contraction into fused multiply-adds,
reassociation of sums, no signed zeros — and without those that would let it assume no NaN or
infinity (the on-line step tests its results for them).

The machine code is kept on disk beside the compiled JAX programs (``numba-<digest>`` in
:func:`rnnpb._xla.cache_folder`; ``RNNPB_XLA_CACHE`` moves it, ``0`` turns it off), in a folder
named by a digest of the kernel modules' source and numba's version: numba checks only a
function's own file for changes, and a kernel calls functions of other files. Deleting the
folder is always safe.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar, cast

import numba
from numba.core import config as numba_config

from rnnpb import _xla

KERNEL_MODULES = ("equations.py", "online.py")
"""The modules of :mod:`rnnpb.model` whose functions are kernels (their source names the
cache)."""

FASTMATH = frozenset({"contract", "reassoc", "nsz"})

_Function = TypeVar("_Function", bound=Callable[..., Any])


def _cache_folder() -> Path | None:
    base = _xla.cache_folder()
    if base is None:
        return None
    digest = hashlib.sha256(numba.__version__.encode())
    here = Path(__file__).parent
    for name in KERNEL_MODULES:
        digest.update((here / name).read_bytes())
    folder = base / f"numba-{digest.hexdigest()[:16]}"
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    return folder


_FOLDER = _cache_folder()
if _FOLDER is not None:
    numba_config.CACHE_DIR = str(_FOLDER)  # pyright: ignore[reportAttributeAccessIssue]  # set at run time


def kernel(function: _Function) -> _Function:
    """``function`` compiled by numba on its first call (see the module's docstring)."""
    compiled = numba.njit(
        cache=_FOLDER is not None, fastmath=set(FASTMATH), error_model="numpy", nogil=True
    )(function)
    return cast("_Function", compiled)
