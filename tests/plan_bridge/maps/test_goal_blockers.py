"""What blocks a goal in a world model built by hand (no pyrobosim needed)."""

from __future__ import annotations

from typing import Any

import pytest

from plan_bridge.maps.blockers import goal_blockers

SHUT = "closed and locked (robots open and close hallways and locations; none unlocks)"


@pytest.mark.parametrize(
    "goal",
    [
        [("At", "robot", "bedroom")],
        [("At", "apple", "shelf_top")],
        [("Has", "shelf", "apple")],
        [("Holding", "robot", "pear")],
        [("HandEmpty", "robot")],
        [("IsOpen", "desk")],
        [("Searched", "shelf_top")],
        [("At", "robot", "kitchen"), ("IsOpen", "shelf")],
    ],
)
def test_a_goal_the_robot_can_reach_has_no_blockers(
    house: Any, goal: list[tuple[str, ...]]
) -> None:
    assert goal_blockers(house(), goal) == []


@pytest.mark.parametrize(
    ("goal", "says"),
    [
        (
            [("At", "apple", "desk_top"), ("Has", "shelf", "apple")],
            "apple cannot be on desk_top and at shelf at once",
        ),
        (
            [("Has", "desk", "apple"), ("Has", "shelf", "apple")],
            "apple cannot be at desk and at shelf at once",
        ),
        (
            [("Holding", "robot", "apple"), ("At", "apple", "shelf_top")],
            "apple cannot be held by robot and be at shelf_top",
        ),
        (
            [("Holding", "robot", "apple"), ("HandEmpty", "robot")],
            "robot cannot hold apple with its hand empty",
        ),
    ],
)
def test_atoms_that_contradict_each_other_are_named(
    house: Any, goal: list[tuple[str, ...]], says: str
) -> None:
    assert says in goal_blockers(house(), goal)


@pytest.mark.parametrize(
    ("goal", "says"),
    [
        (
            ("At", "robot", "bedroom"),
            f"robot cannot get from kitchen to bedroom: corridor is {SHUT}",
        ),
        (("Searched", "shelf_top"), f"no robot can get to shelf_top: corridor is {SHUT}"),
        (
            ("Holding", "robot", "pear"),
            f"no robot can get to pear on shelf_top: corridor is {SHUT}",
        ),
        (
            ("At", "apple", "shelf_top"),
            f"no robot that can get to apple on desk_top can bring it to shelf_top: corridor is {SHUT}",
        ),
        (("IsLocked", "desk"), "desk is not locked and no robot action locks"),
    ],
)
def test_what_a_closed_locked_hallway_blocks_is_named(
    house: Any, goal: tuple[str, ...], says: str
) -> None:
    blockers = goal_blockers(house(hall_open=False), [goal])
    assert len(blockers) == 1 and blockers[0].startswith(says)


def test_a_locked_location_blocks_what_is_in_it_and_what_goes_into_it(house: Any) -> None:
    model = house(desk_locked=True)
    assert goal_blockers(model, [("Holding", "robot", "apple")]) == [
        f"apple is in desk, which is {SHUT}: no robot can take it out"
    ]
    assert goal_blockers(model, [("Has", "desk", "pear")]) == [
        f"nothing can be put on desk: desk is {SHUT}"
    ]
    assert goal_blockers(model, [("Searched", "desk_top")]) == [
        f"desk_top cannot be searched: desk is {SHUT}"
    ]


def test_a_robot_holding_an_object_and_shut_in_with_no_open_location_cannot_empty_its_hand(
    house: Any,
) -> None:
    model = house(hall_open=False, desk_locked=True, holding="apple")
    assert goal_blockers(model, [("HandEmpty", "robot")]) == [
        "robot holds apple and can reach no open location to put it"
    ]
    assert goal_blockers(model, [("At", "apple", "shelf_top")]) == [
        f"robot holds apple and cannot get to shelf_top: corridor is {SHUT}"
    ]
