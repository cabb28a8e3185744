"""The robot actions of the robosim domain, over pyrobosim's robot API.

Each function runs one action of one robot in a :class:`~.world.RobosimWorld` and
returns an :class:`~.results.ActionResult` (pyrobosim's ``ExecutionStatus``): it applies
the events that are due, calls pyrobosim in a worker thread (a preempt cancels the
robot's action), and spends the action's simulated time on the world's clock. The
skills (:mod:`.skills`) are SMACH machines made of these calls.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from typing import Any

from plan_bridge.maps.graph import Leg, Route
from plan_bridge.robosim.description import AT_PLACE_M
from plan_bridge.robosim.results import ACTION_SECONDS, ActionResult
from plan_bridge.robosim.room_paths import room_path
from plan_bridge.robosim.world import RobosimWorld

__all__ = ["act", "cross_path", "drive_route", "follow", "plan_route"]

Preempted = Callable[[], bool]


def plan_route(world: RobosimWorld, robot: Any, target: str) -> tuple[Route | None, ActionResult]:
    """The route of a drive to place ``target``: the map's shortest way over the
    hallways the robots have not seen closed."""
    place = world.name(target)
    if place not in world.model.places:
        return None, ActionResult(
            "INVALID_ACTION", f"{target} is not a place of {world.model.name}"
        )
    world.begin(robot)
    here = world.spot_of(robot)
    if here == place and _at_pose(world, robot, place):
        return None, ActionResult("SUCCESS", f"already at {place}")
    route = world.map.route(here, place, world.closed_halls())
    if route is None:
        shut = ", ".join(sorted(world.closed_halls())) or "none"
        return None, ActionResult(
            "PLANNING_FAILURE",
            f"no way from {here} to {place} over the hallways not seen closed (closed: {shut})",
        )
    return route, ActionResult("SUCCESS")


def drive_route(
    world: RobosimWorld, robot: Any, route: Route, preempted: Preempted
) -> ActionResult:
    """Drive ``route`` leg by leg: inside a room straight to the next place (round what
    is in the way with pyrobosim's planner), through a hallway along its centre line. A
    hallway found closed at its doorway ends the drive there."""
    first = True
    legs = list(route.legs) or [Leg(route.places[0], route.places[-1], None)]
    for leg in legs:
        if leg.hall is not None:
            path, result = cross_path(world, robot, leg.hall, leg.end, begin=False)
        else:
            path, result = _room_path(world, robot, leg.end), ActionResult("SUCCESS")
        if result.status != "SUCCESS":
            return result
        if path is None:
            continue
        result = follow(world, robot, path, preempted, first=first)
        first = False
        if result.status != "SUCCESS":
            return result
        if leg.hall is not None:
            world.crossed.setdefault(robot.name, []).append(leg.hall)
    return ActionResult("SUCCESS")


def _at_pose(world: RobosimWorld, robot: Any, place: str) -> bool:
    pose = robot.get_pose()
    info = world.model.places[place]
    return math.hypot(float(pose.x) - info.x, float(pose.y) - info.y) < AT_PLACE_M


def _place_pose(world: RobosimWorld, place: str, heading_from: Any) -> Any:
    """Where a robot stands at ``place``: the pose pyrobosim gives the spawn or room it
    is named after, else its point facing away from ``heading_from``."""
    from pyrobosim.utils.pose import Pose

    entity = world.sim.get_entity_by_name(place)
    poses = getattr(entity, "nav_poses", None) if entity is not None else None
    info = world.model.places[place]
    if poses and math.hypot(float(poses[0].x) - info.x, float(poses[0].y) - info.y) < 0.05:
        return poses[0]
    yaw = math.atan2(info.y - float(heading_from.y), info.x - float(heading_from.x))
    return Pose(x=info.x, y=info.y, yaw=yaw)


def _room_path(world: RobosimWorld, robot: Any, target: str) -> Any:
    """A path inside the room of place ``target`` to it: straight when nothing is in
    the way, else round the furniture (:mod:`.room_paths`)."""
    from pyrobosim.utils.path import Path
    from pyrobosim.utils.pose import Pose

    start = robot.get_pose()
    goal = _place_pose(world, target, start)
    if _dist(start, goal) < 1e-6:
        return None
    room = world.sim.get_room_by_name(world.model.places[target].room)
    if room is None:
        return Path(poses=[start, goal])
    points = room_path(room, (float(start.x), float(start.y)), (float(goal.x), float(goal.y)))
    poses = [start]
    for x, y in points[1:-1]:
        yaw = math.atan2(y - float(poses[-1].y), x - float(poses[-1].x))
        poses.append(Pose(x=x, y=y, yaw=yaw))
    poses.append(goal)
    return Path(poses=poses)


def cross_path(
    world: RobosimWorld, robot: Any, hall_name: str, target: str, *, begin: bool = True
) -> tuple[Any, ActionResult]:
    """The path through a hallway to its doorway ``target``: its centre line; refused
    when the hallway is closed (what the robot sees at its door)."""
    from pyrobosim.utils.path import Path
    from pyrobosim.utils.pose import Pose

    if begin:
        world.begin(robot)
    name = world.name(hall_name)
    hall = world.model.halls.get(name)
    entity = world.sim.get_hallway_by_name(name)
    if hall is None or entity is None:
        return None, ActionResult("INVALID_ACTION", f"no hallway {hall_name}")
    if name in world.seen_open:
        world.seen_open[name] = bool(entity.is_open)
    if not entity.is_open:
        return None, ActionResult("PRECONDITION_FAILURE", f"{name} is closed")
    points = list(hall.path)
    if world.name(target) == hall.ends[0]:
        points.reverse()
    poses = [robot.get_pose()]
    for x, y in points:
        if math.hypot(float(poses[-1].x) - x, float(poses[-1].y) - y) > 1e-6:
            yaw = math.atan2(y - float(poses[-1].y), x - float(poses[-1].x))
            poses.append(Pose(x=x, y=y, yaw=yaw))
    if len(poses) < 2:
        return None, ActionResult("SUCCESS", f"already at {target}")
    return Path(poses=poses), ActionResult("SUCCESS")


def follow(
    world: RobosimWorld, robot: Any, path: Any, preempted: Preempted, *, first: bool = True
) -> ActionResult:
    """Drive ``path``; an event due on the way happens where the robot is then, and the
    drive goes on only if the rest of its path is still free."""
    from pyrobosim.planning.actions import TaskAction
    from pyrobosim.utils.path import Path
    from pyrobosim.utils.world_collision import is_path_collision_free

    traj, interp = _trajectory(robot, path)
    duration = float(traj.t_pts[-1]) if traj is not None else 0.0
    start = world.now()
    next_event = world.next_event_time()
    event_at = start if next_event is None else next_event
    head = path
    split = next_event is not None and start < event_at < start + duration and interp is not None
    if split:
        k = max(i for i, t in enumerate(interp.t_pts) if t <= event_at - start)
        head = Path(poses=list(interp.poses[: k + 1])) if k >= 1 else None
    result = ActionResult("SUCCESS")
    before = robot.get_pose()
    level_before = float(robot.battery_level)
    if head is not None:
        action = TaskAction("navigate", robot=robot.name, path=head)

        def call() -> Any:
            # The first leg is pyrobosim's navigate action (its fault draw, its battery);
            # the legs after an event follow the rest of the same path.
            if first:
                return robot.execute_action(action, world.realtime_factor)
            return robot.follow_path(head, realtime_factor=world.realtime_factor)

        result = world.run_blocking(robot, call, preempted)
    driven = _driven(traj, interp, robot, before, head is path, result)
    if traj is not None:
        passed = (p for t, p in zip(traj.t_pts, traj.poses, strict=True) if 0 < t < driven[0])
        world.record_drive(robot, [before, *passed, robot.get_pose()])
    world.distance_m += driven[1]
    world.count_drive(robot, level_before, driven[1])
    world.elapse(driven[0] if not split or result.status != "SUCCESS" else event_at - start)
    world.apply_due_events()
    if not split or result.status != "SUCCESS":
        return result
    rest = [
        robot.get_pose(),
        *(p for t, p in zip(traj.t_pts, traj.poses, strict=True) if t > event_at - start),
    ]
    if len(rest) < 2:
        return result
    remaining = Path(poses=rest)
    if not is_path_collision_free(remaining, robot=robot, step_dist=0.025):
        changed = "; ".join(world.changes[-3:])
        return ActionResult("EXECUTION_FAILURE", f"the rest of the path is blocked ({changed})")
    return follow(world, robot, remaining, preempted, first=False)


def act(
    world: RobosimWorld, robot: Any, action: str, args: list[str], preempted: Preempted
) -> ActionResult:
    """One action that is not a drive: pick, place, open, close, detect, search or charge."""
    from pyrobosim.planning.actions import TaskAction

    world.begin(robot)
    seconds = ACTION_SECONDS[action]
    if world.time_scale > 0 and not world.wait_paced(seconds, preempted):
        return ActionResult("CANCELED", f"{action} preempted")
    if action == "charge":
        result = _charge(world, robot, args)
    elif action == "search":
        result = _check_place(world, robot, action, args) or _search(world, args)
    elif action in ("open", "close") and world.name(args[1]) in world.model.halls:
        result = _check_place(world, robot, action, args) or _door(world, robot, action, args)
    else:
        task = TaskAction(action, robot=robot.name)
        if action == "pick":
            task = TaskAction("pick", robot=robot.name, object=world.name(args[1]))
        refused = _check_place(world, robot, action, args)
        if refused is not None:
            result = refused
        else:
            with world.quietly():
                result = world.run_blocking(
                    robot, lambda: robot.execute_action(task, world.realtime_factor), preempted
                )
    if result.status == "SUCCESS" and action == "detect":
        world.searched.add(world.name(args[1]))
    world.elapse(seconds)
    world.apply_due_events()
    return result


def _check_place(
    world: RobosimWorld, robot: Any, action: str, args: list[str]
) -> ActionResult | None:
    """The step's place is where the robot is (pyrobosim acts where the robot stands)."""
    spot = world.name(
        args[2] if action in ("pick", "place", "open", "close", "search") else args[1]
    )
    if action in ("open", "close"):
        here = world.spot_of(robot)
        if here != spot:
            return ActionResult("PRECONDITION_FAILURE", f"{robot.name} is at {here}, not at {spot}")
        gate = world.name(args[1])
        if gate not in world.model.places[here].gates:
            return ActionResult("PRECONDITION_FAILURE", f"{gate} cannot be reached from {here}")
        return None
    here = world.spot_of(robot)
    if here != spot:
        return ActionResult("PRECONDITION_FAILURE", f"{robot.name} is at {here}, not at {spot}")
    return None


def _search(world: RobosimWorld, args: list[str]) -> ActionResult:
    """Look for an object at the spawns of the robot's place: found, or not there
    (the LOOK after it reports what is there, and where the object is not)."""
    item, place = world.name(args[1]), world.name(args[2])
    info = world.model.places.get(place)
    location = world.sim.get_entity_by_name(info.fixture) if info and info.fixture else None
    if location is None or not location.is_open:
        return ActionResult("PRECONDITION_FAILURE", f"cannot see into {args[3]}: it is closed")
    for spawn in info.spawns if info is not None else ():
        entity = world.sim.get_entity_by_name(spawn)
        if entity is not None and any(child.name == item for child in entity.children):
            return ActionResult("SUCCESS", f"{item} found at {spawn}")
    return ActionResult("POSTCONDITION_FAILURE", f"{item} is not at {place}")


def _charge(world: RobosimWorld, robot: Any, args: list[str]) -> ActionResult:
    spot = world.name(args[1])
    location = world.name(args[2])
    here = world.spot_of(robot)
    gate = world.model.gates.get(location)
    if here != spot or gate is None or not gate.is_charger or location != _fixture(world, spot):
        return ActionResult("PRECONDITION_FAILURE", f"{robot.name} is at {here}, not at a charger")
    if world.draw_fault(robot, "charge"):
        return ActionResult("EXECUTION_FAILURE", "Simulated charging failure.")
    world.recharge(robot)
    return ActionResult("SUCCESS")


def _door(world: RobosimWorld, robot: Any, action: str, args: list[str]) -> ActionResult:
    """Open or close a hallway from its doorway. (pyrobosim's robot opens a hallway
    only from where pyrobosim puts its ends, which for ``auto`` hallways is the room's
    centre: the world opens it, with the robot's own fault draw.)"""
    hall = world.name(args[1])
    if robot.manipulated_object is not None:  # as pyrobosim's robot says it
        return ActionResult("PRECONDITION_FAILURE", f"Robot is holding an object. Cannot {action}.")
    if world.draw_fault(robot, action):
        return ActionResult("EXECUTION_FAILURE", f"Simulated {action} failure.")
    call = world.sim.open_location if action == "open" else world.sim.close_location
    with world.quietly():
        result = ActionResult.of(call(hall))
    if result.status == "SUCCESS":
        for other in world.sim.robots:
            other.update_polygons()
    world.seen_open[hall] = bool(world.sim.get_hallway_by_name(hall).is_open)
    return result


def _fixture(world: RobosimWorld, place: str) -> str | None:
    info = world.model.places.get(place)
    return info.fixture if info is not None else None


def _dist(a: Any, b: Any) -> float:
    return math.hypot(float(a.x) - float(b.x), float(a.y) - float(b.y))


def _trajectory(robot: Any, path: Any) -> tuple[Any, Any]:
    from pyrobosim.utils.trajectory import get_constant_speed_trajectory, interpolate_trajectory

    executor = robot.path_executor
    speed = float(getattr(executor, "linear_velocity", 1.0) or 1.0)
    turn = getattr(executor, "max_angular_velocity", None)
    traj = get_constant_speed_trajectory(path, linear_velocity=speed, max_angular_velocity=turn)
    if traj is None or traj.num_points() < 2:
        return None, None
    interp = interpolate_trajectory(traj, float(getattr(executor, "dt", 0.1) or 0.1))
    return traj, interp


def _driven(
    traj: Any, interp: Any, robot: Any, before: Any, whole: bool, result: ActionResult
) -> tuple[float, float]:
    """(simulated seconds, metres) of a drive that ended with ``result``."""
    if traj is None:
        return 0.0, 0.0
    if result.status == "SUCCESS" and whole:
        return float(traj.t_pts[-1]), float(
            sum(_dist(p, q) for p, q in itertools.pairwise(traj.poses))
        )
    if interp is None:
        return 0.0, _dist(before, robot.get_pose())
    pose = robot.get_pose()
    index = min(range(interp.num_points()), key=lambda i: _dist(interp.poses[i], pose))
    metres = sum(_dist(p, q) for p, q in itertools.pairwise(interp.poses[: index + 1]))
    return float(interp.t_pts[index]), float(metres)
