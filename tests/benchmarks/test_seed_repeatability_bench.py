"""Smoke test of benchmarks/seed_repeatability.py: one seed, two runs per configuration."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.timeout(300)
def test_seed_repeatability_compares_fresh_runs_of_each_configuration(tmp_path: Path) -> None:
    out = tmp_path / "seeds.json"
    proc = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "seed_repeatability.py"),
         "--seeds", "1", "--problems", "p01", "--repeats", "2", "--busy", "1",
         "--json", str(out)],
        cwd=ROOT, capture_output=True, text=True, timeout=280, check=False,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stdout + proc.stderr
    data = json.loads(out.read_text())
    assert [row["configuration"] for row in data["rows"]] == [
        "timed_courier p01 seed 1",
        "two_robot_delivery --concurrent seed 1",
    ]
    for row in data["rows"]:
        first, second = row["runs"]
        assert "error" not in first and first["executed"]
        assert row["same"] == {"steps": True, "decisions": True, "outcome": True, "faults": True}
        assert first == second
    assert "2/2 configurations repeated exactly over 2 runs" in proc.stdout


def test_seed_repeatability_needs_two_runs_to_compare() -> None:
    proc = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "seed_repeatability.py"), "--repeats", "1"],
        cwd=ROOT, capture_output=True, text=True, timeout=60, check=False,
    )  # fmt: skip
    assert proc.returncode == 2
    assert "--repeats must be at least 2" in proc.stderr


@pytest.mark.timeout(120)
def test_seed_repeatability_times_the_dispatch_on_both_clocks() -> None:
    proc = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "seed_repeatability.py"),
         "--dispatch-cost", "2"],
        cwd=ROOT, capture_output=True, text=True, timeout=110, check=False,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert re.fullmatch(
        r"timed_courier p01 dispatch, median of 2: simulated clock [\d.]+ ms, "
        r"wall clock [\d.]+ ms\n",
        proc.stdout,
    )
