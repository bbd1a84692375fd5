"""rnnpb: a recurrent neural network with parametric bias as a mirror system (Ito & Tani 2004).

Importing rnnpb sets nothing: no environment variable, backend or global. The one process-wide
choice rnnpb recommends is :func:`configure_xla` (XLA compiles rnnpb's small JAX loops whole);
call it before the first JAX computation (the ``rnnpb`` command does).
"""

from rnnpb._xla import configure as configure_xla

__version__ = "0.1.0"

__all__ = ["__version__", "configure_xla"]
