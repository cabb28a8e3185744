"""The PDDL problem of a pyrobosim world, and goals in pyrobosim's vocabulary.

:func:`describe_world` reads a loaded pyrobosim world into a :class:`WorldModel` (plain
data: spots with their poses and rooms, gates, items, robots); :func:`problem_text`
writes the problem of the shipped domain (``domain.pddl`` next to this module) for a
goal that :func:`parse_goal` checked against the world's names and refused when no run
can reach it from the world as it is (:func:`.goal_checks.goal_blockers`: contradictions, locks,
closed and locked hallways and locations in the way).

Spots are where a robot stands: a room's navigation pose (named as the room), an object
spawn (named as the spawn) and each end of a hallway (``HALLWAY_door_ROOM``: the end in
ROOM). Distances are straight lines between navigation poses (a hallway's own length
along its centre line); the skills drive the real paths.
"""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

from plan_bridge.errors import PlanBridgeError
from plan_bridge.pddl.constructs import did_you_mean
from plan_bridge.pddl.task import Fact, format_fact
from plan_bridge.robosim.target_files import DOMAIN_PATH

__all__ = [
    "DOMAIN_PATH",
    "GOAL_FORMS",
    "GoalError",
    "Spot",
    "WorldModel",
    "describe_world",
    "parse_goal",
    "problem_text",
]


#: The domain's type names: no entity of a world may be named like one.
TYPE_NAMES = frozenset(
    {"thing", "bot", "item", "spot", "area", "spawn", "door", "gate", "hall", "fixture", "object"}
)
#: The domain's predicate and function names: no entity may be named like one either.
SYMBOL_NAMES = frozenset(
    {"at", "holding", "handempty", "isopen", "islocked", "has", "searched", "bot-ready"}
    | {"same-room", "hall-ends", "spawn-of", "reaches-gate", "is-charger", "battery-level"}
    | {"drain-per-metre", "top-speed", "metres"}
)
GOAL_FORMS = (
    "(At ROBOT ROOM|SPAWN|LOCATION|DOOR)",
    "(At OBJECT SPAWN|LOCATION)",
    "(Holding ROBOT OBJECT)",
    "(HandEmpty ROBOT)",
    "(IsOpen HALLWAY|LOCATION)",
    "(IsLocked HALLWAY|LOCATION)",
    "(Has LOCATION|SPAWN OBJECT)",
    "(Searched SPAWN)",
)
"""What a goal may say (a conjunction of these: ``(and ...)`` or several atoms)."""
_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_-]*$")


class GoalError(PlanBridgeError):
    """A goal that does not fit the world (unknown name, wrong form)."""


class WorldModelError(PlanBridgeError):
    """A pyrobosim world that cannot be written as a planning problem."""


@dataclass(frozen=True)
class Spot:
    """A place a robot can stand at."""

    name: str
    kind: str
    """``area`` (a room's navigation pose), ``spawn`` or ``door`` (a hallway's end)."""
    x: float
    y: float
    room: str
    gate: str | None = None
    """The hallway (door) or location (spawn) the robot can open or close from here."""


@dataclass(frozen=True)
class Gate:
    """A hallway or a location (opens, closes, locks)."""

    name: str
    kind: str
    """``hall`` or ``fixture``."""
    is_open: bool
    is_locked: bool
    is_charger: bool = False
    spawns: tuple[str, ...] = ()


@dataclass(frozen=True)
class RobotInfo:
    name: str
    spot: str
    battery: float
    speed: float
    drain: float
    """Battery (percent) per metre driven."""
    holding: str | None = None


@dataclass(frozen=True)
class WorldModel:
    """A pyrobosim world as the planning problem sees it."""

    name: str
    robots: tuple[RobotInfo, ...]
    spots: dict[str, Spot]
    gates: dict[str, Gate]
    items: dict[str, str | None]
    """Object name -> the spawn it is on (None: held by a robot)."""
    hall_ends: dict[str, tuple[str, str]] = field(default_factory=dict)
    """Hallway -> its two door spots."""
    hall_lengths: dict[str, float] = field(default_factory=dict)

    @property
    def names(self) -> set[str]:
        return {
            *(r.name for r in self.robots),
            *self.spots,
            *self.gates,
            *self.items,
        }

    def distance(self, a: str, b: str) -> float:
        """Metres from spot ``a`` to spot ``b`` (a hallway's length between its ends)."""
        for hall, ends in self.hall_ends.items():
            if {a, b} == set(ends):
                return self.hall_lengths[hall]
        first, second = self.spots[a], self.spots[b]
        return math.hypot(first.x - second.x, first.y - second.y)


def _pose_xy(pose: Any) -> tuple[float, float]:
    return float(pose.x), float(pose.y)


def door_name(hallway: str, room: str) -> str:
    """The spot at ``hallway``'s end in ``room``."""
    return f"{hallway}_door_{room}"


def describe_world(world: Any, origin: str = "the world") -> WorldModel:
    """Read a loaded pyrobosim ``World`` (rooms, hallways, locations, spawns, objects,
    robots). Raises :class:`WorldModelError` for names PDDL cannot hold."""
    from pyrobosim.core.hallway import Hallway
    from pyrobosim.core.locations import ObjectSpawn
    from pyrobosim.core.room import Room

    spots: dict[str, Spot] = {}
    gates: dict[str, Gate] = {}
    hall_ends: dict[str, tuple[str, str]] = {}
    hall_lengths: dict[str, float] = {}
    for room in world.rooms:
        x, y = _pose_xy(room.nav_poses[0])
        spots[room.name] = Spot(room.name, "area", x, y, room.name)
    for hall in world.hallways:
        gates[hall.name] = Gate(hall.name, "hall", bool(hall.is_open), bool(hall.is_locked))
        ends: list[str] = []
        for pose in hall.nav_poses[:2]:
            x, y = _pose_xy(pose)
            side = min(
                (hall.room_start, hall.room_end),
                key=lambda r: float(r.polygon.distance(_point(x, y))),
            )
            name = door_name(hall.name, side.name)
            spots[name] = Spot(name, "door", x, y, side.name, hall.name)
            ends.append(name)
        if len(ends) == 2 and ends[0] != ends[1]:
            hall_ends[hall.name] = (ends[0], ends[1])
            nodes = [_pose_xy(node.pose) for node in hall.graph_nodes]
            hall_lengths[hall.name] = sum(
                math.dist(p, q) for p, q in itertools.pairwise(nodes)
            ) or math.dist(_pose_xy(hall.nav_poses[0]), _pose_xy(hall.nav_poses[1]))
    for location in world.locations:
        room = location.parent.name if location.parent is not None else ""
        spawns = tuple(spawn.name for spawn in location.children)
        gates[location.name] = Gate(
            location.name,
            "fixture",
            bool(location.is_open),
            bool(location.is_locked),
            bool(location.is_charger),
            spawns,
        )
        for spawn in location.children:
            if not spawn.nav_poses:
                continue
            x, y = _pose_xy(spawn.nav_poses[0])
            spots[spawn.name] = Spot(spawn.name, "spawn", x, y, room, location.name)
    items: dict[str, str | None] = {}
    for obj in world.objects:
        parent = obj.parent
        items[obj.name] = parent.name if isinstance(parent, ObjectSpawn) else None
    robots = []
    for robot in world.robots:
        place = robot.location
        if isinstance(place, (ObjectSpawn, Room)):
            spot = place.name
        elif isinstance(place, Hallway) and place.name in hall_ends:
            x, y = _pose_xy(robot.get_pose())
            spot = min(
                hall_ends[place.name],
                key=lambda s: math.hypot(spots[s].x - x, spots[s].y - y),
            )
        else:
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
        robots.append(
            RobotInfo(
                robot.name,
                spot,
                float(robot.battery_level),
                speed,
                float(options.battery_usage) if options is not None else 0.0,
                held.name if held is not None else None,
            )
        )
    model = WorldModel(
        str(world.name or "world"), tuple(robots), spots, gates, items, hall_ends, hall_lengths
    )
    _check_names(model, origin)
    return model


def _point(x: float, y: float) -> Any:
    from shapely.geometry import Point

    return Point(x, y)


def _check_names(model: WorldModel, origin: str) -> None:
    seen: dict[str, str] = {}
    groups: list[tuple[str, Iterable[str]]] = [
        ("robot", (r.name for r in model.robots)),
        ("spot", model.spots),
        ("hallway or location", model.gates),
        ("object", model.items),
    ]
    for what, names in groups:
        for name in names:
            if not _NAME.match(name):
                raise WorldModelError(
                    f"{origin}: {what} {name!r} cannot be a PDDL name (letters, digits, _ "
                    f"and -, starting with a letter); rename it in the world file"
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


# -- goals ---------------------------------------------------------------------------

_PREDICATES = {
    name.lower(): name
    for name in ("At", "Holding", "HandEmpty", "IsOpen", "IsLocked", "Has", "Searched")
}


def parse_goal(text: str, model: WorldModel) -> list[Fact]:
    """The goal atoms of ``text`` (pyrobosim's vocabulary, the world's names), checked.

    ``(At apple0 my_desk)`` for a location becomes ``(Has my_desk apple0)``, and
    ``(At robot my_desk)`` its spawn when it has one. Raises :class:`GoalError` naming
    the atom, what is wrong and what is allowed.
    """
    forms = _parse_forms(text)
    atoms: list[Any] = []
    for form in forms:
        if isinstance(form, list) and form and str(form[0]).lower() == "and":
            atoms.extend(form[1:])
        else:
            atoms.append(form)
    if not atoms:
        raise GoalError(f"goal {text!r} is empty; {_allowed()}")
    goal: list[Fact] = []
    for atom in atoms:
        fact = _goal_atom(atom, model)
        if fact not in goal:
            goal.append(fact)
    from plan_bridge.robosim.goal_checks import goal_blockers

    blockers = goal_blockers(model, goal)
    if blockers:
        raise GoalError(
            f"goal {' '.join(text.split())} cannot be reached in {model.name}: "
            + "; ".join(blockers)
        )
    return goal


def _parse_forms(text: str) -> list[Any]:
    """Nested lists of words: ``(and (At a b))`` -> ``[["and", ["At", "a", "b"]]]``."""
    stack: list[list[Any]] = [[]]
    for token in re.findall(r"\(|\)|[^\s()]+", text.split(";", maxsplit=1)[0]):
        if token == "(":
            stack.append([])
        elif token == ")":
            if len(stack) == 1:
                raise GoalError(f"goal {text!r}: a ')' without its '('")
            done = stack.pop()
            stack[-1].append(done)
        else:
            stack[-1].append(token)
    if len(stack) != 1:
        raise GoalError(f"goal {text!r}: {len(stack) - 1} '(' not closed")
    return stack[0]


def _allowed() -> str:
    return "a goal is one or more of " + ", ".join(GOAL_FORMS)


def _goal_atom(atom: Any, model: WorldModel) -> Fact:
    predicate, args, shown = _goal_words(atom)
    words = _GoalWords(shown, args, [_kind(name, model, shown) for name in args])
    if predicate == "At":
        return _at_goal(words, model)
    if predicate == "Holding":
        words.need(0, ("robot",), GOAL_FORMS[2])
        words.need(1, ("object",), GOAL_FORMS[2])
    elif predicate == "HandEmpty":
        words.need(0, ("robot",), GOAL_FORMS[3])
    elif predicate in ("IsOpen", "IsLocked"):
        words.need(0, ("hallway", "location"), GOAL_FORMS[4 if predicate == "IsOpen" else 5])
    elif predicate == "Has":
        words.need(1, ("object",), GOAL_FORMS[6])
        if words.kinds[0] == "spawn":
            return ("At", args[1], args[0])
        words.need(0, ("location",), GOAL_FORMS[6])
    elif predicate == "Searched":
        words.need(0, ("spawn",), GOAL_FORMS[7])
    return (predicate, *args)


def _goal_words(atom: Any) -> tuple[str, list[str], str]:
    """The predicate (as the domain spells it), the arguments and the atom as shown in
    messages, after checking the atom's form, predicate and arity."""
    if isinstance(atom, list) and atom and str(atom[0]).lower() == "not":
        raise GoalError(
            f"goal atom {_show(atom)}: negated goals are not modelled (pyrobosim's goal "
            f"vocabulary has no negation, and the robosim domain no predicate for a closed "
            f"hallway or location): closing one cannot be a goal yet; {_allowed()}"
        )
    if not isinstance(atom, list) or not atom or any(isinstance(a, list) for a in atom):
        raise GoalError(
            f"goal atom {_show(atom)}: not an atom such as (At apple0 table0); {_allowed()}"
        )
    words = [str(a) for a in atom]
    shown = "(" + " ".join(words) + ")"
    predicate = _PREDICATES.get(words[0].lower())
    if predicate is None:
        hint = did_you_mean(words[0], _PREDICATES.values())
        raise GoalError(f"goal atom {shown}: unknown predicate {words[0]!r}{hint}; {_allowed()}")
    args = words[1:]
    arity = {"HandEmpty": 1, "IsOpen": 1, "IsLocked": 1, "Searched": 1}.get(predicate, 2)
    if len(args) != arity:
        forms = [f for f in GOAL_FORMS if f.startswith(f"({predicate} ")]
        raise GoalError(f"goal atom {shown}: {predicate} takes {arity} name(s): {', '.join(forms)}")
    return predicate, args, shown


@dataclass(frozen=True)
class _GoalWords:
    """A goal atom's arguments with what each names (robot, room, spawn...)."""

    shown: str
    args: list[str]
    kinds: list[str]

    def need(self, index: int, allowed: Sequence[str], form: str) -> None:
        if self.kinds[index] not in allowed:
            raise GoalError(
                f"goal atom {self.shown}: {self.args[index]} is a {self.kinds[index]}; "
                f"the form is {form}"
            )


def _at_goal(words: _GoalWords, model: WorldModel) -> Fact:
    """``(At ROBOT PLACE)`` or ``(At OBJECT PLACE)``; a location stands for its spawn."""
    args, kinds, shown = words.args, words.kinds, words.shown
    if args[0] not in {r.name for r in model.robots}:
        words.need(0, ("object",), GOAL_FORMS[1])
        if kinds[1] == "location":
            return ("Has", args[1], args[0])
        words.need(1, ("spawn",), GOAL_FORMS[1])
        return ("At", args[0], args[1])
    if kinds[1] == "location":
        spawns = model.gates[args[1]].spawns
        if len(spawns) != 1:
            raise GoalError(
                f"goal atom {shown}: location {args[1]} has the object spawns "
                f"{', '.join(spawns) or 'none'}; name the one the robot goes to"
            )
        return ("At", args[0], spawns[0])
    if kinds[1] == "hallway":
        a, b = model.hall_ends[args[1]]
        raise GoalError(f"goal atom {shown}: a robot stands at one end of a hallway: {a} or {b}")
    words.need(1, ("room", "spawn", "door"), GOAL_FORMS[0])
    return ("At", args[0], args[1])


def _show(atom: Any) -> str:
    if isinstance(atom, list):
        return "(" + " ".join(_show(a) for a in atom) + ")"
    return str(atom)


def _kind(name: str, model: WorldModel, shown: str) -> str:
    if any(r.name == name for r in model.robots):
        return "robot"
    if name in model.items:
        return "object"
    if name in model.gates:
        return "hallway" if model.gates[name].kind == "hall" else "location"
    spot = model.spots.get(name)
    if spot is not None:
        return {"area": "room", "spawn": "spawn", "door": "door"}[spot.kind]
    raise GoalError(
        f"goal atom {shown}: {name!r} is not a robot, room, hallway, location, object "
        f"spawn or object of {model.name}{did_you_mean(name, model.names)}"
    )


# -- what blocks a goal ----------------------------------------------------------------


def problem_text(model: WorldModel, goal: Sequence[Fact], name: str | None = None) -> str:
    """The PDDL problem of ``model`` with ``goal`` (atoms from :func:`parse_goal`)."""
    by_type: dict[str, list[str]] = {}
    for robot in model.robots:
        by_type.setdefault("bot", []).append(robot.name)
    by_type["item"] = sorted(model.items)
    for spot in model.spots.values():
        by_type.setdefault(spot.kind, []).append(spot.name)
    for gate in model.gates.values():
        by_type.setdefault(gate.kind, []).append(gate.name)
    facts: list[str] = []
    numbers: list[str] = []
    _robot_facts(model, facts, numbers)
    _item_and_gate_facts(model, facts)
    _distance_facts(model, facts, numbers)
    objects = "\n    ".join(
        f"{' '.join(names)} - {kind}" for kind, names in by_type.items() if names
    )
    goal_text = " ".join(format_fact(atom) for atom in goal)
    problem_name = name or f"{model.name}-goal"
    return (
        f"; Generated by plan_bridge.robosim from the pyrobosim world {model.name}.\n"
        f"(define (problem {_pddl_name(problem_name)})\n"
        f"  (:domain robosim)\n"
        f"  (:objects\n    {objects})\n"
        f"  (:init\n    " + "\n    ".join([*facts, *numbers]) + ")\n"
        f"  (:goal (and {goal_text})))\n"
    )


def _robot_facts(model: WorldModel, facts: list[str], numbers: list[str]) -> None:
    for robot in model.robots:
        facts.append(f"(At {robot.name} {robot.spot})")
        facts.append(f"(bot-ready {robot.name})")
        facts.append(
            f"(Holding {robot.name} {robot.holding})"
            if robot.holding
            else f"(HandEmpty {robot.name})"
        )
        numbers.append(f"(= (battery-level {robot.name}) {_num(robot.battery)})")
        numbers.append(f"(= (drain-per-metre {robot.name}) {_num(robot.drain)})")
        numbers.append(f"(= (top-speed {robot.name}) {_num(robot.speed)})")


def _item_and_gate_facts(model: WorldModel, facts: list[str]) -> None:
    """Where the items are; which hallways and locations are open, locked, chargers;
    which spawns belong to a location and which spots reach a gate."""
    for item, spawn in sorted(model.items.items()):
        if spawn is not None and spawn in model.spots:
            facts.append(f"(At {item} {spawn})")
            fixture = model.spots[spawn].gate
            if fixture is not None:
                facts.append(f"(Has {fixture} {item})")
    for gate in model.gates.values():
        flags = (
            ("IsOpen", gate.is_open),
            ("IsLocked", gate.is_locked),
            ("is-charger", gate.is_charger),
        )
        facts.extend(f"({predicate} {gate.name})" for predicate, on in flags if on)
        facts.extend(
            f"(spawn-of {spawn} {gate.name})" for spawn in gate.spawns if spawn in model.spots
        )
    for spot in model.spots.values():
        if spot.gate is not None:
            facts.append(f"(reaches-gate {spot.name} {spot.gate})")


def _distance_facts(model: WorldModel, facts: list[str], numbers: list[str]) -> None:
    """The spots of one room reach each other; a hallway joins its two ends."""
    rooms: dict[str, list[str]] = {}
    for spot in model.spots.values():
        rooms.setdefault(spot.room, []).append(spot.name)
    for members in rooms.values():
        for a, b in itertools.permutations(members, 2):
            facts.append(f"(same-room {a} {b})")
            numbers.append(f"(= (metres {a} {b}) {_num(_length(model, a, b))})")
    for hall, (a, b) in model.hall_ends.items():
        for first, second in ((a, b), (b, a)):
            facts.append(f"(hall-ends {first} {second} {hall})")
            numbers.append(f"(= (metres {first} {second}) {_num(_length(model, a, b))})")


def _length(model: WorldModel, a: str, b: str) -> float:
    # A zero-length drive would be a zero-length durative action: a centimetre at least.
    return max(round(model.distance(a, b), 3), 0.01)


def _num(value: float) -> str:
    return f"{round(float(value), 3):g}"


def _pddl_name(text: str) -> str:
    cleaned = re.sub(r"[^A-Za-z0-9_-]", "-", text)
    return cleaned if cleaned[:1].isalpha() else f"w-{cleaned}"
