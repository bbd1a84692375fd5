"""rnnpb: a recurrent neural network with parametric bias as a mirror system (Ito & Tani 2004)."""

__version__ = "0.1.0"
