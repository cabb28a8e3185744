"""A task view's helpers: the planner gets the task's facts only; a new task's map
atoms replace the old ones in the belief."""

from __future__ import annotations

from typing import Any

from plan_bridge.belief import Belief, FactSnapshot
from plan_bridge.execution.semantics import ActionModel
from plan_bridge.execution.task_view import TaskView, adopt_map_atoms, project
from plan_bridge.maps.tasks import RouteTasks


def test_the_planner_gets_the_facts_of_the_tasks_objects_only(house: Any) -> None:
    view = RouteTasks(house())
    assert isinstance(view, TaskView)
    task = view.task_for(view.belief(), [("at", "apple", "shelf_top")])
    belief = view.belief()
    seen = project(FactSnapshot(belief, belief.values), task)
    assert ("at", "apple", "desk_top") in seen
    assert ("at", "pear", "shelf_top") not in seen  # the pear is not the task's
    assert ("isopen", "corridor") not in seen  # nor the open hallway
    assert seen.values == {("battery-level", "robot"): 90.0}


def test_a_new_task_brings_its_routes_into_the_belief(house: Any) -> None:
    view = RouteTasks(house())
    goal = [("at", "apple", "shelf_top")]
    first = view.task_for(view.belief(), goal)
    belief = Belief(view.belief())
    adopt_map_atoms(view, belief, first, ActionModel(first).initial_values())
    assert ("route", "kitchen", "shelf_top") in belief.facts
    assert ("at", "pear", "shelf_top") in belief.facts  # what the task does not hold stays
    # The robot is found at the bedroom's doorway: the next task has its place.
    belief.observe(
        [(("at", "robot", "kitchen"), False), (("at", "robot", "corridor_door_bedroom"), True)]
    )
    second = view.task_for(belief.facts, goal)
    adopt_map_atoms(view, belief, second, ActionModel(second).initial_values())
    assert ("route", "corridor_door_bedroom", "shelf_top") in belief.facts
    assert ("route", "kitchen", "shelf_top") not in belief.facts
    assert belief.values[("metres", "corridor_door_bedroom", "shelf_top")] > 0
    assert belief.values[("battery-level", "robot")] == 90.0
