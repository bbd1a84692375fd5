"""MuJoCo, imported when a simulation or a renderer is first made, with an OpenGL chosen then.

MuJoCo picks its OpenGL from ``MUJOCO_GL`` once, when ``import mujoco`` runs. Importing rnnpb
must not set that variable, so rnnpb imports MuJoCo only here, when the program first needs it
(:func:`rnnpb.robot.load_model`, :class:`~rnnpb.robot.MujocoRobot`,
:class:`~rnnpb.robot.RobotRenderer`). If ``MUJOCO_GL`` is set, or the program imported MuJoCo
itself, that choice stands. Otherwise rnnpb chooses headless rendering: EGL where the EGL
library is installed, else OSMesa (software, slower), and says clearly when neither is.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import sys
from collections.abc import Callable, MutableMapping
from types import ModuleType

from rnnpb.errors import ConfigError

# Headless OpenGL in order of preference, each with the library MuJoCo's context loads.
HEADLESS: tuple[tuple[str, str], ...] = (("egl", "EGL"), ("osmesa", "OSMesa"))


def _loadable(library: str) -> bool:
    name = ctypes.util.find_library(library)
    if name is None:
        return False
    try:
        ctypes.CDLL(name)
    except OSError:
        return False
    return True


def choose_gl(
    environ: MutableMapping[str, str] | None = None, loadable: Callable[[str], bool] = _loadable
) -> str:
    """Set ``MUJOCO_GL`` to the first headless OpenGL whose library loads, unless it is set.

    Returns the value in effect. Raises :class:`~rnnpb.errors.ConfigError` when neither EGL nor
    OSMesa is installed.
    """
    environ = os.environ if environ is None else environ
    if environ.get("MUJOCO_GL", "").strip():
        return environ["MUJOCO_GL"]
    for backend, library in HEADLESS:
        if loadable(library):
            environ["MUJOCO_GL"] = backend
            return backend
    raise ConfigError(
        "MuJoCo needs OpenGL to render and found neither EGL (libEGL) nor OSMesa (libOSMesa): "
        "install one (e.g. apt install libegl1, or libosmesa6), or set MUJOCO_GL yourself "
        "(glfw needs a display)"
    )


def import_mujoco() -> ModuleType:
    """The ``mujoco`` module; on its first import, with ``MUJOCO_GL`` chosen by
    :func:`choose_gl`."""
    if "mujoco" not in sys.modules:
        choose_gl()
    import mujoco

    return mujoco
