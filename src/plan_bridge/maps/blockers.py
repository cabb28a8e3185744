"""Goals no run can reach from a world as it is loaded, and why.

:func:`goal_blockers` is what :func:`~plan_bridge.maps.goals.parse_goal` asks
before any planning: atoms that contradict each other (a robot at two places, an
object held by two robots, a hand empty and holding), and atoms the robots cannot
make true (a lock - no robot action locks -, a place behind closed, locked hallways,
an object in, or to be put in, a closed, locked location). It ignores the battery and
what robots do to each other, so a planner may still find no plan; what it reports is
certain.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field

from plan_bridge.maps.graph import PlaceMap
from plan_bridge.maps.model import RobotInfo, WorldModel
from plan_bridge.pddl.task import Fact

__all__ = ["goal_blockers"]


#: Why a closed, locked gate stays closed.
_SHUT = "closed and locked (robots open and close hallways and locations; none unlocks)"


def goal_blockers(model: WorldModel, goal: Sequence[Fact]) -> list[str]:
    """Why no run can reach ``goal`` (atoms of :func:`parse_goal`) from the world as it
    is: atoms that contradict each other, and atoms the robots cannot make true (a
    lock, a place behind closed, locked hallways, an object in or for a closed, locked
    location). Empty when nothing is in the way as far as this can tell: it ignores
    the battery and what the robots do to each other, so the planner may still find
    no plan; what it reports is certain."""
    reasons = _contradictions(model, goal)
    if reasons:
        return reasons
    graph = PlaceMap(model)
    shut = [hall for hall in model.halls if not _usable(model, hall)]
    reach = {robot.name: graph.reachable(robot.place, shut) for robot in model.robots}
    items: dict[str, tuple[set[str], set[str]]] = {}

    def item(name: str) -> tuple[set[str], set[str]]:
        if name not in items:
            items[name] = _item_reach(model, name, reach)
        return items[name]

    for fact in goal:
        reason = _blocker(model, fact, reach, item)
        if reason:
            reasons.append(reason)
    return reasons


@dataclass
class _Wanted:
    """What a goal asks of each robot and object."""

    where: dict[str, list[str]] = field(default_factory=dict)
    """Robot or object -> the spots it is to be at."""
    inside: dict[str, list[str]] = field(default_factory=dict)
    """Object -> the locations it is to be at."""
    held: dict[str, list[str]] = field(default_factory=dict)
    """Object -> the robots to hold it."""
    holds: dict[str, list[str]] = field(default_factory=dict)
    """Robot -> the objects it is to hold."""
    empty: set[str] = field(default_factory=set)

    @classmethod
    def of(cls, goal: Sequence[Fact]) -> _Wanted:
        wanted = cls()
        for fact in goal:
            name, *args = fact
            if name == "At":
                wanted.where.setdefault(args[0], []).append(args[1])
            elif name == "Has":
                wanted.inside.setdefault(args[1], []).append(args[0])
            elif name == "Holding":
                wanted.held.setdefault(args[1], []).append(args[0])
                wanted.holds.setdefault(args[0], []).append(args[1])
            elif name == "HandEmpty":
                wanted.empty.add(args[0])
        return wanted


def _contradictions(model: WorldModel, goal: Sequence[Fact]) -> list[str]:
    """Atoms of ``goal`` that cannot hold together."""
    wanted = _Wanted.of(goal)
    return [*_place_clashes(model, wanted), *_hold_clashes(wanted)]


def _place_clashes(model: WorldModel, wanted: _Wanted) -> Iterable[str]:
    """Something to be at two places at once."""
    for thing, spots in wanted.where.items():
        if len(spots) > 1:
            yield f"{thing} cannot be at {' and at '.join(spots)} at once"
    for obj, locations in wanted.inside.items():
        if len(locations) > 1:
            yield f"{obj} cannot be at {' and at '.join(locations)} at once"
        for spawn in wanted.where.get(obj, []):
            if spawn in model.places and model.places[spawn].fixture not in locations:
                yield f"{obj} cannot be on {spawn} and at {locations[0]} at once"


def _hold_clashes(wanted: _Wanted) -> Iterable[str]:
    """An object held twice or held and placed; a robot holding two or holding none."""
    where, inside = wanted.where, wanted.inside
    for obj, robots in wanted.held.items():
        if len(robots) > 1:
            yield f"{obj} cannot be held by {' and by '.join(robots)} at once"
        if obj in where or obj in inside:
            places = [*where.get(obj, []), *inside.get(obj, [])]
            yield f"{obj} cannot be held by {robots[0]} and be at {places[0]}"
    for robot, objects in wanted.holds.items():
        if len(objects) > 1:
            yield f"{robot} holds one object at a time, not {' and '.join(objects)}"
        if robot in wanted.empty:
            yield f"{robot} cannot hold {objects[0]} with its hand empty"


def _usable(model: WorldModel, gate: str | None) -> bool:
    """Whether a gate is open or can be opened (it is not closed and locked)."""
    info = model.gates.get(gate) if gate is not None else None
    return info is not None and (info.is_open or not info.is_locked)


def _item_reach(
    model: WorldModel, item: str, reach: dict[str, set[str]]
) -> tuple[set[str], set[str]]:
    """(the spawns ``item`` can be brought to, the robots that can hold it)."""
    start = model.item_place(item)
    places = {start} if start is not None else set()
    robots = {r.name for r in model.robots if r.holding == item}
    while True:
        takers = {
            r.name
            for r in model.robots
            if any(s in reach[r.name] and _usable(model, model.places[s].fixture) for s in places)
        }
        drops = {
            s
            for r in robots | takers
            for s in reach[r]
            if model.places[s].is_spawn and _usable(model, model.places[s].fixture)
        }
        if takers <= robots and drops <= places:
            return places, robots
        robots |= takers
        places |= drops


def _shut_halls(model: WorldModel, reached: Iterable[str]) -> str:
    """The closed, locked hallways between the places ``reached`` and the others."""
    inside = set(reached)
    shut = [
        hall.name
        for hall in model.halls.values()
        if not _usable(model, hall.name) and (hall.ends[0] in inside) != (hall.ends[1] in inside)
    ]
    if not shut:
        return "no hallway leads there"
    return f"{', '.join(shut)} {'is' if len(shut) == 1 else 'are'} {_SHUT}"


_Reach = dict[str, set[str]]
"""Robot -> the spots it can drive to."""
_ItemReach = Callable[[str], tuple[set[str], set[str]]]
"""Object -> (the spawns it can be brought to, the robots that can hold it)."""


def _blocker(model: WorldModel, fact: Fact, reach: _Reach, item: _ItemReach) -> str:
    """Why ``fact`` cannot be made true ("" when it can, as far as this can tell)."""
    name, *args = fact
    if name == "At" and args[0] in reach:
        return _robot_at_blocker(model, args, reach, item)
    check = _BLOCKERS.get(name)
    return check(model, args, reach, item) if check is not None else ""


def _robot_at_blocker(model: WorldModel, args: list[str], reach: _Reach, item: _ItemReach) -> str:
    robot = _robot(model, args[0])
    if args[1] in reach[robot.name]:
        return ""
    way = _shut_halls(model, reach[robot.name])
    return f"{robot.name} cannot get from {robot.place} to {args[1]}: {way}"


def _robot(model: WorldModel, name: str) -> RobotInfo:
    return {r.name: r for r in model.robots}[name]


def _object_at_blocker(model: WorldModel, args: list[str], reach: _Reach, item: _ItemReach) -> str:
    obj, spawn = args
    places, _ = item(obj)
    if spawn in places:
        return ""
    return _placement_blocker(model, obj, spawn, model.places[spawn].fixture, reach)


def _has_blocker(model: WorldModel, args: list[str], reach: _Reach, item: _ItemReach) -> str:
    location, obj = args
    places, _ = item(obj)
    if places & set(model.spawn_places(location)):
        return ""
    return _placement_blocker(model, obj, location, location, reach)


def _placement_blocker(
    model: WorldModel, obj: str, target: str, gate: str | None, reach: _Reach
) -> str:
    if not _usable(model, gate):
        return f"nothing can be put on {target}: {gate} is {_SHUT}"
    return _why_stuck(model, obj, target, reach)


def _holding_blocker(model: WorldModel, args: list[str], reach: _Reach, item: _ItemReach) -> str:
    _, holders = item(args[1])
    if args[0] in holders:
        return ""
    return _why_stuck(model, args[1], args[0], reach)


def _hand_empty_blocker(model: WorldModel, args: list[str], reach: _Reach, item: _ItemReach) -> str:
    robot = _robot(model, args[0])
    if robot.holding is None or any(
        model.places[s].is_spawn and _usable(model, model.places[s].fixture)
        for s in reach[robot.name]
    ):
        return ""
    return f"{robot.name} holds {robot.holding} and can reach no open location to put it"


def _open_blocker(model: WorldModel, args: list[str], reach: _Reach, item: _ItemReach) -> str:
    info = model.gates[args[0]]
    if info.is_open:
        return ""
    if info.is_locked:
        return f"{info.name} is {_SHUT}"
    spots = set(model.gate_places(info.name))
    if any(spots & reach[r] for r in reach):
        return ""
    return f"no robot can get to {info.name}: {_shut_halls(model, _anyone(reach))}"


def _locked_blocker(model: WorldModel, args: list[str], reach: _Reach, item: _ItemReach) -> str:
    if model.gates[args[0]].is_locked:
        return ""
    return (
        f"{args[0]} is not locked and no robot action locks (pyrobosim's robots "
        f"navigate, pick, place, open, close and detect; only the world's events lock: "
        f"--events with lock:)"
    )


def _searched_blocker(model: WorldModel, args: list[str], reach: _Reach, item: _ItemReach) -> str:
    spot = model.places[args[0]]
    if not _usable(model, spot.fixture):
        return f"{args[0]} cannot be searched: {spot.fixture} is {_SHUT}"
    if any(args[0] in reach[r] for r in reach):
        return ""
    return f"no robot can get to {args[0]}: {_shut_halls(model, _anyone(reach))}"


#: Per predicate, why an atom of it cannot be made true (``At`` of a robot aside).
_BLOCKERS: dict[str, Callable[[WorldModel, list[str], _Reach, _ItemReach], str]] = {
    "At": _object_at_blocker,
    "Has": _has_blocker,
    "Holding": _holding_blocker,
    "HandEmpty": _hand_empty_blocker,
    "IsOpen": _open_blocker,
    "IsLocked": _locked_blocker,
    "Searched": _searched_blocker,
}


def _anyone(reach: dict[str, set[str]]) -> set[str]:
    """The places some robot can get to."""
    return set().union(*reach.values())


def _why_stuck(model: WorldModel, obj: str, target: str, reach: dict[str, set[str]]) -> str:
    """Why ``obj`` cannot be brought to ``target`` (a spawn, a location or a robot)."""
    spawn = model.item_place(obj)
    if spawn is None:
        holder = next((r.name for r in model.robots if r.holding == obj), "")
        way = _shut_halls(model, reach.get(holder, ()))
        return f"{holder} holds {obj} and cannot get to {target}: {way}"
    gate = model.places[spawn].fixture
    if not _usable(model, gate):
        return f"{obj} is in {gate}, which is {_SHUT}: no robot can take it out"
    if not any(spawn in reach[r.name] for r in model.robots):
        return f"no robot can get to {obj} on {spawn}: {_shut_halls(model, _anyone(reach))}"
    takers = set().union(*(reach[r.name] for r in model.robots if spawn in reach[r.name]))
    way = _shut_halls(model, takers)
    return f"no robot that can get to {obj} on {spawn} can bring it to {target}: {way}"
