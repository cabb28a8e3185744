"""`plan-bridge check` and `plan-bridge run --json` on every mission."""

from __future__ import annotations

import json

import pytest
from pr2_missions import plan_bridge

# (mission, whether seed 1 must reach the goal, text its progress output (-v) must show)
MISSIONS = [
    ("fetch_drink", False, "step 1:"),
    ("door_opening", False, "step 1:"),
    ("recharge", False, "step 1:"),
    ("table_clearing", True, "step 1:"),
    ("two_robot_delivery", True, "_PARALLEL_"),
]


@pytest.mark.timeout(180)
@pytest.mark.parametrize(("name", "must_succeed", "shown"), MISSIONS, ids=[m[0] for m in MISSIONS])
def test_plan_bridge_check_passes_and_run_prints_json_results(
    name: str, must_succeed: bool, shown: str
) -> None:
    check, run = plan_bridge(
        ["check", f"domains/{name}"], ["run", f"domains/{name}", "--seed", "1", "--json", "-v"]
    )
    assert check.returncode == 0, check.stderr
    assert f"{name}: OK (3 problem(s) checked)" in check.stdout
    assert run.returncode in ((0,) if must_succeed else (0, 1)), run.stderr
    assert "Traceback" not in run.stderr
    data = json.loads(run.stdout)
    assert data["target"] == name and data["problem"] == "p01.pddl"
    assert data["seed"] == 1 and data["fail_rate"] == 0.2  # the default of domain folders
    assert data["goal_reached"] == (run.returncode == 0)
    for key in ("outcome", "actions_executed", "replans", "planner_calls", "faults_injected"):
        assert key in data
    assert "summary:" in run.stderr and shown in run.stderr
