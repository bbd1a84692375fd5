"""The figures choose no matplotlib backend and draw without one."""

import subprocess
import sys


def test_importing_and_drawing_choose_no_backend(tmp_path):
    # A fresh interpreter, so that no other test has chosen a backend before.
    code = f"""
import os, sys
os.environ.pop("MPLBACKEND", None)
import numpy as np
from rnnpb.analysis import figures
import matplotlib
assert "matplotlib.pyplot" not in sys.modules
figures.plot_training({{"set 1": [(0, 1.0), (10, 1e-3), (100, 1e-4)]}},
                      {str(tmp_path / "training.png")!r})
assert "matplotlib.pyplot" not in sys.modules
assert matplotlib.rcParams._get_backend_or_none() is None
"""
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "training.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
