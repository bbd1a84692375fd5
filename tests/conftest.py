"""The test suite makes the process-wide choices a library leaves to its user (importing rnnpb
sets none): XLA's loop setting, before the first JAX computation of the test process, and the
compiled programs kept on disk for the next test process (rnnpb._xla.compilation_cache)."""

import rnnpb
from rnnpb import _xla

rnnpb.configure_xla()
_xla.compilation_cache()
