"""Where to look for a lost object: places ranked by fit, a task that searches them,
and the verdict when none is left."""

from __future__ import annotations

from typing import Any

import pytest

from plan_bridge.belief import FactSnapshot
from plan_bridge.belief.whereabouts import ABSENT
from plan_bridge.maps.model import Gate, Place, RobotInfo, WorldModel
from plan_bridge.maps.search import ObjectNotFoundError, kind_of, search_order, search_tiers
from plan_bridge.maps.tasks import RouteTasks


def flat() -> WorldModel:
    """One room with a fridge, a table, a desk, a closed cupboard, a locked safe and a
    charger; a soda (coke) and a water on the desk, a robot in the room."""
    spots = {
        "fridge_in": ("fridge", "fridge", 1.0),
        "table_top": ("table", "table", 3.0),
        "desk_top": ("desk", "desk", 5.0),
        "cupboard_in": ("cupboard", "cabinet", 7.0),
        "safe_in": ("safe", "safe", 9.0),
        "dock": ("charger", "charger", 11.0),
    }
    places = {"room": Place("room", 0.0, 0.0, "room", aliases=("room",))}
    gates = {}
    for spawn, (fixture, category, x) in spots.items():
        places[spawn] = Place(spawn, x, 1.0, "room", (spawn,), fixture, aliases=(spawn,))
        closed = fixture in ("cupboard", "safe")
        gates[fixture] = Gate(
            fixture,
            "fixture",
            not closed,
            fixture == "safe",
            is_charger=fixture == "charger",
            spawns=(spawn,),
            category=category,
        )
    return WorldModel(
        "flat",
        (RobotInfo("robot", "room", 90.0, 1.0, 0.5),),
        places,
        gates,
        {},
        {"soda": "desk_top", "water": "desk_top"},
        {"soda": "coke", "water": "water"},
        {name: name for name in places},
        {name: "spawn" for name in spots} | {"room": "room"},
    )


def lost_soda(*absent: str, water: str = "desk_top") -> FactSnapshot:
    view = RouteTasks(flat())
    facts = {f for f in view.belief() if f[1] != "soda"}
    facts = {f for f in facts if not (f[0] == "at" and f[1] == "water")}
    facts.add(("at", "water", water))
    facts |= {(ABSENT, "soda", place) for place in ("desk_top", *absent)}
    return FactSnapshot(facts, view.belief().values)


def test_drinks_are_looked_for_in_fridges_and_on_tables_before_other_places() -> None:
    tiers = search_tiers(flat(), lost_soda(), "soda")
    assert tiers[0] == ["cupboard_in", "fridge_in", "table_top"]


def test_places_where_objects_of_its_category_lie_come_first() -> None:
    # No other coke: a water on the table says nothing about a soda (another category).
    assert search_tiers(flat(), lost_soda(water="table_top"), "soda")[0] == [
        "cupboard_in",
        "fridge_in",
        "table_top",
    ]
    model = flat()
    model.item_categories["water"] = "coke"
    assert search_tiers(model, lost_soda(water="fridge_in"), "soda")[0] == ["fridge_in"]


def test_locked_closed_locations_and_chargers_are_not_searched() -> None:
    places = {p for tier in search_tiers(flat(), lost_soda(), "soda") for p in tier}
    assert "safe_in" not in places
    assert "dock" not in places


def test_places_searched_are_not_searched_again() -> None:
    tiers = search_tiers(flat(), lost_soda("fridge_in", "table_top", "cupboard_in"), "soda")
    assert tiers == []


def test_the_task_of_a_lost_object_lets_the_robot_search_the_first_place_in_order() -> None:
    view = RouteTasks(flat())
    task = view.task_for(lost_soda(), [("holding", "robot", "soda")])
    may_hold = {f for f in task.initial_facts if f[0] == "may-hold"}
    assert may_hold == {("may-hold", "fridge_in", "soda")}
    assert "fridge_in" in task.objects_of_type("spot")


def test_only_a_task_with_a_lost_object_carries_the_search_action() -> None:
    # Grounded over every robot, object and place, an unusable search action made a
    # fleet's plans an order of magnitude slower: tasks that look for nothing drop it.
    view = RouteTasks(flat())
    lost = view.task_for(lost_soda(), [("holding", "robot", "soda")])
    seen = lost_soda()
    found = FactSnapshot(seen | {("at", "soda", "table_top")}, seen.values)
    goal = [("holding", "robot", "soda")]
    assert "search" in lost.actions and "search" not in view.task_for(found, goal).actions
    assert "search" in view.task_for(found, goal, every_action=True).actions


def test_the_search_order_weighs_fit_against_the_way_there() -> None:
    metres = {"fridge_in": 1.4, "table_top": 3.2, "cupboard_in": 7.1, "desk_top": 5.1}
    assert search_order(flat(), lost_soda(), "soda", metres) == [
        "fridge_in",
        "table_top",
        "cupboard_in",
    ]
    # Where objects of its category lie is likelier: worth a longer way.
    model = flat()
    model.item_categories["water"] = "coke"
    order = search_order(
        model, lost_soda(water="cupboard_in"), "soda", metres | {"cupboard_in": 2.0}
    )
    assert order[0] == "cupboard_in"


def test_places_the_robots_cannot_reach_are_not_in_the_search_order() -> None:
    assert search_order(flat(), lost_soda(), "soda", {"table_top": 3.0}) == ["table_top"]


def test_an_object_in_no_place_left_ends_with_the_places_searched() -> None:
    view = RouteTasks(flat())
    facts = lost_soda("fridge_in", "table_top", "cupboard_in")
    with pytest.raises(ObjectNotFoundError) as caught:
        view.task_for(facts, [("holding", "robot", "soda")])
    assert caught.value.item == "soda"
    assert caught.value.searched == ["cupboard_in", "desk_top", "fridge_in", "table_top"]
    assert "soda not found" in str(caught.value)


def test_an_object_the_map_did_not_know_joins_its_objects() -> None:
    view = RouteTasks(flat())
    facts = FactSnapshot({*view.belief(), ("at", "cup0", "table_top")}, view.belief().values)
    task = view.task_for(facts, [("holding", "robot", "cup0")])
    assert "cup0" in task.objects
    assert view.objects()["cup0"] == "item"


@pytest.mark.parametrize(
    ("category", "kind"),
    [("coke", "drink"), ("water_bottle", "drink"), ("banana", "food"), ("lamp", "")],
)
def test_object_categories_have_kinds(category: str, kind: str) -> None:
    assert kind_of(category) == kind


def test_search_tiers_fit_any_world_model(house: Any) -> None:
    # A model whose locations have no category: every place is one tier.
    facts = FactSnapshot({("at", "robot", "kitchen"), (ABSENT, "apple", "desk_top")})
    assert search_tiers(house(), facts, "apple") == [["shelf_top"]]


def test_each_robot_gets_a_place_of_its_own_and_keeps_it_on_its_way(house: Any) -> None:
    view = RouteTasks(house(rover=True))
    start = view.belief()
    lost = {f for f in start if "apple" not in f[1:]}
    facts = FactSnapshot(lost, start.values)
    robots = ["robot", "rover"]
    # The nearest place by each robot's own route: the robot (kitchen) the desk, the
    # rover (bedroom) the shelf.
    given = view.search_shares(facts, "apple", robots, remember=True)
    assert given == {"robot": "desk_top", "rover": "shelf_top"}
    # Both are believed at the other's room now: each keeps the place it was given.
    swapped = (lost - {("at", "robot", "kitchen"), ("at", "rover", "bedroom")}) | {
        ("at", "robot", "bedroom"),
        ("at", "rover", "kitchen"),
    }
    moved = FactSnapshot(swapped, start.values)
    assert view.search_shares(moved, "apple", robots) == given
    fresh = RouteTasks(house(rover=True))
    assert fresh.search_shares(moved, "apple", robots) == {
        "robot": "shelf_top",
        "rover": "desk_top",
    }
