"""rnnpb: a recurrent neural network with parametric bias as a mirror system (Ito & Tani 2004)."""

from rnnpb import _xla

__version__ = "0.1.0"

# Before any JAX computation: XLA reads its flags once, when its CPU backend starts.
_xla.configure()
