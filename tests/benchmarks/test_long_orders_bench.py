"""Smoke test of benchmarks/long_orders.py: a short order stream, killed once and resumed.

No timing or memory thresholds: the numbers depend on the machine and its load. What is
checked is that every figure is measured and that the resumed run ends with the same
orders done, failed and refused as the uninterrupted one.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "benchmarks" / "long_orders.py"


@pytest.mark.timeout(600)
def test_a_quick_stream_measures_memory_and_journal_and_a_killed_run_resumes_the_same(
    tmp_path: Path,
) -> None:
    figures = tmp_path / "figures.json"
    done = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick", "--kills", "1", "--json", str(figures)],
        capture_output=True,
        text=True,
        timeout=580,
        check=False,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    result = json.loads(figures.read_text())
    orders = result["orders"]
    assert orders["orders"] > 0
    ended = sum(orders[k] for k in ("done", "failed", "refused", "cancelled"))
    assert ended == orders["orders"] and orders["queued"] == orders["active"] == 0
    assert result["actions"] > 0 and result["memory"]["max_mb"] > 0
    assert result["journal"]["bytes_per_action"] > 0
    assert result["journal"]["structures"] <= result["journal"]["plan_machines"]
    assert [r["same_orders"] for r in result["resumes"]] == [True], result["resumes"]
    assert "resume: killed" in done.stdout
