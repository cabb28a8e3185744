"""Smoke test of benchmarks/temporal_bench.py: tiny sizes, every section reported.

No timing assertions: the numbers depend on the machine and its load.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.timeout(240)
def test_temporal_bench_quick_reports_overhead_jitter_and_a_long_plan(tmp_path: Path) -> None:
    out = tmp_path / "temporal.json"
    proc = subprocess.run(
        [
            sys.executable,
            str(ROOT / "benchmarks" / "temporal_bench.py"),
            "--quick",
            "--trials",
            "1",
            "--steps",
            "8",
            "--scales",
            "0.002",
            "--json",
            str(out),
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=200,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    for line in (
        "(a) plan + dispatch against TAMER alone",
        "plan + dispatch / TAMER solve:",
        "(b) dispatch jitter",
        "timed courier p01",
        "patrol (8 steps)",
        "(c) 8-action temporal plan",
        "the same steps as a sequential plan",
    ):
        assert line in proc.stdout, proc.stdout
    results = json.loads(out.read_text())
    assert results["overhead"]["direct_solve_s"] > 0
    assert results["overhead"]["ours_plan_dispatch_s"] > 0
    # One row per plan and time scale; every step's start measured once per trial.
    assert [(row["plan"], row["time_scale"]) for row in results["jitter"]] == [
        ("timed courier p01", 0.002),
        ("patrol (8 steps)", 0.002),
    ]
    assert [row["starts"] for row in results["jitter"]] == [14, 8]
    assert results["hundred"]["steps"] == 8


def test_temporal_bench_refuses_a_time_scale_of_zero() -> None:
    proc = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "temporal_bench.py"), "--scales", "0"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert proc.returncode == 2
    assert "--scales: one or more time scales above 0 expected" in proc.stderr
