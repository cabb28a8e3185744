"""Generated pyrobosim buildings: rooms on a grid, a table in each, parcels to deliver.

For scaling tests and benchmarks (``benchmarks/scale.py``) and for trying plan_bridge
on a building of any size::

    python -m plan_bridge.robosim.buildings out/grid25 --rooms 25 --robots 2 --deliveries 3
    plan-bridge run out/grid25

A building is ``rooms`` square rooms of :attr:`Building.room_m` metres on a grid of
:attr:`Building.pitch_m` metres, each joined to its right and upper neighbour by a
hallway (``conn_method`` ``auto`` by default, pyrobosim's: from room centre to room
centre; ``angle`` and ``points`` are the other two). Each room has a table (at its
centre by default, where ``auto`` hallways pass: pyrobosim then puts their ends inside
the table); the first room a charger. Robots start in rooms spread over the building;
a delivery takes an object from a table to a table far from it. The world folder gets
``world.yaml``, ``locations.yaml`` (the table and the charger) and ``goals.yaml``:
``deliver`` (every delivery, the default) and ``first`` (the first one).

Everything is drawn from ``seed``: the same arguments give the same building.
"""

from __future__ import annotations

import argparse
import math
import random
from dataclasses import dataclass
from pathlib import Path
from typing import Any

__all__ = ["Building", "main", "write_building"]

_CONNECTIONS = ("auto", "angle", "points")
_ITEMS = ("apple", "banana")
_PLANNERS = ("none", "world_graph", "rrt")


@dataclass(frozen=True)
class Building:
    """What to generate (see the module's doc)."""

    rooms: int = 9
    robots: int = 1
    deliveries: int = 1
    seed: int = 0
    connection: str = "auto"
    """pyrobosim's ``conn_method`` of every hallway: ``auto``, ``angle`` or ``points``."""
    table_at_centre: bool = True
    """A room's table at its centre (else against its lower wall)."""
    planner: str = "none"
    """The robots' pyrobosim path planner: ``none`` (plan_bridge's skills drive the map's
    routes and do not use one), ``world_graph`` or ``rrt``. pyrobosim's load time is
    mostly its world graph's (every pair of the graph's nodes checked, once per robot:
    minutes for a large building)."""
    room_m: float = 3.0
    pitch_m: float = 5.0
    battery: float = 100.0
    drain: float = 0.5
    """Battery (percent) per metre."""
    speed: float = 0.5

    def __post_init__(self) -> None:
        if self.rooms < 1 or self.robots < 1 or self.deliveries < 0:
            raise ValueError("a building has at least one room and one robot")
        if self.robots > self.rooms:
            raise ValueError(f"{self.robots} robots need as many rooms, not {self.rooms}")
        if self.connection not in _CONNECTIONS:
            raise ValueError(f"connection must be one of {', '.join(_CONNECTIONS)}")
        if self.planner not in _PLANNERS:
            raise ValueError(f"planner must be one of {', '.join(_PLANNERS)}")

    @property
    def columns(self) -> int:
        return math.ceil(math.sqrt(self.rooms))

    def room(self, index: int) -> str:
        row, column = divmod(index, self.columns)
        return f"room_{row}_{column}"

    def centre(self, index: int) -> tuple[float, float]:
        row, column = divmod(index, self.columns)
        return column * self.pitch_m, row * self.pitch_m


def world_data(spec: Building) -> dict[str, Any]:
    """The pyrobosim world file of ``spec`` as data."""
    rooms = [_room(spec, i) for i in range(spec.rooms)]
    hallways = [_hallway(spec, a, b) for a, b in _neighbours(spec)]
    locations = [_table(spec, i) for i in range(spec.rooms)]
    x, y = spec.centre(0)
    locations.append(
        {
            "name": "charger",
            "category": "charger",
            "parent": spec.room(0),
            "pose": {"position": {"x": x + spec.room_m / 2 - 0.5, "y": y + spec.room_m / 2 - 0.4}},
            "is_charger": True,
        }
    )
    deliveries = _deliveries(spec)
    objects = [
        {"name": name, "category": _ITEMS[n % len(_ITEMS)], "parent": f"table_{spec.room(a)}"}
        for n, (name, a, _) in enumerate(deliveries)
    ]
    return {
        "params": {"name": f"building{spec.rooms}", "object_radius": 0.0375},
        "metadata": {
            "locations": ["$PWD/locations.yaml"],
            "objects": ["$DATA/example_object_data_food.yaml"],
        },
        "robots": [_robot(spec, n) for n in range(spec.robots)],
        "rooms": rooms,
        "hallways": hallways,
        "locations": locations,
        "objects": objects,
    }


def goals(spec: Building) -> dict[str, str]:
    """The named goals of the building's goals.yaml."""
    atoms = [f"(At {name} table_{spec.room(b)}_tabletop)" for name, _, b in _deliveries(spec)]
    if not atoms:
        return {"visit": f"(At {_robot_name(spec, 0)} {spec.room(spec.rooms - 1)})"}
    return {"deliver": f"(and {' '.join(atoms)})", "first": atoms[0]}


def write_building(folder: str | Path, spec: Building) -> Path:
    """Write the world folder of ``spec`` into ``folder``; its path."""
    import yaml

    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    (out / "world.yaml").write_text(
        f"# A generated building: {spec}\n" + yaml.safe_dump(world_data(spec), sort_keys=False),
        encoding="utf-8",
    )
    (out / "locations.yaml").write_text(_LOCATIONS, encoding="utf-8")
    lines = [f"{name}: {goal}" for name, goal in goals(spec).items()]
    (out / "goals.yaml").write_text(
        "# Named goals of the generated building; the first is the default.\n"
        + "\n".join(lines)
        + "\n",
        encoding="utf-8",
    )
    return out


_LOCATIONS = """\
# The furniture of the generated buildings: a table (both long sides reachable) and
# a charging dock.
table:
  footprint:
    type: box
    dims: [0.9, 1.2]
    height: 0.5
  nav_poses:
    - position: {x: -0.75, y: 0.0}
    - position: {x: 0.75, y: 0.0}
      rotation_eul: {yaw: 3.14}
  locations:
    - name: "tabletop"
      footprint:
        type: parent
        padding: 0.1
  color: [0.4, 0.25, 0.1]
charger:
  footprint:
    type: box
    dims: [0.6, 0.3]
    height: 0.1
  locations:
    - name: "dock"
      footprint:
        type: parent
      nav_poses:
        - position: {x: 0.0, y: -0.4}
          rotation_eul: {yaw: 1.57}
  color: [0.4, 0.4, 0.4]
"""


def _robot_name(spec: Building, n: int) -> str:
    return "robot" if spec.robots == 1 else f"robot{n}"


def _start_rooms(spec: Building) -> list[int]:
    """Rooms spread over the building, one per robot."""
    step = spec.rooms / spec.robots
    return sorted({min(spec.rooms - 1, int(n * step)) for n in range(spec.robots)})


def _robot(spec: Building, n: int) -> dict[str, Any]:
    planner: dict[str, Any] = {"type": spec.planner}
    if spec.planner == "none":
        planner = {}
    elif spec.planner == "world_graph":
        planner.update(collision_check_step_dist=0.025, max_connection_dist=10.0)
    else:
        planner.update(
            collision_check_step_dist=0.025,
            max_connection_dist=1.0,
            bidirectional=True,
            rrt_connect=True,
            rrt_star=False,
            max_time=5.0,
        )
    room = _start_rooms(spec)[n]
    x, y = spec.centre(room)
    robot: dict[str, Any] = {
        "name": _robot_name(spec, n),
        "radius": 0.15,
        "location": spec.room(room),
        "pose": {"position": {"x": x - spec.room_m / 2 + 0.5, "y": y - spec.room_m / 2 + 0.5}},
        "initial_battery_level": spec.battery,
        "path_executor": {
            "type": "constant_velocity",
            "linear_velocity": spec.speed,
            "max_angular_velocity": 2.0,
            "dt": 0.1,
            "validate_during_execution": False,
        },
        "grasping": {
            "generator": "parallel_grasp",
            "max_width": 0.175,
            "depth": 0.1,
            "height": 0.04,
            "width_clearance": 0.01,
            "depth_clearance": 0.01,
        },
        "action_execution_options": {"navigate": {"battery_usage": spec.drain}},
    }
    if planner:
        robot["path_planner"] = planner
    return robot


def _room(spec: Building, index: int) -> dict[str, Any]:
    x, y = spec.centre(index)
    return {
        "name": spec.room(index),
        "footprint": {"type": "box", "dims": [spec.room_m, spec.room_m]},
        "pose": {"position": {"x": x, "y": y}},
        "wall_width": 0.2,
    }


def _neighbours(spec: Building) -> list[tuple[int, int]]:
    pairs = []
    for index in range(spec.rooms):
        column = index % spec.columns
        right, up = index + 1, index + spec.columns
        if column + 1 < spec.columns and right < spec.rooms:
            pairs.append((index, right))
        if up < spec.rooms:
            pairs.append((index, up))
    return pairs


def _hallway(spec: Building, a: int, b: int) -> dict[str, Any]:
    hallway: dict[str, Any] = {
        "room_start": spec.room(a),
        "room_end": spec.room(b),
        "width": 0.7,
        "conn_method": spec.connection,
        "is_open": True,
        "is_locked": False,
    }
    (ax, ay), (bx, by) = spec.centre(a), spec.centre(b)
    if spec.connection == "angle":
        hallway["conn_angle"] = math.atan2(by - ay, bx - ax)
    elif spec.connection == "points":
        # From just inside one room to just inside the other, off the centre line.
        inside = spec.room_m / 2 - 0.4
        ux, uy = (bx - ax) / spec.pitch_m, (by - ay) / spec.pitch_m
        ox, oy = -uy * 0.6, ux * 0.6
        hallway["conn_points"] = [
            [ax + ux * inside + ox, ay + uy * inside + oy],
            [bx - ux * inside + ox, by - uy * inside + oy],
        ]
    return hallway


def _table(spec: Building, index: int) -> dict[str, Any]:
    x, y = spec.centre(index)
    if not spec.table_at_centre:
        y -= spec.room_m / 2 - 0.7
    return {
        "name": f"table_{spec.room(index)}",
        "category": "table",
        "parent": spec.room(index),
        "pose": {"position": {"x": x, "y": y}},
    }


def _deliveries(spec: Building) -> list[tuple[str, int, int]]:
    """(object, room it lies in, room it goes to): far apart, drawn from the seed."""
    draw = random.Random(spec.seed)
    result = []
    rooms = list(range(spec.rooms))
    for n in range(spec.deliveries):
        source = draw.choice(rooms)
        far = sorted(rooms, key=lambda r: -math.dist(spec.centre(r), spec.centre(source)))
        target = draw.choice(far[: max(1, len(far) // 3)])
        result.append((f"parcel{n}", source, target))
    return result


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m plan_bridge.robosim.buildings",
        description="Write a generated pyrobosim building (a world folder) for plan-bridge.",
    )
    parser.add_argument("folder", help="the world folder to write")
    parser.add_argument("--rooms", type=int, default=9)
    parser.add_argument("--robots", type=int, default=1)
    parser.add_argument("--deliveries", type=int, default=1)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--connection", choices=_CONNECTIONS, default="auto")
    parser.add_argument("--table-aside", action="store_true", help="tables against a wall")
    parser.add_argument(
        "--planner",
        choices=_PLANNERS,
        default="none",
        help="the robots' pyrobosim path planner (plan_bridge does not use one)",
    )
    args = parser.parse_args(argv)
    try:
        spec = Building(
            args.rooms,
            args.robots,
            args.deliveries,
            args.seed,
            args.connection,
            not args.table_aside,
            args.planner,
        )
    except ValueError as exc:
        parser.error(str(exc))
    folder = write_building(args.folder, spec)
    print(folder)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
