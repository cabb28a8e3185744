"""Smoke test of benchmarks/replan_latency.py: one mission, one seed, both planners.

No timing assertions: the numbers depend on the machine and its load.
"""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "benchmarks" / "replan_latency.py"


def _bench() -> ModuleType:
    spec = importlib.util.spec_from_file_location("replan_latency", SCRIPT)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_journal_times_pair_each_failure_with_the_next_step_start() -> None:
    events = [
        {"kind": "plan_computed", "reason": "initial plan", "planning_time_s": 0.2},
        {"kind": "state_entered", "path": "/ROOT/PLAN/01_GO_A_B", "time": 1.0},
        {"kind": "step_finished", "outcome": "aborted", "time": 1.5},
        {"kind": "state_entered", "path": "/ROOT/PLAN/01_GO_A_B/SKILL", "time": 1.6},
        {"kind": "plan_computed", "reason": "replan: go failed", "planning_time_s": 0.01},
        {"kind": "plan_computed", "reason": "replan (plan reused: same state and goal)"},
        {"kind": "state_entered", "path": "/ROOT/PLAN/02_GO_A_C", "time": 1.75},
    ]
    calls, waits = _bench().journal_times(events)
    assert calls == [0.2, 0.01]
    assert waits == [pytest.approx(0.25)]


def test_percentiles_are_nearest_rank() -> None:
    percentile = _bench().percentile
    assert percentile([3.0, 1.0, 2.0, 4.0], 0.5) == 2.0
    assert percentile([float(n) for n in range(1, 21)], 0.95) == 19.0
    assert percentile([], 0.5) == 0.0


@pytest.mark.timeout(240)
def test_quick_run_reports_both_planners_and_their_ratio(tmp_path: Path) -> None:
    out = tmp_path / "latency.json"
    proc = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick", "--json", str(out)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=200,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    assert "replan latency: 1 seeds, fail rate 0.3" in proc.stdout
    assert "FD/this p50" in proc.stdout
    results = json.loads(out.read_text())
    rows = {(row["mission"], row["planner"]): row for row in results["rows"]}
    assert set(rows) == {
        ("fetch_drink", "auto"),
        ("fetch_drink", "fast-downward"),
        ("all", "auto"),
        ("all", "fast-downward"),
    }
    for row in rows.values():
        assert row["calls"] >= 1 and row["call_p50_s"] > 0
    assert set(rows["fetch_drink", "auto"]["planners_won"]) <= {"warm-gbfs", "fast-downward"}
