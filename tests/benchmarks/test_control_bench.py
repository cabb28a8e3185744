"""Smoke test of benchmarks/control_bench.py: it runs in quick mode and prints its table.

No timing assertions: the numbers depend on the machine and its load.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.timeout(180)
def test_control_bench_quick_compares_with_and_without_the_hook() -> None:
    proc = subprocess.run(
        [
            sys.executable,
            str(ROOT / "benchmarks" / "control_bench.py"),
            "--quick",
            "--states",
            "50",
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=150,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    for line in (
        "before the hook",
        "with the hook, no control",
        "with a controller attached",
        "hook cost, no control:",
        "noise (same code twice):",
    ):
        assert line in proc.stdout, proc.stdout
