"""A loaded pyrobosim world read into the task level's :class:`~plan_bridge.maps.model.WorldModel`.

Spots are where a robot can stand: each room's navigation pose, the navigation pose in
front of each object spawn, and each hallway's two **doorways**. A doorway is where the
hallway's centre line leaves the free space of its room (the room's footprint shrunk by
the robot's inflation radius, furniture ignored), a few centimetres inside the room:
for hallways of ``conn_method: points`` that is where pyrobosim puts the hallway's
navigation poses; for ``auto`` and ``angle`` hallways pyrobosim puts them at the
room's centre, often inside the furniture there, so they are not used. Spots within
:data:`MERGE_M` of each other are one place (see :mod:`plan_bridge.maps.model`).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

from plan_bridge.errors import PlanBridgeError
from plan_bridge.maps.model import Gate, Hall, Place, RobotInfo, WorldModel, door_name

__all__ = ["MERGE_M", "WorldModelError", "describe_world", "robot_place"]

#: Spots closer than this (metres) stand at one point: they are one place. (pyrobosim's
#: pddlstream_simple_world has a room's pose 2.1 cm from a counter's.)
MERGE_M = 0.05
#: A robot this close to a place's point (metres) stands at it (the nearest such place:
#: places are at least MERGE_M apart).
AT_PLACE_M = 0.04
#: How far inside its room a doorway stands (metres) from where the hallway leaves it.
DOORWAY_INSET_M = 0.05

#: The domain's type names: no entity of a world may be named like one.
TYPE_NAMES = frozenset({"thing", "bot", "item", "spot", "gate", "hall", "fixture", "object"})
#: The domain's predicate and function names: no entity may be named like one either.
SYMBOL_NAMES = frozenset(
    {"at", "holding", "handempty", "isopen", "islocked", "has", "searched", "bot-ready"}
    | {"route", "hall-ends", "spawn-of", "reaches-gate", "is-charger", "battery-level"}
    | {"drain-per-metre", "top-speed", "metres"}
)


class WorldModelError(PlanBridgeError):
    """A pyrobosim world that cannot be written as a planning problem."""


@dataclass
class _Spot:
    name: str
    kind: str  # "spawn", "room" or "door"
    x: float
    y: float
    room: str
    spawn_of: str | None = None
    door_of: str | None = None


@dataclass
class _Group:
    spots: list[_Spot] = field(default_factory=list)

    def place(self) -> Place:
        order = {"spawn": 0, "room": 1, "door": 2}
        named = min(self.spots, key=lambda s: order[s.kind])
        spawns = tuple(s.name for s in self.spots if s.kind == "spawn")
        fixtures = [s.spawn_of for s in self.spots if s.spawn_of is not None]
        doors = tuple(dict.fromkeys(s.door_of for s in self.spots if s.door_of is not None))
        room = next((s.room for s in self.spots if s.room), "")
        aliases = (named.name, *(s.name for s in self.spots if s.name != named.name))
        return Place(
            named.name,
            named.x,
            named.y,
            room,
            spawns,
            fixtures[0] if fixtures else None,
            doors,
            tuple(dict.fromkeys(aliases)),
        )


def describe_world(world: Any, origin: str = "the world") -> WorldModel:
    """Read a loaded pyrobosim ``World`` (rooms, hallways, locations, spawns, objects,
    robots). Raises :class:`WorldModelError` for names PDDL cannot hold."""
    from pyrobosim.core.locations import ObjectSpawn

    spots: list[_Spot] = []
    for room in world.rooms:
        x, y = _room_point(room)
        spots.append(_Spot(room.name, "room", x, y, room.name))
    gates: dict[str, Gate] = {}
    hall_lines: dict[str, tuple[str, str, tuple[str, str], tuple[tuple[float, float], ...]]] = {}
    radius = float(getattr(world, "inflation_radius", 0.0) or 0.0)
    for hall in world.hallways:
        gates[hall.name] = Gate(hall.name, "hall", bool(hall.is_open), bool(hall.is_locked))
        path = _doorway_path(hall, radius)
        first, last = (
            door_name(hall.name, hall.room_start.name),
            door_name(hall.name, hall.room_end.name),
        )
        spots.append(_Spot(first, "door", *path[0], hall.room_start.name, door_of=hall.name))
        spots.append(_Spot(last, "door", *path[-1], hall.room_end.name, door_of=hall.name))
        hall_lines[hall.name] = (first, last, (hall.room_start.name, hall.room_end.name), path)
    for location in world.locations:
        room = location.parent.name if location.parent is not None else ""
        gates[location.name] = Gate(
            location.name,
            "fixture",
            bool(location.is_open),
            bool(location.is_locked),
            bool(location.is_charger),
            tuple(spawn.name for spawn in location.children),
            str(getattr(location, "category", "") or ""),
        )
        for spawn in location.children:
            if spawn.nav_poses:
                x, y = _xy(spawn.nav_poses[0])
                spots.append(_Spot(spawn.name, "spawn", x, y, room, spawn_of=location.name))
    places, aliases = _merge(spots)
    halls = {
        name: Hall(
            name,
            (aliases[first], aliases[last]),
            rooms,
            sum(math.dist(p, q) for p, q in itertools.pairwise(path)),
            path,
        )
        for name, (first, last, rooms, path) in hall_lines.items()
    }
    items: dict[str, str | None] = {}
    categories: dict[str, str] = {}
    for obj in world.objects:
        parent = obj.parent
        items[obj.name] = parent.name if isinstance(parent, ObjectSpawn) else None
        categories[obj.name] = str(getattr(obj, "category", "") or "")
    kinds = {spot.name: spot.kind for spot in spots}
    partial = WorldModel(
        str(world.name or "world"), (), places, gates, halls, items, categories, aliases, kinds
    )
    robots = tuple(_robot_info(partial, robot, origin) for robot in world.robots)
    model = dataclasses.replace(partial, robots=robots)
    _check_names(model, origin)
    return model


def _xy(pose: Any) -> tuple[float, float]:
    return float(pose.x), float(pose.y)


def _room_point(room: Any) -> tuple[float, float]:
    """Where a robot stands for a room: its navigation pose, or the free point nearest
    to it when furniture stands there (pyrobosim's default is the room's centre)."""
    from shapely.geometry import Point

    from plan_bridge.robosim.room_paths import free_point

    x, y = _xy(room.nav_poses[0])
    free = room.internal_collision_polygon
    if free.is_empty or free.covers(Point(x, y)):
        return x, y
    return free_point(free, (x, y))


def _doorway_path(hall: Any, radius: float) -> tuple[tuple[float, float], ...]:
    """The centre line of ``hall`` from its doorway in its first room to its doorway in
    its second (see the module's doc)."""
    from pyrobosim.utils.polygon import inflate_polygon
    from shapely.geometry import LineString
    from shapely.ops import substring

    line = LineString([(float(p[0]), float(p[1])) for p in hall.points])
    if line.length <= 0:
        point = (float(hall.points[0][0]), float(hall.points[0][1]))
        return (point, point)
    start_shell = inflate_polygon(hall.room_start.polygon, -radius)
    end_shell = inflate_polygon(hall.room_end.polygon, -radius)
    end_from = _first_inside(line, end_shell)
    leave = _last_inside(line, start_shell, before=end_from)
    enter = _first_inside(line, end_shell, after=leave)
    inset = min(DOORWAY_INSET_M, max(0.0, (enter - leave) / 4))
    leave = max(0.0, leave - inset) if leave > 0 else 0.0
    enter = min(line.length, enter + inset) if enter < line.length else line.length
    piece = substring(line, leave, enter)
    coords = [(round(float(x), 4), round(float(y), 4)) for x, y in piece.coords]
    if len(coords) < 2:
        point = line.interpolate(leave)
        coords = [(float(point.x), float(point.y))] * 2
    return tuple(coords)


def _distances_inside(line: Any, shell: Any) -> list[float]:
    """Distances along ``line`` of the ends of its pieces inside ``shell``."""
    from shapely.geometry import Point

    inside = line.intersection(shell)
    pieces = [g for g in getattr(inside, "geoms", [inside]) if not g.is_empty]
    return sorted(line.project(Point(c)) for g in pieces for c in getattr(g, "coords", []))


def _last_inside(line: Any, shell: Any, before: float) -> float:
    """How far along ``line`` it last is inside ``shell`` before distance ``before``
    (0 when it starts outside)."""
    ends = [d for d in _distances_inside(line, shell) if d <= before + 1e-9]
    return ends[-1] if ends else 0.0


def _first_inside(line: Any, shell: Any, after: float = 0.0) -> float:
    """How far along ``line`` it first is inside ``shell`` after distance ``after``
    (its length when it never is)."""
    ends = [d for d in _distances_inside(line, shell) if d >= after - 1e-9]
    return ends[0] if ends else float(line.length)


def _merge(spots: Iterable[_Spot]) -> tuple[dict[str, Place], dict[str, str]]:
    """Places of the spots (those at one point merged) and each spot's place."""
    groups: list[_Group] = []
    for spot in spots:
        for group in groups:
            if any(math.hypot(s.x - spot.x, s.y - spot.y) < MERGE_M for s in group.spots):
                group.spots.append(spot)
                break
        else:
            groups.append(_Group([spot]))
    places: dict[str, Place] = {}
    aliases: dict[str, str] = {}
    for group in groups:
        place = group.place()
        places[place.name] = place
        for name in place.aliases:
            aliases[name] = place.name
    return places, aliases


def robot_place(model: WorldModel, robot: Any) -> str:
    """The place a pyrobosim robot is at: the place whose point it stands on; else, in
    a hallway, the nearer of its doorways, and in a room, the room's own place (a place
    of the room that is not an object spawn's, when the room's is: a robot is only at a
    spawn when it stands where it can reach it); "" when it is nowhere."""
    from pyrobosim.core.hallway import Hallway
    from pyrobosim.core.locations import ObjectSpawn
    from pyrobosim.core.room import Room

    pose = robot.get_pose()
    x, y = float(pose.x), float(pose.y)
    nearest = model.nearest_place(x, y)
    if nearest is not None:
        place = model.places[nearest]
        if math.hypot(place.x - x, place.y - y) < AT_PLACE_M:
            return nearest
    where = robot.location
    if isinstance(where, Hallway):
        return model.nearest_place(x, y, hall=where.name) or ""
    if isinstance(where, ObjectSpawn):
        room_entity = where.parent.parent if where.parent is not None else None
    elif isinstance(where, Room):
        room_entity = where
    else:
        room_entity = getattr(where, "parent", None)
    if room_entity is None:
        return ""
    own = model.place_of(room_entity.name)
    if own is not None and not model.places[own].is_spawn:
        return own
    others = [p for p in model.places.values() if p.room == room_entity.name and not p.is_spawn]
    if not others:
        return own or ""
    return min(others, key=lambda p: math.hypot(p.x - x, p.y - y)).name


def _robot_info(model: WorldModel, robot: Any, origin: str) -> RobotInfo:
    place = robot_place(model, robot)
    if not place:
        raise WorldModelError(
            f"{origin}: robot {robot.name} is not in a room, hallway or object spawn "
            f"(at {robot.get_pose()}); place it in a room (robots: location: ROOM)"
        )
    options = robot.action_execution_options.get("navigate")
    executor = robot.path_executor
    speed = float(getattr(executor, "linear_velocity", 0.0) or 0.0)
    if not speed > 0 or math.isinf(speed):
        speed = float(robot.dynamics.vel_limits[0])
    if not speed > 0 or math.isinf(speed):
        speed = 1.0
    held = robot.manipulated_object
    return RobotInfo(
        robot.name,
        place,
        float(robot.battery_level),
        speed,
        float(options.battery_usage) if options is not None else 0.0,
        held.name if held is not None else None,
    )


_NAME_PATTERN = "letters, digits, _ and -, starting with a letter"


def _check_names(model: WorldModel, origin: str) -> None:
    import re

    pattern = re.compile(r"^[A-Za-z][A-Za-z0-9_-]*$")
    seen: dict[str, str] = {}
    groups: list[tuple[str, Iterable[str]]] = [
        ("robot", (r.name for r in model.robots)),
        ("room, spawn or doorway", model.aliases),
        ("hallway or location", model.gates),
        ("object", model.items),
    ]
    for what, names in groups:
        for name in names:
            if not pattern.match(name):
                raise WorldModelError(
                    f"{origin}: {what} {name!r} cannot be a PDDL name ({_NAME_PATTERN}); "
                    f"rename it in the world file"
                )
            if name.lower() in TYPE_NAMES | SYMBOL_NAMES:
                raise WorldModelError(
                    f"{origin}: {what} {name!r} has the name of a type, predicate or function "
                    f"of the robosim domain ({', '.join(sorted(TYPE_NAMES | SYMBOL_NAMES))}); "
                    f"rename it in the world file"
                )
            key = name.lower()
            if key in seen:
                raise WorldModelError(
                    f"{origin}: the name {name!r} is used by a {seen[key]} and a {what}; "
                    f"PDDL names are not case-sensitive: rename one of them"
                )
            seen.setdefault(key, what)
