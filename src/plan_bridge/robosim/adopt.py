"""What a :class:`~.world.RobosimWorld` does outside its own skills: take what a user's
skill did into the pyrobosim world (:func:`adopt_step`), and save and restore the
world for checkpoints (:func:`snapshot_world`, :func:`restore_world`).

The world calls these with itself, an :class:`AdoptingWorld` (what they read and
write of it), and hands over its private parts (its actions' seeded options, its
pending events) as arguments.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from plan_bridge.belief import Observation
from plan_bridge.execution.clock import SimClock
from plan_bridge.execution.snapshots import SnapshotError
from plan_bridge.maps.graph import PlaceMap
from plan_bridge.maps.model import WorldModel
from plan_bridge.robosim.events import WorldEvent, parse_events

if TYPE_CHECKING:
    from plan_bridge.planning.types import PlanStep

__all__ = ["AdoptingWorld", "adopt_step", "restore_world", "snapshot_world"]


class AdoptingWorld(Protocol):
    """What adopting a step and a checkpoint read and write of a
    :class:`~plan_bridge.robosim.world.RobosimWorld` (see its attributes)."""

    actions_run: int
    faults: int
    distance_m: float
    trails: dict[str, list[list[list[float]]]]
    searched: set[str]
    crossed: dict[str, list[str]]
    changes: list[str]

    @property
    def path(self) -> Path: ...
    @property
    def sim(self) -> Any: ...
    @property
    def model(self) -> WorldModel: ...
    @property
    def map(self) -> PlaceMap: ...
    @property
    def clock(self) -> SimClock: ...
    @property
    def robots(self) -> dict[str, Any]: ...
    @property
    def battery_start(self) -> dict[str, float]: ...
    @property
    def charged(self) -> dict[str, float]: ...
    @property
    def seen_open(self) -> dict[str, bool]: ...
    def now(self) -> float: ...
    def name(self, pddl: str) -> str: ...
    def robot(self, name: str) -> Any: ...
    def spot_of(self, robot: Any) -> str: ...
    def spawn_names(self) -> list[str]: ...
    def record_drive(self, robot: Any, points: Iterable[Any]) -> None: ...
    def recharge(self, robot: Any) -> None: ...
    def learn_object(self, name: str, spawn: str | None, category: str) -> None: ...
    def quietly(self) -> Any: ...


def _pose(x: float, y: float, yaw: float = 0.0) -> Any:
    from pyrobosim.utils.pose import Pose

    return Pose(x=x, y=y, yaw=yaw)


def _put_robot(world: AdoptingWorld, robot: Any, place_name: str) -> None:
    """Stand ``robot`` at a place (what a user's drive did): the navigation pose of the
    spawn or room it is named after, else its point."""
    import copy

    place = world.model.places[place_name]
    entity = world.sim.get_entity_by_name(place.name)
    poses = getattr(entity, "nav_poses", None) if entity is not None else None
    pose = copy.deepcopy(poses[0]) if poses else _pose(place.x, place.y, robot.get_pose().get_yaw())
    robot.set_pose(pose)
    held = robot.manipulated_object
    if held is not None:
        held.set_pose(robot.get_pose())


def _put_object(world: AdoptingWorld, name: str, spawn_name: str) -> None:
    obj = world.sim.get_object_by_name(name)
    for robot in world.sim.robots:
        if robot.manipulated_object is obj:
            robot.manipulated_object = None
    world.sim.update_object(obj, loc=spawn_name)


def _set_gate(world: AdoptingWorld, name: str, is_open: bool | None, locked: bool | None) -> None:
    entity = world.sim.get_entity_by_name(name)
    if locked is False or (is_open is not None and locked is None and entity.is_locked):
        entity.is_locked = False
    if is_open is not None and bool(entity.is_open) != is_open:
        entity.set_open(is_open, recursive=True)
        world.sim.update_polygons()
        for robot in world.sim.robots:
            robot.update_polygons()
    if locked:
        entity.is_locked = True


def adopt_step(world: AdoptingWorld, step: PlanStep, observations: Sequence[Observation]) -> None:
    """Make the pyrobosim world agree with a step a user's skill did, then with its
    observations (robot and object places, holding, open/locked, battery)."""
    args = [world.name(a) for a in step.arguments]
    action = step.action.lower()
    if action in ("navigate", "cross"):
        robot = world.robot(args[0])
        before = world.spot_of(robot)
        start = robot.get_pose()
        _put_robot(world, robot, args[2])
        world.record_drive(robot, [start, robot.get_pose()])
        route = world.map.route(before, args[2]) if before in world.model.places else None
        drained = route.length if route is not None else 0.0
        info = next(r for r in world.model.robots if r.name == robot.name)
        robot.battery_level = max(0.0, float(robot.battery_level) - info.drain * drained)
        world.distance_m += drained
    elif action == "pick":
        robot, obj = world.robot(args[0]), world.sim.get_object_by_name(args[1])
        robot._attach_object(obj)
    elif action == "place":
        robot = world.robot(args[0])
        held = robot.manipulated_object
        place = world.model.places.get(args[2])
        if held is not None and place is not None and place.spawns:
            _put_object(world, held.name, place.spawns[0])
    elif action in ("open", "close"):
        _set_gate(world, args[1], action == "open", None)
    elif action == "detect":
        world.searched.add(args[1])
    elif action == "charge":
        world.recharge(world.robot(args[0]))
    for fact, value in observations:
        _adopt_observation(world, fact, value)
    world.sim.mark_changed()


def _adopt_observation(world: AdoptingWorld, fact: tuple[str, ...], value: bool | float) -> None:
    name, *raw = fact
    args = [world.name(a) for a in raw]
    if name == "battery-level" and not isinstance(value, bool):
        world.robot(args[0]).battery_level = float(value)
    elif name in ("isopen", "islocked") and isinstance(value, bool):
        _set_gate(
            world,
            args[0],
            value if name == "isopen" else None,
            value if name == "islocked" else None,
        )
    elif name == "at" and value is True:
        robot = world.robots.get(args[0].lower())
        if robot is not None:
            _put_robot(world, robot, args[1])
        elif args[1] in world.model.places and world.model.places[args[1]].is_spawn:
            _put_object(world, args[0], world.model.places[args[1]].spawns[0])
    elif name == "holding" and value is True:
        world.robot(args[0])._attach_object(world.sim.get_object_by_name(args[1]))
    elif name == "searched" and isinstance(value, bool):
        (world.searched.add if value else world.searched.discard)(args[0])


def snapshot_world(
    world: AdoptingWorld, options: Mapping[tuple[str, str], Any], pending: Sequence[WorldEvent]
) -> dict[str, Any]:
    """The world's state as JSON data: robots, objects, gates, clock, faults, events
    (``pending``), and the random state of its actions' seeded ``options``."""
    robots = []
    for robot in world.sim.robots:
        pose = robot.get_pose()
        held = robot.manipulated_object
        robots.append(
            {
                "name": robot.name,
                "pose": [float(pose.x), float(pose.y), float(pose.get_yaw())],
                "battery": float(robot.battery_level),
                "holding": held.name if held is not None else None,
            }
        )
    objects = []
    for obj in world.sim.objects:
        pose = obj.pose
        objects.append(
            {
                "name": obj.name,
                "category": str(obj.category or ""),
                "parent": obj.parent.name if obj.parent is not None else None,
                "pose": [float(pose.x), float(pose.y), float(pose.get_yaw())],
            }
        )
    gates = {
        name: [bool(entity.is_open), bool(entity.is_locked)]
        for name in world.model.gates
        for entity in [world.sim.get_entity_by_name(name)]
    }
    rng = {
        f"{robot}/{action}": option.rng.bit_generator.state
        for (robot, action), option in options.items()
    }
    return {
        "kind": "robosim",
        "world": str(world.path),
        "time": world.now(),
        "actions_run": world.actions_run,
        "faults": world.faults,
        "distance_m": world.distance_m,
        "trails": {
            name: [list(map(list, part)) for part in parts] for name, parts in world.trails.items()
        },
        "battery_start": dict(world.battery_start),
        "charged": dict(world.charged),
        "searched": sorted(world.searched),
        "seen_open": dict(world.seen_open),
        "crossed": {name: list(halls) for name, halls in world.crossed.items()},
        "changes": list(world.changes),
        "pending": [event.to_json() | {"origin": event.origin} for event in pending],
        "robots": robots,
        "objects": objects,
        "gates": gates,
        "rng": rng,
    }


def _objects_as_in(world: AdoptingWorld, entries: list[dict[str, Any]]) -> None:
    """The objects of a snapshot, and only those: events took some away and added others
    (an object added is put on its spawn, or any, if a robot held it)."""
    wanted = {entry["name"] for entry in entries}
    with world.quietly():
        for obj in list(world.sim.objects):
            if obj.name not in wanted:
                world.sim.remove_object(obj, show=False)
        for entry in entries:
            if world.sim.get_object_by_name(entry["name"]) is not None:
                continue
            parent = entry["parent"] or world.spawn_names()[0]
            world.sim.add_object(
                name=entry["name"],
                category=entry.get("category") or None,
                parent=parent,
                show=False,
            )
            world.learn_object(entry["name"], entry["parent"], entry.get("category") or "")


def restore_world(
    world: AdoptingWorld, data: dict[str, Any], options: Mapping[tuple[str, str], Any]
) -> list[WorldEvent]:
    """Put a :func:`snapshot_world` back (the same world file; the random state into
    ``options``); the world's pending events."""
    if data.get("kind") != "robosim":
        raise SnapshotError("not a snapshot of a pyrobosim world (a checkpoint of another world)")
    for name, (is_open, locked) in data["gates"].items():
        _set_gate(world, name, bool(is_open), bool(locked))
    held = {}
    for entry in data["robots"]:
        robot = world.robot(entry["name"])
        robot.manipulated_object = None
        x, y, yaw = entry["pose"]
        robot.set_pose(_pose(x, y, yaw))
        robot.battery_level = float(entry["battery"])
        if entry["holding"]:
            held[entry["holding"]] = robot
    _objects_as_in(world, data["objects"])
    for entry in data["objects"]:
        if entry["name"] in held:
            continue
        x, y, yaw = entry["pose"]
        world.sim.update_object(entry["name"], loc=entry["parent"], pose=_pose(x, y, yaw))
    for name, robot in held.items():
        robot._attach_object(world.sim.get_object_by_name(name))
    for key, state in data["rng"].items():
        robot_name, action = key.split("/", 1)
        options[(robot_name, action)].rng.bit_generator.state = state
    world.clock.reset(float(data["time"]))
    world.actions_run = int(data["actions_run"])
    world.faults = int(data["faults"])
    world.distance_m = float(data["distance_m"])
    # (Snapshots written before trails were recorded lack them: the trails start here.)
    world.trails = {r.name: [] for r in world.sim.robots}
    for name, parts in data.get("trails", {}).items():
        world.trails[name] = [[[float(x), float(y)] for x, y in part] for part in parts]
    # (Snapshots written before battery use was counted lack these: the world's own.)
    world.battery_start.update({k: float(v) for k, v in data.get("battery_start", {}).items()})
    world.charged.update({k: float(v) for k, v in data.get("charged", {}).items()})
    world.searched = set(data["searched"])
    # (Snapshots written before the map lack these: the world file's and none.)
    world.seen_open.update({k: bool(v) for k, v in data.get("seen_open", {}).items()})
    world.crossed = {
        r.name: list(data.get("crossed", {}).get(r.name, [])) for r in world.sim.robots
    }
    world.changes = list(data["changes"])
    world.sim.mark_changed()
    return parse_events(
        [{k: v for k, v in e.items() if k != "origin"} for e in data["pending"]], "checkpoint"
    )
