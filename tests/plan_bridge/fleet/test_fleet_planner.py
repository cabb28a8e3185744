"""Planning a fleet robot by robot: plans side by side, kept where they still hold."""

from __future__ import annotations

import dataclasses
import gc
import time
from typing import Any

import pytest

from plan_bridge.belief import FactSnapshot
from plan_bridge.execution.semantics import ActionModel
from plan_bridge.fleet.jobs import jobs_of
from plan_bridge.fleet.planner import FleetPlanner, _Planning
from plan_bridge.maps.tasks import RouteTasks
from plan_bridge.planning.types import PlanResult, PlanStatus

pytestmark = pytest.mark.timeout(120)

SWAP = [("at", "apple", "shelf_top"), ("at", "pear", "desk_top")]


def start(task: Any) -> FactSnapshot:
    return FactSnapshot(task.initial_facts, ActionModel(task).initial_values())


def test_two_robots_plan_apart_and_work_side_by_side(kairos: Any, house: Any) -> None:
    view = RouteTasks(house(rover=True))
    task = view.task_for(view.belief(), SWAP)
    fleet = FleetPlanner(kairos, view)
    result = fleet.solve(task, timeout=30)
    assert result.solved and result.planner == "kairos"
    robots = {step.arguments[0] for step in result.actions}
    assert robots == {"robot", "rover"}
    # Each robot carries one object: both start at time 0.
    firsts = {r: min(s.start or 0.0 for s in result.actions if s.arguments[0] == r) for r in robots}
    assert firsts == {"robot": 0.0, "rover": 0.0}
    assert ActionModel(task).check_plan(result.actions, start(task)).valid


def test_a_robot_whose_plan_still_holds_keeps_it(kairos: Any, house: Any) -> None:
    view = RouteTasks(house(rover=True))
    task = view.task_for(view.belief(), SWAP)
    fleet = FleetPlanner(kairos, view)
    first = fleet.solve(task, timeout=30)
    again = fleet.solve(task, timeout=30)
    assert again.solved and again.planner == "kept"
    assert "2 of 2 robots kept their plans" in again.warnings
    assert [str(s) for s in again.actions] == [str(s) for s in first.actions]


def test_one_job_is_planned_with_the_two_nearest_robots(kairos: Any, house: Any) -> None:
    view = RouteTasks(house(rover=True))
    task = view.task_for(view.belief(), [("at", "pear", "desk_top")])
    result = FleetPlanner(kairos, view).solve(task, timeout=30)
    assert result.solved
    assert ActionModel(task).check_plan(result.actions, start(task)).valid


def test_a_robot_the_belief_does_not_place_gets_no_part_not_even_as_a_helper(
    kairos: Any, house: Any
) -> None:
    """A robot whose node died mid-drive is nowhere in the belief (left out of plans)."""
    model = house(rover=True)
    ghost = dataclasses.replace(model.robots[0], name="ghost")
    view = RouteTasks(dataclasses.replace(model, robots=(*model.robots, ghost)))
    belief = view.belief()
    nowhere = FactSnapshot(
        [f for f in belief if "ghost" not in f[1:]],
        {k: v for k, v in belief.values.items() if "ghost" not in k[1:]},
    )
    task = view.task_for(nowhere, SWAP)
    assert "ghost" not in task.objects
    fleet = FleetPlanner(kairos, view)
    result = fleet.solve(task, timeout=30)
    assert result.solved and {s.arguments[0] for s in result.actions} <= {"robot", "rover"}
    # A share with no plan alone asks a robot with no share to help (none but the ghost
    # here), else the nearest placed robot: never the ghost.
    facts = start(task)
    plan = _Planning(facts, frozenset(), time.monotonic() + 30, None, 0.0, ("robot", "rover"))
    shares = {"robot": jobs_of([("at", "pear", "desk_top")], ["robot"], facts, view), "rover": []}
    failed = PlanResult(PlanStatus.UNSOLVABLE, [])
    helped = fleet._with_helper("robot", shares, plan, failed)
    assert helped.solved and {s.arguments[0] for s in helped.actions} <= {"robot", "rover"}


def test_one_robot_is_planned_as_the_inner_planner_does(kairos: Any, house: Any) -> None:
    view = RouteTasks(house())
    task = view.task_for(view.belief(), SWAP)
    result = FleetPlanner(kairos, view).solve(task, timeout=30)
    assert result.solved and {s.arguments[0] for s in result.actions} == {"robot"}


def test_robots_look_for_a_lost_object_at_different_places_at_once(kairos: Any, house: Any) -> None:
    # Nobody knows where the apple is: the robot (kitchen) and the rover (bedroom)
    # each look at a place of their own, both from the start.
    view = RouteTasks(house(rover=True))
    belief = view.belief()
    facts = FactSnapshot({f for f in belief if "apple" not in f[1:]}, belief.values)
    task = view.task_for(facts, [("holding", "robot", "apple")])
    result = FleetPlanner(kairos, view).solve(task, timeout=30)
    assert result.solved
    searches = {s.arguments[0]: s.arguments[2] for s in result.actions if s.action == "search"}
    assert set(searches) == {"robot", "rover"}
    assert searches["robot"] != searches["rover"]
    firsts = {
        r: min(s.start or 0.0 for s in result.actions if s.arguments[0] == r) for r in searches
    }
    assert firsts == {"robot": 0.0, "rover": 0.0}


def test_a_lost_object_is_looked_for_only_where_it_was_not_looked_for_yet(
    kairos: Any, house: Any
) -> None:
    # The apple is not on the desk (the robot looked): the task names the desk, so
    # the fleet's parts know it, and nobody looks there again.
    view = RouteTasks(house(rover=True))
    belief = view.belief()
    facts = {f for f in belief if "apple" not in f[1:]} | {("absent", "apple", "desk_top")}
    task = view.task_for(FactSnapshot(facts, belief.values), [("holding", "robot", "apple")])
    assert ("absent", "apple", "desk_top") in task.initial_facts
    result = FleetPlanner(kairos, view).solve(task, timeout=30)
    assert result.solved
    assert {s.arguments[2] for s in result.actions if s.action == "search"} == {"shelf_top"}


def test_the_fleet_keeps_models_only_for_its_last_tasks(kairos: Any, house: Any) -> None:
    # A day of orders plans hundreds of tasks: the planner's action models (each holds
    # its task) must not pile up. (Weak keys did: a model's task kept its key alive.)
    view = RouteTasks(house(rover=True))
    fleet = FleetPlanner(kairos, view)
    places = ("desk_top", "shelf_top")
    for n in range(60):
        view._tasks.clear()  # a new task object every time
        goal = [("at", "apple", places[n % 2]), ("at", "pear", places[(n + 1) % 2])]
        assert fleet.solve(view.task_for(view.belief(), goal), timeout=30).solved
    gc.collect()
    models = [o for o in gc.get_objects() if isinstance(o, ActionModel)]
    assert len(models) <= 40
