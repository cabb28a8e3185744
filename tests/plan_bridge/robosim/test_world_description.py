"""pyrobosim worlds read into the task level's model (places, doorways, hallways), and
goals in pyrobosim's vocabulary over them."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")

from plan_bridge.maps.goals import GoalError, parse_goal
from plan_bridge.robosim.buildings import Building, write_building
from plan_bridge.robosim.description import WorldModelError, describe_world
from plan_bridge.robosim.loading import load_world_file

FETCH = Path(__file__).resolve().parents[3] / "domains" / "robosim_fetch"


def test_test_world_gives_places_for_rooms_spawns_and_doorways(test_world_model) -> None:
    model = test_world_model
    assert [r.name for r in model.robots] == ["robot"]
    assert model.robots[0].place == "kitchen"
    assert model.items["apple0"] == "my_desk_desktop"
    assert model.item_place("apple0") == "my_desk_desktop"
    assert model.gates["table0"].is_locked and model.gates["table0"].is_open
    assert not model.gates["trash"].is_open
    hall = model.halls["hall_bedroom_kitchen"]
    assert hall.ends == ("hall_bedroom_kitchen_door_kitchen", "hall_bedroom_kitchen_door_bedroom")
    assert hall.rooms == ("kitchen", "bedroom")
    # The way through runs from one doorway to the other.
    ends = [model.places[end].xy for end in hall.ends]
    assert math.dist(hall.path[0], ends[0]) < 1e-6 and math.dist(hall.path[-1], ends[1]) < 1e-6
    assert hall.length == pytest.approx(
        sum(math.dist(p, q) for p, q in zip(hall.path, hall.path[1:], strict=False))
    )
    desk = model.places["my_desk_desktop"]
    assert (desk.room, desk.spawns, desk.fixture) == ("bedroom", ("my_desk_desktop",), "my_desk")
    assert model.place_of("counter0_left") == "counter0_left"
    assert model.spot_kinds["hall_bedroom_kitchen_door_bedroom"] == "door"


def test_goal_vocabulary_is_pyrobosims_and_locations_become_their_spawns(test_world_model) -> None:
    model = test_world_model
    assert parse_goal("(At apple0 table0_tabletop)", model) == [("at", "apple0", "table0_tabletop")]
    assert parse_goal("(and (At robot my_desk) (HandEmpty robot))", model) == [
        ("at", "robot", "my_desk_desktop"),
        ("handempty", "robot"),
    ]
    assert parse_goal("(At apple0 table0) (isopen trash)", model) == [
        ("has", "table0", "apple0"),
        ("isopen", "trash"),
    ]
    assert parse_goal("(Has my_desk_desktop soda) (Holding robot gala)", model) == [
        ("at", "soda", "my_desk_desktop"),
        ("holding", "robot", "gala"),
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
    model = describe_world(load_world_file(FETCH / "world.yaml"))
    assert model.gates["charger"].is_charger
    assert model.chargers() == ["charger_dock"]
    assert not model.gates["fridge"].is_open
    robot = model.robots[0]
    assert (robot.battery, robot.drain, robot.speed) == (25.0, 2.5, 0.5)


def test_a_world_name_like_a_domain_symbol_is_refused(
    tmp_path: Path, test_world_file: Path
) -> None:
    text = test_world_file.read_text().replace("$DATA", str(test_world_file.parent))
    world = tmp_path / "w.yaml"
    world.write_text(text.replace("name: gala", "name: spot"))
    with pytest.raises(WorldModelError, match="'spot' has the name of a type"):
        describe_world(load_world_file(world))


@pytest.mark.parametrize("connection", ["auto", "angle", "points"])
def test_every_hallway_has_two_doorways_of_its_own_inside_its_rooms(
    tmp_path: Path, connection: str
) -> None:
    # With auto and angle hallways, pyrobosim puts both ends of every hallway of a room
    # at the room's centre, inside the table that stands there: the doorways are where
    # the hallway meets the room's free space instead, one per hallway and room.
    folder = write_building(tmp_path / connection, Building(rooms=4, connection=connection))
    world = load_world_file(folder / "world.yaml")
    model = describe_world(world)
    ends = [end for hall in model.halls.values() for end in hall.ends]
    assert len(ends) == 2 * len(model.halls) == len(set(ends)) == 8
    for hall in model.halls.values():
        for end, room in zip(hall.ends, hall.rooms, strict=True):
            place = model.places[end]
            assert place.room == room and place.doors == (hall.name,)
            assert world.get_room_by_name(room).is_collision_free([place.x, place.y])


def test_a_room_whose_pose_is_inside_its_table_stands_for_a_free_point(tmp_path: Path) -> None:
    folder = write_building(tmp_path / "b", Building(rooms=1))
    world = load_world_file(folder / "world.yaml")
    room = world.get_room_by_name("room_0_0")
    assert not room.is_collision_free(room.nav_poses[0])  # pyrobosim's: in the table
    place = describe_world(world).places["room_0_0"]
    assert room.is_collision_free([place.x, place.y])
