"""Robot domains written the way PlanSys2, ROSPlan and RoboCup@Work stacks write them,
checked, planned and run end to end through the command line (data/peer_patterns):

* battery_patrol: durative actions, a numeric battery, durations from numbers, a
  constant of the domain, ``-type`` without its space, ``(:metric minimize
  (total-time))``, and a knowledge-base problem whose goal is given at run time;
* work_cell: classical actions with action costs, ``object`` among the declared
  types, upper-case names with dashes, a snapshot with its goal commented out;
* lamp_photo: required concurrency (two durative actions that must overlap).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from plan_bridge.cli import main

DATA = Path(__file__).parent / "data" / "peer_patterns"
PATROL = DATA / "battery_patrol"
CELL = DATA / "work_cell"
LAMP = DATA / "lamp_photo"


def _json(capsys: pytest.CaptureFixture[str], *args: str) -> dict[str, object]:
    code = main([*args, "--json"])
    captured = capsys.readouterr()
    data: dict[str, object] = json.loads(captured.out)
    data["exit"], data["stderr"] = code, captured.err
    return data


def test_a_temporal_numeric_patrol_with_a_total_time_metric(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["check", str(PATROL)]) == 0
    out = capsys.readouterr().out
    assert "patrol.pddl: temporal+numeric problem, planned by kairos" in out
    assert "battery_patrol: OK (2 problem(s) checked)" in out

    plan = _json(capsys, "plan", str(PATROL), "--problem", "patrol")
    assert plan["exit"] == 0 and plan["status"] == "solved"
    steps = plan["plan"]
    assert isinstance(steps, list)
    # The battery (25) does not last the tour (30): the robot charges first.
    assert steps[0] == "(recharge r1)" and steps[-1] == "(inspect r1 wpc)"
    assert isinstance(plan["makespan"], float) and plan["makespan"] > 15

    run = _json(capsys, "run", str(PATROL), "--problem", "patrol", "--quiet")
    assert run["exit"] == 0 and run["goal_reached"] and run["executed"] == steps


def test_the_knowledge_base_problem_takes_its_goal_at_run_time(
    capsys: pytest.CaptureFixture[str],
) -> None:
    # Numbers in the goal too: come back charged.
    goal = "(inspected wpc) (robot_at r1 charger) (>= (battery r1) 50)"
    assert main(["check", str(PATROL), "--goal", goal]) == 0
    assert "kb.pddl: 3 actions, 5 objects, 2 goal atoms (given with --goal)" in (
        capsys.readouterr().err
    )
    run = _json(capsys, "run", str(PATROL), "--goal", goal, "--quiet")
    assert run["exit"] == 0 and run["goal_reached"]
    executed = run["executed"]
    assert isinstance(executed, list)
    assert "(inspect r1 wpc)" in executed and executed[-1] == "(recharge r1)"


def test_a_work_cell_with_action_costs_and_knowledge_base_names(
    capsys: pytest.CaptureFixture[str],
) -> None:
    plan = _json(capsys, "plan", str(CELL), "--problem", "order")
    assert plan["exit"] == 0 and plan["planner"] == "fast-downward"
    steps = plan["plan"]
    assert isinstance(steps, list)
    assert steps[0].startswith("(move_base youbot-1 start ")  # PDDL names: case-insensitive
    run = _json(capsys, "run", str(CELL), "--problem", "order", "--quiet")
    assert run["exit"] == 0 and run["goal_reached"]

    # The snapshot's goal is commented out: empty, with the warning; --goal fills it,
    # in the knowledge base's spelling.
    assert main(["run", str(CELL), "--problem", "snapshot"]) == 0
    err = capsys.readouterr().err
    assert "snapshot.pddl:18:1: the goal is empty" in err
    run = _json(
        capsys, "run", str(CELL), "--problem", "snapshot", "--goal", "(object-on AXIS-2 WS-02)"
    )
    assert run["exit"] == 0 and run["goal_reached"]
    assert run["executed"] == [
        "(move_base youbot-1 start sh-01)",
        "(perceive youbot-1 sh-01)",
        "(pick youbot-1 sh-01 axis-2)",
        "(stow youbot-1 platform-left axis-2)",
        "(move_base youbot-1 sh-01 ws-02)",
        "(unstow youbot-1 platform-left axis-2)",
        "(place youbot-1 ws-02 axis-2)",
    ]
    assert "problem snapshot.pddl, goal (object-on AXIS-2 WS-02)" in str(run["stderr"])


def test_required_concurrency_is_planned_with_overlapping_actions(
    capsys: pytest.CaptureFixture[str],
) -> None:
    plan = _json(capsys, "plan", str(LAMP))
    assert plan["exit"] == 0
    actions = plan["actions"]
    assert isinstance(actions, list)
    lamp, photo = actions
    assert lamp["action"] == "(switch-on lamp1)" and photo["action"] == "(photograph hall lamp1)"
    # The photograph happens while the lamp is lit: within the switch-on.
    assert lamp["start"] <= photo["start"]
    assert photo["start"] + photo["duration"] <= lamp["start"] + lamp["duration"]


def test_required_concurrency_runs_with_symbolic_skills(
    capsys: pytest.CaptureFixture[str],
) -> None:
    run = _json(capsys, "run", str(LAMP), "--quiet")
    assert run["exit"] == 0 and run["goal_reached"]
