"""Smoke test of benchmarks/robosim_search.py: one seed of the soda taken away on
pyrobosim's test_world, planned and scripted. No timing thresholds: what is checked is
that both runs end as the issue asks (exit as aborted, naming the soda and the places
searched) and that the table is printed."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "benchmarks" / "robosim_search.py"


@pytest.mark.timeout(600)
def test_one_seed_of_a_taken_object_ends_naming_it_within_a_sweep() -> None:
    done = subprocess.run(
        [sys.executable, str(SCRIPT), "--seeds", "1", "--jobs", "1", "--cases", "test_world taken"],
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    rows = [line for line in done.stdout.splitlines() if line.startswith("| test_world taken")]
    assert len(rows) == 2
    assert all("1/1 exit 1 within a sweep" in row for row in rows)
    assert "soda not found" in done.stdout and "trash_top" in done.stdout
