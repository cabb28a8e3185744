"""Paths inside a room: straight, round the furniture, out of it first."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")

import itertools

from shapely.geometry import LineString, Point

from plan_bridge.robosim.buildings import Building, write_building
from plan_bridge.robosim.loading import load_world_file
from plan_bridge.robosim.room_paths import room_path


@pytest.fixture(scope="module")
def room(tmp_path_factory: pytest.TempPathFactory):  # type: ignore[no-untyped-def]
    """A 3 m room with a table (0.9 x 1.2 m) at its centre, (0, 0)."""
    folder = write_building(tmp_path_factory.mktemp("b"), Building(rooms=1))
    return load_world_file(Path(folder) / "world.yaml").get_room_by_name("room_0_0")


def test_a_clear_way_is_straight(room) -> None:  # type: ignore[no-untyped-def]
    assert room_path(room, (-1.0, -1.0), (-1.0, 1.0)) == [(-1.0, -1.0), (-1.0, 1.0)]


def test_the_way_goes_round_the_table_in_free_space_and_stays_short(room) -> None:  # type: ignore[no-untyped-def]
    start, goal = (-1.1, 0.0), (1.1, 0.0)
    path = room_path(room, start, goal)
    assert path[0] == start and path[-1] == goal and len(path) >= 3
    free = room.internal_collision_polygon
    for a, b in itertools.pairwise(path):
        assert free.covers(LineString([a, b]))
        assert math.dist(a, b) > 1e-6  # no point twice
    length = sum(math.dist(a, b) for a, b in itertools.pairwise(path))
    assert length < 2 * math.dist(start, goal)


def test_a_start_inside_the_furniture_leaves_it_first(room) -> None:  # type: ignore[no-untyped-def]
    path = room_path(room, (0.0, 0.0), (-1.1, -1.1))
    free = room.internal_collision_polygon
    assert not free.covers(Point(path[0]))
    assert free.covers(Point(path[1])) and path[-1] == (-1.1, -1.1)
