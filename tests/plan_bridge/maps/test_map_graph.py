"""The map of places: routes over the hallways that are not closed."""

from __future__ import annotations

from typing import Any

import pytest

from plan_bridge.maps.graph import Leg, PlaceMap


def test_a_route_goes_through_rooms_and_hallways_with_their_lengths(house: Any) -> None:
    graph = PlaceMap(house())
    route = graph.route("desk_top", "shelf_top")
    assert route is not None
    assert route.places == (
        "desk_top",
        "corridor_door_kitchen",
        "corridor_door_bedroom",
        "shelf_top",
    )
    assert route.legs[1] == Leg("corridor_door_kitchen", "corridor_door_bedroom", "corridor")
    assert route.halls == ("corridor",)
    # desk (1,1) -> door (4,0) straight, the hallway's 2 m, door (6,0) -> shelf (9,1).
    assert route.length == pytest.approx(2 * (10**0.5) + 2.0)


def test_a_closed_hallway_cuts_the_route_and_what_is_reachable(house: Any) -> None:
    graph = PlaceMap(house())
    assert graph.route("kitchen", "bedroom", closed={"corridor"}) is None
    assert graph.reachable("kitchen", closed={"corridor"}) == {
        "kitchen",
        "corridor_door_kitchen",
        "desk_top",
    }
    inside = graph.reachable("kitchen", closed={"corridor"})
    assert graph.halls_between(inside, {"corridor"}) == ["corridor"]
    assert graph.lengths_from("kitchen")["bedroom"] == pytest.approx(10.0)


def test_places_of_one_room_are_one_drive_apart(house: Any) -> None:
    graph = PlaceMap(house())
    route = graph.route("kitchen", "desk_top")
    assert route is not None and route.legs == (Leg("kitchen", "desk_top", None),)
    assert graph.route("kitchen", "kitchen") is not None
    assert graph.route("kitchen", "nowhere") is None
    assert len(graph) == 6 and graph.links() == 3 + 3 + 1
