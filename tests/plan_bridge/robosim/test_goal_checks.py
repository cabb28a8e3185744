"""What blocks a goal in a world model built by hand (no pyrobosim needed)."""

from __future__ import annotations

import pytest

from plan_bridge.robosim.goal_checks import goal_blockers
from plan_bridge.robosim.problem import Gate, RobotInfo, Spot, WorldModel, problem_text

SHUT = "closed and locked (robots open and close hallways and locations; none unlocks)"


def house(
    *, hall_open: bool = True, desk_locked: bool = False, holding: str | None = None
) -> WorldModel:
    """Two rooms joined by a hallway; a desk (one spawn) in the kitchen, a shelf in
    the bedroom; a robot in the kitchen, an apple on the desk."""
    spots = {
        "kitchen": Spot("kitchen", "area", 0.0, 0.0, "kitchen"),
        "bedroom": Spot("bedroom", "area", 10.0, 0.0, "bedroom"),
        "hall_door_kitchen": Spot("hall_door_kitchen", "door", 4.0, 0.0, "kitchen", "hall"),
        "hall_door_bedroom": Spot("hall_door_bedroom", "door", 6.0, 0.0, "bedroom", "hall"),
        "desk_top": Spot("desk_top", "spawn", 1.0, 1.0, "kitchen", "desk"),
        "shelf_top": Spot("shelf_top", "spawn", 9.0, 1.0, "bedroom", "shelf"),
    }
    gates = {
        "hall": Gate("hall", "hall", hall_open, not hall_open),
        "desk": Gate("desk", "fixture", not desk_locked, desk_locked, spawns=("desk_top",)),
        "shelf": Gate("shelf", "fixture", True, False, spawns=("shelf_top",)),
    }
    return WorldModel(
        "house",
        (RobotInfo("robot", "kitchen", 90.0, 1.0, 0.5, holding),),
        spots,
        gates,
        {"apple": None if holding == "apple" else "desk_top", "pear": "shelf_top"},
        {"hall": ("hall_door_kitchen", "hall_door_bedroom")},
        {"hall": 2.0},
    )


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
def test_a_goal_the_robot_can_reach_has_no_blockers(goal: list[tuple[str, ...]]) -> None:
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
def test_atoms_that_contradict_each_other_are_named(goal: list[tuple[str, ...]], says: str) -> None:
    assert says in goal_blockers(house(), goal)


@pytest.mark.parametrize(
    ("goal", "says"),
    [
        (("At", "robot", "bedroom"), f"robot cannot get from kitchen to bedroom: hall is {SHUT}"),
        (("Searched", "shelf_top"), f"no robot can get to shelf_top: hall is {SHUT}"),
        (("Holding", "robot", "pear"), f"no robot can get to pear on shelf_top: hall is {SHUT}"),
        (
            ("At", "apple", "shelf_top"),
            f"no robot that can get to apple on desk_top can bring it to shelf_top: hall is {SHUT}",
        ),
        (("IsLocked", "desk"), "desk is not locked and no robot action locks"),
    ],
)
def test_what_a_closed_locked_hallway_blocks_is_named(goal: tuple[str, ...], says: str) -> None:
    blockers = goal_blockers(house(hall_open=False), [goal])
    assert len(blockers) == 1 and blockers[0].startswith(says)


def test_a_locked_location_blocks_what_is_in_it_and_what_goes_into_it() -> None:
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


def test_a_robot_holding_an_object_and_shut_in_with_no_open_location_cannot_empty_its_hand() -> (
    None
):
    model = house(hall_open=False, desk_locked=True, holding="apple")
    assert goal_blockers(model, [("HandEmpty", "robot")]) == [
        "robot holds apple and can reach no open location to put it"
    ]
    assert goal_blockers(model, [("At", "apple", "shelf_top")]) == [
        f"robot holds apple and cannot get to shelf_top: hall is {SHUT}"
    ]


def test_the_problem_text_lists_facts_per_robot_item_gate_and_room() -> None:
    text = problem_text(house(hall_open=False, desk_locked=True), [("At", "robot", "bedroom")])
    for line in (
        "(At robot kitchen)",
        "(bot-ready robot)",
        "(HandEmpty robot)",
        "(= (battery-level robot) 90)",
        "(At apple desk_top)",
        "(Has desk apple)",
        "(IsLocked desk)",
        "(IsLocked hall)",
        "(IsOpen shelf)",
        "(spawn-of desk_top desk)",
        "(reaches-gate hall_door_kitchen hall)",
        "(same-room kitchen desk_top)",
        "(same-room desk_top kitchen)",
        "(hall-ends hall_door_bedroom hall_door_kitchen hall)",
        "(= (metres hall_door_kitchen hall_door_bedroom) 2)",
        "(:goal (and (At robot bedroom)))",
    ):
        assert line in text
    assert "(IsOpen desk)" not in text and "(same-room kitchen bedroom)" not in text
