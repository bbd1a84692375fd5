"""``rnnpb serve`` stopped by SIGTERM (what a service manager or ``kill`` sends) cleans up as
Ctrl-C does: its temporary working folder is gone."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path


def test_sigterm_removes_the_serves_temporary_folder(model_dir, tmp_path):
    env = dict(os.environ, TMPDIR=str(tmp_path), PYTHONPATH=str(Path(__file__).parents[2] / "src"))
    process = subprocess.Popen(
        [sys.executable, "-m", "rnnpb.cli", "serve", "--model", str(model_dir), "--port", "0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env=env,
    )
    try:
        deadline = time.monotonic() + 90
        assert process.stdout is not None
        for line in process.stdout:
            if line.startswith("rnnpb dashboard:"):
                break
            assert time.monotonic() < deadline, "the server did not start"
        assert list(tmp_path.glob("rnnpb-serve-*")), "no working folder was made"
        process.send_signal(signal.SIGTERM)
        assert process.wait(timeout=30) in (0, 130)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
        if process.stdout is not None:
            process.stdout.close()
    assert not list(tmp_path.glob("rnnpb-serve-*"))
