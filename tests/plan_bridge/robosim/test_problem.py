"""The problem generated from pyrobosim worlds, and goals in pyrobosim's vocabulary."""

from __future__ import annotations

from pathlib import Path

import pytest

from plan_bridge.robosim.problem import GoalError, parse_goal, problem_text

FETCH = Path(__file__).resolve().parents[3] / "domains" / "robosim_fetch"

pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")


def test_test_world_gives_its_entities_as_typed_objects_and_facts(test_world_model) -> None:
    model = test_world_model
    assert [r.name for r in model.robots] == ["robot"]
    assert model.robots[0].spot == "kitchen"
    assert model.items["apple0"] == "my_desk_desktop"
    assert model.gates["table0"].is_locked and model.gates["table0"].is_open
    assert not model.gates["trash"].is_open
    assert model.hall_ends["hall_bedroom_kitchen"] == (
        "hall_bedroom_kitchen_door_kitchen",
        "hall_bedroom_kitchen_door_bedroom",
    )
    text = problem_text(model, [("At", "apple0", "table0_tabletop")])
    for line in (
        "robot - bot",
        "(At robot kitchen)",
        "(At apple0 my_desk_desktop)",
        "(Has my_desk apple0)",
        "(IsLocked table0)",
        "(spawn-of table0_tabletop table0)",
        "(hall-ends hall_bedroom_kitchen_door_kitchen hall_bedroom_kitchen_door_bedroom hall_bedroom_kitchen)",
        "(:goal (and (At apple0 table0_tabletop)))",
    ):
        assert line in text
    assert "(IsOpen trash)" not in text


def test_goal_vocabulary_is_pyrobosims_and_locations_become_their_spawns(test_world_model) -> None:
    model = test_world_model
    assert parse_goal("(At apple0 table0_tabletop)", model) == [("At", "apple0", "table0_tabletop")]
    assert parse_goal("(and (At robot my_desk) (HandEmpty robot))", model) == [
        ("At", "robot", "my_desk_desktop"),
        ("HandEmpty", "robot"),
    ]
    assert parse_goal("(At apple0 table0) (isopen trash)", model) == [
        ("Has", "table0", "apple0"),
        ("IsOpen", "trash"),
    ]
    assert parse_goal("(Has my_desk_desktop soda) (Holding robot gala)", model) == [
        ("At", "soda", "my_desk_desktop"),
        ("Holding", "robot", "gala"),
    ]


@pytest.mark.parametrize(
    ("goal", "says"),
    [
        ("(At apple0 tabel0_tabletop)", "did you mean table0_tabletop?"),
        ("(Near robot kitchen)", "unknown predicate 'Near'"),
        ("(Holding apple0 robot)", "apple0 is a object; the form is (Holding ROBOT OBJECT)"),
        ("(At robot counter0)", "has the object spawns counter0_left, counter0_right"),
        ("(At robot hall_bedroom_kitchen)", "one end of a hallway"),
        ("(At apple0 table0_tabletop", "'(' not closed"),
        ("", "is empty"),
    ],
)
def test_bad_goals_say_what_is_wrong_and_what_is_allowed(
    test_world_model, goal: str, says: str
) -> None:
    with pytest.raises(GoalError) as caught:
        parse_goal(goal, test_world_model)
    assert says in str(caught.value)


def test_the_fetch_world_has_a_closed_fridge_a_charger_and_a_battery() -> None:
    from plan_bridge.robosim.loading import load_world_file
    from plan_bridge.robosim.problem import describe_world

    model = describe_world(load_world_file(FETCH / "world.yaml"))
    assert model.gates["charger"].is_charger
    assert not model.gates["fridge"].is_open
    robot = model.robots[0]
    assert (robot.battery, robot.drain, robot.speed) == (25.0, 2.5, 0.5)
    text = problem_text(model, [("IsOpen", "fridge")])
    assert "(is-charger charger)" in text
    assert "(= (battery-level robot) 25)" in text


def test_a_world_name_like_a_domain_symbol_is_refused(
    tmp_path: Path, test_world_file: Path
) -> None:
    from plan_bridge.robosim.loading import load_world_file
    from plan_bridge.robosim.problem import WorldModelError, describe_world

    text = test_world_file.read_text().replace("$DATA", str(test_world_file.parent))
    world = tmp_path / "w.yaml"
    world.write_text(text.replace("name: gala", "name: spawn"))
    with pytest.raises(WorldModelError, match="'spawn' has the name of a type"):
        describe_world(load_world_file(world))
