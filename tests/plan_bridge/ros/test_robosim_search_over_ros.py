"""Looking for things over ROS 2 (issue 36): ``plan-bridge run domains/robosim_search
--ros`` finds the soda somebody moved and fetches it; the soda taken away ends with exit
1 and the reason, naming it and the places searched. The robot node runs pyrobosim and
the events; the executive learns of them through the skills' observations only."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("smach.ros.rclpy_api", reason="needs rclpy (the ros extra)")
pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")

pytestmark = [pytest.mark.ros, pytest.mark.timeout(240)]

ROOT = Path(__file__).resolve().parents[3]
SEARCH = ROOT / "domains" / "robosim_search"
#: Python starting twice, pyrobosim and the planner: seconds, not minutes.
RUN_TIMEOUT = 200


def run_ros(events: str, seed: int) -> subprocess.CompletedProcess[str]:
    # DDS on this machine, in the random domain tests/conftest.py chose for this run.
    env = {**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    assert env.get("ROS_DOMAIN_ID")
    return subprocess.run(
        [
            sys.executable, "-m", "plan_bridge", "run", str(SEARCH), "--ros", "--json",
            "--events", str(SEARCH / "events" / f"{events}.yaml"), "--seed", str(seed),
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env=env,
        timeout=RUN_TIMEOUT,
    )  # fmt: skip


def test_a_moved_object_is_searched_for_and_fetched_over_ros() -> None:
    result = run_ros("moved", 3)
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["goal_reached"] and data["ros"]["robot"] == "started"
    assert any(step.startswith("(search robot soda") for step in data["executed"])
    assert data["world_changes"] == 1


def test_an_object_taken_away_ends_over_ros_with_exit_1_naming_it_and_the_places() -> None:
    result = run_ros("taken", 2)
    assert result.returncode == 1, result.stderr
    data = json.loads(result.stdout)
    assert data["outcome"] == "aborted"
    assert data["explanation"].startswith("soda not found")
    assert "searched 8: counter_left, counter_right," in data["explanation"]
    assert "soda not found" in result.stderr
