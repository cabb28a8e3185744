"""The timed courier mission: temporal + numeric planning, dispatch, faults, replanning."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from plan_bridge.execution.executive import Executive
from plan_bridge.pddl.task import load_task

ROOT = Path(__file__).resolve().parents[2]
FOLDER = ROOT / "domains" / "timed_courier"

pytestmark = pytest.mark.timeout(240)


def run_mission(problem: str, *, seed: int, fail_rate: float) -> tuple[Executive, object]:
    sys.path.insert(0, str(ROOT / "domains"))
    try:
        from timed_courier.skills import setup
    finally:
        sys.path.remove(str(ROOT / "domains"))
    task = load_task(FOLDER / "domain.pddl", FOLDER / "problems" / problem)
    mission = setup(task, seed=seed, fail_rate=fail_rate)
    mission.world.time_scale = 0.001
    executive = Executive(task, mission.skills, "auto")
    executive.time_scale = 0.001
    assert executive.execute() == "succeeded"
    return executive, mission.world


def test_the_courier_reaches_its_numeric_goal_through_the_held_fire_door() -> None:
    executive, world = run_mission("p01.pddl", seed=1, fail_rate=0.0)
    assert world.goal_reached()  # type: ignore[attr-defined]
    assert executive.report.replans == 0
    assert executive.belief.values[("delivered",)] >= 1
    executed = executive.report.executed
    assert any(step.startswith("(hold-door") for step in executed)
    assert any(step.startswith("(pass-door") for step in executed)


@pytest.mark.parametrize("seed", [1, 3, 5])
def test_with_late_halfway_and_drifting_actions_the_courier_replans_to_the_goal(
    seed: int,
) -> None:
    executive, world = run_mission("p01.pddl", seed=seed, fail_rate=0.2)
    assert world.goal_reached()  # type: ignore[attr-defined]
    assert world.faults  # type: ignore[attr-defined]
    # What the world really drained is what the belief holds (observed numbers).
    true_level = world.values["(charge-level courier)"]  # type: ignore[attr-defined]
    assert executive.belief.values[("charge-level", "courier")] == pytest.approx(true_level)


def test_check_names_the_kind_and_the_engines(capsys: pytest.CaptureFixture[str]) -> None:
    from plan_bridge.cli import main

    assert main(["check", str(FOLDER)]) == 0
    out = capsys.readouterr().out
    assert "p01.pddl: temporal+numeric problem, planned by kairos then tamer" in out


def test_plan_json_gives_start_duration_and_makespan(capsys: pytest.CaptureFixture[str]) -> None:
    import json

    from plan_bridge.cli import main

    domain, problem = FOLDER / "domain.pddl", FOLDER / "problems" / "p01.pddl"
    assert main(["plan", str(domain), str(problem), "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert payload["planner"] == "kairos"
    ends = [a["start"] + a["duration"] for a in payload["actions"]]
    assert payload["makespan"] == pytest.approx(max(ends))


def test_run_json_adds_planned_and_executed_makespans(capsys: pytest.CaptureFixture[str]) -> None:
    import json

    from plan_bridge.cli import main

    code = main(["run", str(FOLDER), "--problem", "p01", "--json", "--quiet"])
    captured = capsys.readouterr()
    assert code == 0, captured.err + captured.out
    payload = json.loads(captured.out)
    assert payload["goal_reached"] is True
    assert payload["makespan_planned"] > 0 and payload["makespan_executed"] >= 0
