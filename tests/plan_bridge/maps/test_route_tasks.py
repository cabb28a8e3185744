"""The task view of a map: the places a goal needs, routes between them, built in
memory (no PDDL text read)."""

from __future__ import annotations

from typing import Any

import pytest

from plan_bridge.belief import FactSnapshot
from plan_bridge.maps.tasks import RouteTasks, TaskError


def values(task: Any) -> dict[tuple[str, ...], float]:
    assert task.spec is not None
    return dict(task.spec.values)


def test_the_task_holds_the_places_the_goal_needs_and_routes_between_them(house: Any) -> None:
    view = RouteTasks(house())
    task = view.task_for(view.belief(), [("at", "apple", "shelf_top")])
    assert task.problem_text is None and task.spec is not None  # built, not read
    assert set(task.objects_of_type("spot")) == {"kitchen", "desk_top", "shelf_top"}
    assert set(task.objects) == {
        "robot",
        "apple",
        "kitchen",
        "desk_top",
        "shelf_top",
        "desk",
        "shelf",
    }
    assert ("route", "desk_top", "shelf_top") in task.initial_facts
    assert values(task)[("metres", "kitchen", "shelf_top")] == pytest.approx(
        4 + 2 + 10**0.5, abs=1e-3
    )
    assert ("spawn-of", "shelf_top", "shelf") in task.initial_facts
    assert ("at", "apple", "desk_top") in task.initial_facts
    assert task.goal_facts == (("at", "apple", "shelf_top"),)
    # The pear is not the goal's: not an object of the task.
    assert "pear" not in task.objects


def test_a_closed_hallway_is_crossed_between_its_doorways_once_opened(house: Any) -> None:
    model = house(hall_open=False)
    # Closed, and not locked: a robot may open it.
    model.gates["corridor"] = type(model.gates["corridor"])("corridor", "hall", False, False)
    view = RouteTasks(model)
    task = view.task_for(view.belief(), [("at", "robot", "bedroom")])
    assert {"corridor_door_kitchen", "corridor_door_bedroom", "corridor"} <= set(task.objects)
    assert (
        "hall-ends",
        "corridor_door_kitchen",
        "corridor_door_bedroom",
        "corridor",
    ) in task.initial_facts
    assert ("reaches-gate", "corridor_door_kitchen", "corridor") in task.initial_facts
    assert ("route", "kitchen", "bedroom") not in task.initial_facts
    assert ("route", "kitchen", "corridor_door_kitchen") in task.initial_facts


def test_a_locked_hallway_leaves_no_route_and_no_doorway(house: Any) -> None:
    view = RouteTasks(house(hall_open=False))
    task = view.task_for(view.belief(), [("at", "robot", "bedroom")])
    assert "corridor_door_kitchen" not in task.objects
    assert not any(f[0] == "route" and "bedroom" in f for f in task.initial_facts)


def test_the_same_belief_gives_the_same_task_and_a_move_another(house: Any) -> None:
    view = RouteTasks(house())
    belief = view.belief()
    goal = [("at", "apple", "shelf_top")]
    first = view.task_for(belief, goal)
    assert view.task_for(FactSnapshot(belief, belief.values), goal) is first
    moved = FactSnapshot(
        (belief - {("at", "robot", "kitchen")}) | {("at", "robot", "corridor_door_bedroom")},
        belief.values,
    )
    second = view.task_for(moved, goal)
    assert second is not first and "corridor_door_bedroom" in second.objects
    assert view.closed_for(second) == frozenset()


def test_the_belief_at_the_start_knows_every_object_and_gate(house: Any) -> None:
    belief = RouteTasks(house()).belief()
    assert {("at", "pear", "shelf_top"), ("has", "shelf", "pear"), ("isopen", "corridor")} <= belief
    assert ("handempty", "robot") in belief and ("bot-ready", "robot") in belief
    assert belief.values[("battery-level", "robot")] == 90.0


def test_a_robot_the_belief_does_not_place_is_an_error(house: Any) -> None:
    view = RouteTasks(house())
    belief = view.belief()
    lost = FactSnapshot(belief - {("at", "robot", "kitchen")}, belief.values)
    with pytest.raises(TaskError, match="does not say where robot is"):
        view.task_for(lost, [("at", "apple", "shelf_top")])


def test_a_robot_the_belief_does_not_place_is_left_out_while_another_is_placed(
    house: Any,
) -> None:
    """A robot whose node died mid-drive is nowhere in the belief: the task is the
    other robots'; asked for by name, it is still an error."""
    view = RouteTasks(house(rover=True))
    belief = view.belief()
    lost = FactSnapshot(belief - {("at", "robot", "kitchen")}, belief.values)
    task = view.task_for(lost, [("at", "apple", "shelf_top")])
    assert "rover" in task.objects and "robot" not in task.objects
    with pytest.raises(TaskError, match="does not say where robot is"):
        view.task_for(lost, [("at", "apple", "shelf_top")], robots=["robot", "rover"])


def test_the_spec_writes_the_task_as_pddl(house: Any) -> None:
    view = RouteTasks(house())
    task = view.task_for(view.belief(), [("at", "apple", "shelf_top")])
    text = task.pddl_problem
    assert text is not None
    for line in (
        "(:domain robosim)",
        "robot - bot",
        "(at robot kitchen)",
        "(route desk_top shelf_top)",
        "(= (top-speed robot) 1)",
        "(:goal (and (at apple shelf_top)))",
    ):
        assert line in text
