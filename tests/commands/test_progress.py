"""Long commands show progress on a terminal, and nothing in a log or with --no-progress."""

import io
import sys

from rnnpb.commands import demo
from rnnpb.commands.progress import progress_bar
from rnnpb.experiments import ExperimentConfig


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def _drawn(monkeypatch, stream, **options):
    monkeypatch.setattr(sys, "stderr", stream)
    with progress_bar(total=5, unit="step", desc="interacting", **options) as bar:
        for _ in range(5):
            bar.update(1)
    return stream.getvalue()


def test_the_bar_is_drawn_on_a_terminal_only(monkeypatch):
    assert "interacting" in _drawn(monkeypatch, _Terminal())
    assert _drawn(monkeypatch, io.StringIO()) == ""
    assert _drawn(monkeypatch, _Terminal(), disable=True) == ""


def test_the_demo_says_how_long_it_takes():
    # The measured minutes (docs/experiments.md), twice as long with one worker.
    full, quick_minutes = demo.MEASURED_MINUTES["full"], demo.MEASURED_MINUTES["quick"]
    assert demo._estimate(ExperimentConfig()).startswith(
        f"about {full:.0f} minutes on 2 cores with 2"
    )
    assert demo._estimate(ExperimentConfig(workers=1)).startswith(f"about {2 * full:.0f} minutes")
    quick = ExperimentConfig.quick_run()
    assert demo._estimate(quick).startswith(f"about {quick_minutes:.0f} minute")
    assert not demo._estimate(quick).startswith("about 1 minutes")
