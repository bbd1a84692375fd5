"""Figures the notes quote from committed benchmark output say what that output holds."""

from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _rows(name: str) -> list[dict]:
    text = (ROOT / "benchmarks" / name).read_text(encoding="utf-8")
    return [json.loads(line) for line in text.splitlines() if line.strip()]


def _note(name: str) -> str:
    return " ".join((ROOT / "notes" / name).read_text(encoding="utf-8").split())


def test_the_familiarity_widths_range_is_the_committed_output_s():
    rows = _rows("safety_familiarity_width_dev.jsonl")
    aucs = [row["familiarity_auc"] for row in rows]
    widths = [row["width"] for row in rows]
    quoted = f"widths {min(widths):.2f}–{max(widths):.2f} gave AUC {min(aucs):.3f}–{max(aucs):.3f}"
    assert quoted == "widths 0.02–0.08 gave AUC 0.855–0.871"
    assert quoted in _note("2026-12-06-teaching-seeds-suite.md")


def test_the_safety_labels_share_of_starts_is_the_committed_output_s():
    rows = _rows("safety_labels_dev.jsonl")
    without_skip = {
        s for row in rows if row["transient"] == 0 for s in row["learned_unsafe_share_of_starts"]
    }
    quoted = f"{100 * min(without_skip):.0f}–{100 * max(without_skip):.0f} % of starts"
    assert quoted in _note("2026-12-06-teaching-seeds-suite.md")
    assert all(
        share == 0
        for row in rows
        if row["transient"] >= 5
        for share in row["learned_unsafe_share_of_starts"]
    )
