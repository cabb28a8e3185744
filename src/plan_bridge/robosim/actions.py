"""The robot actions of the robosim domain, over pyrobosim's robot API.

Each function runs one action of one robot in a :class:`~.world.RobosimWorld` and
returns an :class:`~.world.ActionResult` (pyrobosim's ``ExecutionStatus``): it applies
the events that are due, calls pyrobosim in a worker thread (a preempt cancels the
robot's action), and spends the action's simulated time on the world's clock. The
skills (:mod:`.skills`) are SMACH machines made of these calls.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Callable
from typing import Any

from plan_bridge.robosim.world import ACTION_SECONDS, ActionResult, RobosimWorld

__all__ = ["act", "follow", "plan_drive"]

Preempted = Callable[[], bool]


def plan_drive(world: RobosimWorld, robot: Any, target: str) -> tuple[Any, ActionResult]:
    """Plan the path of a drive to spot ``target`` (pyrobosim's path planner)."""
    spot = world.model.spots.get(world.name(target))
    if spot is None:
        return None, ActionResult("INVALID_ACTION", f"{target} is not a spot of {world.model.name}")
    world.begin(robot)
    if spot.kind == "door":
        goal: Any = _door_pose(world, spot.name)
    else:
        goal = world.sim.get_entity_by_name(spot.name)
    began = time.perf_counter()
    path = _without_repeats(robot.plan_path(goal=goal))
    world.robot_wall_s += time.perf_counter() - began
    if path is None or path.num_poses < 2:
        if (path is not None and path.num_poses == 1) or world.spot_of(robot) == spot.name:
            return None, ActionResult("SUCCESS", f"already at {spot.name}")
        return None, ActionResult(
            "PLANNING_FAILURE", f"no path from {world.spot_of(robot)} to {spot.name}"
        )
    return path, ActionResult("SUCCESS")


def _without_repeats(path: Any) -> Any:
    """``path`` without waypoints at the position of the one before (the last one's yaw
    kept). pyrobosim's bidirectional RRT sometimes puts the node where its two trees met
    twice, the second time with a yaw of 0 (``fill_yaws`` of a zero-length leg): the
    robot would turn there and back (time that differs from run to run, as whether it
    happens depends on the order of a set of nodes), and pyrobosim would warn about
    trajectory points at the same time."""
    from pyrobosim.utils.path import Path

    if path is None or path.num_poses < 2:
        return path
    kept = [path.poses[0]]
    for index, pose in enumerate(path.poses[1:], start=1):
        if _dist(kept[-1], pose) > 1e-9:
            kept.append(pose)
        elif index == path.num_poses - 1 and len(kept) > 1:
            kept[-1] = pose
    if len(kept) == path.num_poses:
        return path
    return Path(poses=kept, planning_time=path.planning_time)


def cross_path(
    world: RobosimWorld, robot: Any, hall_name: str, target: str
) -> tuple[Any, ActionResult]:
    """The path through a hallway to its end ``target``: its centre line."""
    from pyrobosim.utils.path import Path

    world.begin(robot)
    hall = world.sim.get_hallway_by_name(world.name(hall_name))
    if hall is None:
        return None, ActionResult("INVALID_ACTION", f"no hallway {hall_name}")
    if not hall.is_open:
        return None, ActionResult("PRECONDITION_FAILURE", f"{hall.name} is closed")
    goal = _door_pose(world, world.name(target))
    nodes = [node.pose for node in hall.graph_nodes]
    if _dist(nodes[0], goal) < _dist(nodes[-1], goal):
        nodes.reverse()
    poses = [robot.get_pose()]
    for pose in [*nodes, goal]:
        if _dist(poses[-1], pose) > 1e-6:
            poses.append(pose)
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
    """One action that is not a drive: pick, place, open, close, detect or charge."""
    from pyrobosim.planning.actions import TaskAction

    world.begin(robot)
    seconds = ACTION_SECONDS[action]
    if world.time_scale > 0 and not world.wait_paced(seconds, preempted):
        return ActionResult("CANCELED", f"{action} preempted")
    if action == "charge":
        result = _charge(world, robot, args)
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
    spot = world.name(args[2] if action in ("pick", "place", "open", "close") else args[1])
    if action in ("open", "close"):
        here = world.spot_of(robot)
        if here != spot:
            return ActionResult("PRECONDITION_FAILURE", f"{robot.name} is at {here}, not at {spot}")
        gate = world.name(args[1])
        if world.model.spots[here].gate != gate:
            return ActionResult("PRECONDITION_FAILURE", f"{gate} cannot be reached from {here}")
        return None
    here = world.spot_of(robot)
    if here != spot:
        return ActionResult("PRECONDITION_FAILURE", f"{robot.name} is at {here}, not at {spot}")
    return None


def _charge(world: RobosimWorld, robot: Any, args: list[str]) -> ActionResult:
    spot = world.name(args[1])
    location = world.name(args[2])
    here = world.spot_of(robot)
    gate = world.model.gates.get(location)
    if here != spot or gate is None or not gate.is_charger or spot not in gate.spawns:
        return ActionResult("PRECONDITION_FAILURE", f"{robot.name} is at {here}, not at a charger")
    if world.draw_fault(robot, "charge"):
        return ActionResult("EXECUTION_FAILURE", "Simulated charging failure.")
    world.recharge(robot)
    return ActionResult("SUCCESS")


def _door_pose(world: RobosimWorld, door: str) -> Any:
    spot = world.model.spots[door]
    hall = world.sim.get_hallway_by_name(spot.gate)
    return min(hall.nav_poses, key=lambda p: math.hypot(p.x - spot.x, p.y - spot.y))


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
