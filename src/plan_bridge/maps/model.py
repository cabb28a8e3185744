"""A world as the task level sees it: places, hallways, gates, objects and robots.

Plain data, read from a simulator or a robot's map (pyrobosim's reader is
:func:`plan_bridge.robosim.description.describe_world`), shared by the map's graph
(:mod:`.graph`), the goals (:mod:`.goals`) and the tasks the planner gets
(:mod:`.tasks`).

A **place** is where a robot can stand: a room's navigation pose, the pose in front of
an object spawn, or a doorway (where a hallway meets a room). Spots of the world that
stand at one point (a room's pose and a spawn's, two hallways' doorways) are **one**
place, so nothing that senses where a robot is ever has to tell them apart. A place is
named after what stands there, in this order: the first object spawn, the room, the
first doorway (``HALLWAY_door_ROOM``); every spot's own name stays an alias of it, so
goals may use any of them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

__all__ = ["Gate", "Hall", "Place", "RobotInfo", "WorldModel", "door_name"]


def door_name(hallway: str, room: str) -> str:
    """The doorway of ``hallway`` in ``room``."""
    return f"{hallway}_door_{room}"


@dataclass(frozen=True)
class Place:
    """Where a robot can stand."""

    name: str
    x: float
    y: float
    room: str
    """The room it is in ("" for none)."""
    spawns: tuple[str, ...] = ()
    """The object spawns a robot reaches from here (where objects lie)."""
    fixture: str | None = None
    """The location those spawns belong to (it opens and closes from here)."""
    doors: tuple[str, ...] = ()
    """The hallways that end here."""
    aliases: tuple[str, ...] = ()
    """Every name of a spot that stands here (its own name first)."""

    @property
    def gates(self) -> tuple[str, ...]:
        """The hallways and the location a robot opens and closes from here."""
        return ((self.fixture,) if self.fixture is not None else ()) + self.doors

    @property
    def is_spawn(self) -> bool:
        return bool(self.spawns)

    @property
    def xy(self) -> tuple[float, float]:
        return (self.x, self.y)


@dataclass(frozen=True)
class Gate:
    """A hallway or a location that opens, closes and locks."""

    name: str
    kind: str
    """``hall`` or ``fixture``."""
    is_open: bool
    is_locked: bool
    is_charger: bool = False
    spawns: tuple[str, ...] = ()
    """A location's object spawns."""
    category: str = ""
    """A location's category (``table``, ``fridge``...)."""


@dataclass(frozen=True)
class Hall:
    """A hallway between two rooms: its doorways and the way through it."""

    name: str
    ends: tuple[str, str]
    """The places of its two doorways (in its first room, in its second)."""
    rooms: tuple[str, str]
    length: float
    """Metres from one doorway to the other along its centre line."""
    path: tuple[tuple[float, float], ...]
    """The centre line from ``ends[0]`` to ``ends[1]`` (its first and last point are
    the doorways)."""


@dataclass(frozen=True)
class RobotInfo:
    name: str
    place: str
    battery: float
    speed: float
    """Metres per second."""
    drain: float
    """Battery (percent) per metre driven."""
    holding: str | None = None


@dataclass(frozen=True)
class WorldModel:
    """A world as the task level sees it (see the module's doc)."""

    name: str
    robots: tuple[RobotInfo, ...]
    places: dict[str, Place]
    gates: dict[str, Gate]
    halls: dict[str, Hall]
    items: dict[str, str | None]
    """Object -> the spawn it lies on (None: a robot holds it)."""
    item_categories: dict[str, str] = field(default_factory=dict)
    aliases: dict[str, str] = field(default_factory=dict)
    """Every spot's name (room, spawn, doorway) -> its place."""
    spot_kinds: dict[str, str] = field(default_factory=dict)
    """Every spot's name -> what it is: ``room``, ``spawn`` or ``door``."""

    @property
    def names(self) -> set[str]:
        """Every name a goal may use."""
        return {
            *(r.name for r in self.robots),
            *self.places,
            *self.aliases,
            *self.gates,
            *self.items,
        }

    @property
    def rooms(self) -> set[str]:
        return {place.room for place in self.places.values() if place.room}

    def place_of(self, name: str) -> str | None:
        """The place a spot's name (room, spawn, doorway, place) stands for."""
        return self.aliases.get(name)

    def spawn_place(self, spawn: str) -> str | None:
        """The place from which a robot reaches object spawn ``spawn``."""
        return self.aliases.get(spawn)

    def item_place(self, item: str) -> str | None:
        """The place in front of the spawn an object lies on (None: held, or unknown)."""
        spawn = self.items.get(item)
        return None if spawn is None else self.aliases.get(spawn)

    def robot(self, name: str) -> RobotInfo:
        for robot in self.robots:
            if robot.name == name:
                return robot
        raise KeyError(f"no robot {name!r} in {self.name}")

    def distance(self, a: str, b: str) -> float:
        """Straight-line metres between two places."""
        first, second = self.places[a], self.places[b]
        return math.hypot(first.x - second.x, first.y - second.y)

    def nearest_place(
        self, x: float, y: float, room: str | None = None, hall: str | None = None
    ) -> str | None:
        """The place nearest to (x, y): among ``hall``'s doorways when given, else
        among ``room``'s places when given, else among all."""
        if hall is not None and hall in self.halls:
            candidates: list[str] = list(self.halls[hall].ends)
        elif room:
            candidates = [p.name for p in self.places.values() if p.room == room]
        else:
            candidates = list(self.places)
        if not candidates:
            return None
        return min(
            candidates,
            key=lambda p: math.hypot(self.places[p].x - x, self.places[p].y - y),
        )

    def spawn_places(self, fixture: str) -> list[str]:
        """The places from which a robot reaches the spawns of location ``fixture``."""
        gate = self.gates.get(fixture)
        if gate is None:
            return []
        return list(dict.fromkeys(p for s in gate.spawns if (p := self.aliases.get(s))))

    def gate_places(self, gate: str) -> list[str]:
        """The places a robot opens and closes ``gate`` from."""
        hall = self.halls.get(gate)
        if hall is not None:
            return list(dict.fromkeys(hall.ends))
        return self.spawn_places(gate)

    def chargers(self) -> list[str]:
        """The places in front of a charger's spawns."""
        return [
            place
            for gate in self.gates.values()
            if gate.is_charger
            for place in self.spawn_places(gate.name)
        ]
