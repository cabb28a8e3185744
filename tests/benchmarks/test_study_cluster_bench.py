"""Smoke test of benchmarks/study_cluster.py on a tiny study: it prints a row per executor.

No timing assertions: the numbers depend on the machine and its load.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "benchmarks" / "study_cluster.py"
ROOMS = str(ROOT / "tests" / "plan_bridge" / "data" / "rooms")


@pytest.mark.slow
@pytest.mark.timeout(300)
def test_study_cluster_bench_compares_local_and_cluster_executors(tmp_path: Path) -> None:
    pytest.importorskip("distributed")
    done = subprocess.run(
        [
            sys.executable,
            str(SCRIPT),
            "--runs",
            "1",
            "--workers",
            "1",
            "--targets",
            ROOMS,
            "--approaches",
            "planned",
            "--fault-rates",
            "0,0.5",
            "--keep",
            str(tmp_path),
        ],
        capture_output=True,
        text=True,
        timeout=280,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert "rows identical across executors" in done.stdout
    for executor in ("`--jobs 1`", "`--jobs 2`", "`--cluster local:1`"):
        assert f"| {executor} |" in done.stdout
    assert (tmp_path / "c1" / "report.md").exists()
