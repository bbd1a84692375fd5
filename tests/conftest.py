"""The test suite makes the process-wide choices a library leaves to its user (importing rnnpb
sets none): XLA's loop setting, before the first JAX computation of the test process."""

import rnnpb

rnnpb.configure_xla()
