"""Smoke test of benchmarks/temporal_repeatability.py: one seed, two runs, compared."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.timeout(240)
def test_temporal_repeatability_compares_the_runs_of_each_seed(tmp_path: Path) -> None:
    out = tmp_path / "repeat.json"
    proc = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "temporal_repeatability.py"),
         "--seeds", "1", "--repeats", "2", "--problems", "p01", "--json", str(out)],
        cwd=ROOT, capture_output=True, text=True, timeout=200, check=False,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    data = json.loads(out.read_text())
    (row,) = data["rows"]
    assert len(row["runs"]) == 2 and all(r["exit"] in (0, 1) for r in row["runs"])
    assert row["repeats"] == (row["runs"][0] == row["runs"][1])
    assert "configurations repeated exactly over 2 runs" in proc.stdout
