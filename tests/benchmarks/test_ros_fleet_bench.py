"""Smoke test of benchmarks/ros_fleet.py: a short order stream over ROS 2, a robot's node
killed, in one process beside it.

No timing thresholds: the numbers depend on the machine and its load. What is checked is
that every figure is measured, and that with a robot killed no order is lost or done
twice and the dead robot's orders were taken over.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("smach.ros.rclpy_api", reason="needs rclpy (the ros extra)")
pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "benchmarks" / "ros_fleet.py"


@pytest.mark.timeout(600)
def test_a_quick_stream_over_ros_loses_no_order_when_a_robot_node_is_killed(
    tmp_path: Path,
) -> None:
    figures = tmp_path / "figures.json"
    done = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick", "--json", str(figures)],
        capture_output=True,
        text=True,
        timeout=580,
        check=False,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    [result] = json.loads(figures.read_text())
    for where in ("local", "ros"):
        tally = result[where]["tally"]
        assert tally["open"] == [] and tally["done_twice"] == [], tally
        assert sum(tally["counts"].values()) == result[where]["orders"]["orders"] > 0
    kill = result["ros"]["kill"]
    assert kill["gone_s"] is not None and kill["gone_s"] > 0, kill
    assert "kill -> gone" in done.stdout
