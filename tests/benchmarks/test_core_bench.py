"""Smoke test of benchmarks/core_bench.py: it runs in quick mode and reports every scenario,
in one process or as the spread over fresh processes.

No timing assertions: the numbers depend on the machine and its load.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "benchmarks" / "core_bench.py"

SCENARIOS = (
    "chain",
    "remap_loop",
    "concurrence",
    "concurrence_busy",
    "iterator_small",
    "iterator_medium",
    "iterator_large",
    "nested",
    "nested_key",
    "nested_logged",
    "nested_key_logged",
    "preempt_event",
    "preempt_sleep",
    "preempt_poll",
    "call_function",
    "call_method",
    "handloop",
    "peer_py_trees",
    "peer_transitions",
)


@pytest.mark.timeout(180)
def test_core_bench_quick_reports_every_scenario(tmp_path: Path) -> None:
    out = tmp_path / "core_bench.json"
    proc = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick", "--processes", "1", "--json", str(out)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert proc.returncode == 0, f"stdout:\n{proc.stdout}\nstderr:\n{proc.stderr}"
    missing = [n for n in SCENARIOS if not re.search(rf"^{n}\s", proc.stdout, re.MULTILINE)]
    assert not missing, f"scenarios missing from the table: {missing}\n{proc.stdout}"
    assert "Targets" in proc.stdout
    assert re.search(r"^\s+(PASS|MISS)\s", proc.stdout, re.MULTILINE)
    data = json.loads(out.read_text(encoding="utf-8"))
    assert data["mode"] == "quick"
    assert set(SCENARIOS) <= set(data["results"])


@pytest.mark.timeout(300)
def test_core_bench_compares_with_an_original_core_in_every_logging_configuration(
    tmp_path: Path,
) -> None:
    # Any SMACH-compatible core can stand in for the original: ours, loaded as a second
    # package from the source tree, exercises the loading and the comparison table.
    out = tmp_path / "core_bench.json"
    proc = subprocess.run(
        [
            sys.executable,
            str(SCRIPT),
            "--quick",
            "--processes",
            "1",
            "--original",
            str(ROOT / "src"),
            "--json",
            str(out),
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=240,
        check=False,
    )
    assert proc.returncode == 0, f"stdout:\n{proc.stdout}\nstderr:\n{proc.stderr}"
    assert "Against the original SMACH core" in proc.stdout
    for row in ("chain            repeated", "chain            first", "nested           first"):
        assert row in proc.stdout, proc.stdout
    data = json.loads(out.read_text(encoding="utf-8"))
    same_run = data["original_same_run"]
    assert set(same_run) == {"default", "noop", "format"}
    assert "remap_loop/first/original" in same_run["noop"]
    aims = data["same_run_original"]["aims"]
    assert {a["aim"].split(" ")[0] for a in aims} >= {"chain", "remap_loop", "nested", "iterator"}


@pytest.mark.timeout(300)
def test_core_bench_reports_the_spread_of_each_scenario_over_fresh_processes(
    tmp_path: Path,
) -> None:
    out = tmp_path / "core_bench.json"
    proc = subprocess.run(
        [
            sys.executable,
            str(SCRIPT),
            "--quick",
            "--processes",
            "2",
            "--only",
            "nested,nested_key",
            "--cpu-time",
            "--original",
            str(ROOT / "src"),
            "--json",
            str(out),
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=240,
        check=False,
    )
    assert proc.returncode == 0, f"stdout:\n{proc.stdout}\nstderr:\n{proc.stderr}"
    assert "2 fresh processes" in proc.stdout
    nesting = ("nested", "nested_key", "nested_logged", "nested_key_logged")
    for name in nesting:
        assert re.search(rf"^{name}\s+us/execution\s", proc.stdout, re.MULTILINE), proc.stdout
        assert re.search(rf"^\s+(PASS|MISS)\s+{name}\s", proc.stdout, re.MULTILINE), proc.stdout
    assert "chain" not in proc.stdout  # (--only)
    data = json.loads(out.read_text(encoding="utf-8"))
    assert data["processes"] == 2
    assert len({run["pid"] for run in data["runs"]}) == 2
    rows = {row["scenario"]: row for row in data["spread"]}
    assert set(nesting) <= set(rows)
    assert all(len(rows[name]["per_process"]) == 2 for name in nesting)
    cells = data["original"]["cells"]
    assert {(c["scenario"], c["mode"]) for c in cells} == {
        (s, m) for s in ("nested", "nested_key") for m in ("repeated", "first")
    }
    assert all(len(c["ratios"]) == 2 for c in cells)
    assert {a["aim"] for a in data["original"]["aims"]} == {
        "nested (repeated)",
        "nested (first)",
        "nested_key (repeated)",
        "nested_key (first)",
    }
