"""The robot node's process: ``python -m plan_bridge.ros.skill_server TARGET ...``.

Reads the command line, loads the target (a domain folder with its own skills and
simulated world, a pyrobosim world, or a bare domain for symbolic actions), builds
its world and skills, and serves them on a ROS 2 node with the server
:func:`run_robot_node` is given (:mod:`plan_bridge.ros.skill_server`'s ``main`` gives
its :class:`~plan_bridge.ros.skill_server.SkillServer`) until SIGINT or SIGTERM (or,
with ``--exit-with-parent``, until the process that started it is gone). See
:mod:`plan_bridge.ros.skill_server` for what it serves and prints.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import os
import signal
import sys
import threading
from collections.abc import Callable, Sequence
from typing import Any, Protocol

from plan_bridge.errors import PlanBridgeError
from plan_bridge.execution.simulation import SimulatedWorld
from plan_bridge.ros.lease import select_short_lease
from plan_bridge.ros.pacing import Pacer, pace
from smach.ros.executor import wait_for_callbacks
from smach.ros.rclpy_api import ExternalShutdownException, MultiThreadedExecutor, rclpy

__all__ = ["RobotServer", "run_robot_node"]


class RobotServer(Protocol):
    """What the process needs of the server it runs (a
    :class:`~plan_bridge.ros.skill_server.SkillServer`): to stop its skills, then to go."""

    def halt_all(self) -> None: ...

    def destroy(self) -> None: ...


#: Makes the server: called with the node, the world and the keywords of
#: :class:`~plan_bridge.ros.skill_server.SkillServer`.
ServerFactory = Callable[..., RobotServer]


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python -m plan_bridge.ros.skill_server",
        description="A simulated robot node: serve a domain's actions as ROS 2 actions. A "
        "domain folder runs its own skill state machines against its simulated world; a "
        "pyrobosim world (WORLD.yaml, or a folder with world.yaml) runs the robosim skills "
        "against it; a domain.pddl runs every action symbolically.",
    )
    parser.add_argument(
        "target",
        metavar="TARGET",
        help="a domain folder, a domain.pddl, or a pyrobosim world (WORLD.yaml or a folder)",
    )
    parser.add_argument("problem_file", metavar="PROBLEM", nargs="?", help="problem file")
    parser.add_argument(
        "--problem",
        help="problem file or name in the folder's problems/ (default: the first); for a "
        "pyrobosim world folder, a goal of its goals.yaml",
    )
    parser.add_argument(
        "--goal",
        help='the goal: of a pyrobosim world, e.g. "(At apple0 table0_tabletop)", or '
        "replacing a PDDL problem's (as plan-bridge run --goal)",
    )
    parser.add_argument(
        "--events",
        metavar="EVENTS.yaml",
        help="pyrobosim world: changes of the world at simulated times (docs/sim.md)",
    )
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--fail-rate",
        type=float,
        default=None,
        help="fault probability (default: 0.1 for a domain's own skills, 0 for symbolic ones)",
    )
    parser.add_argument(
        "--time-scale",
        type=float,
        default=0.01,
        help="wall seconds per simulated second of a domain's skills or a pyrobosim world "
        "(default 0.01; 0: no pacing)",
    )
    parser.add_argument(
        "--action-time", type=float, default=0.2, help="seconds per symbolic action"
    )
    parser.add_argument("--prefix", default="skills", help="action names: PREFIX/ACTION")
    parser.add_argument(
        "--robot",
        metavar="NAME",
        help="pyrobosim world: be robot NAME's node only: run its skills here, under "
        "PREFIX/NAME, acting through the world node under PREFIX (started without --robot)",
    )
    parser.add_argument(
        "--node-name", help="the ROS node's name (default: skill_server, robot_NAME with --robot)"
    )
    parser.add_argument(
        "--lease",
        type=float,
        default=2.0,
        help="DDS lease in seconds, so that executives notice a crashed robot in about that "
        "time (default 2; 0 keeps Fast DDS's 20 s; ignored if FASTDDS_DEFAULT_PROFILES_FILE is set)",
    )
    parser.add_argument(
        "--exit-with-parent",
        action="store_true",
        help="exit when the process that started this one exits (used by plan-bridge run --ros)",
    )
    return parser


@dataclasses.dataclass
class _Robot:
    """What the robot node serves: the loaded target, its world and how it runs."""

    target: Any
    setup: Any
    world: Any
    fail_rate: float
    symbolic: bool
    robosim: bool
    pacer: Pacer | None


def _load(args: argparse.Namespace) -> _Robot:
    """Load the target and build its world; PlanBridgeError or OSError if that fails."""
    from plan_bridge.missions.mission import load_target
    from plan_bridge.missions.world_target import WorldTarget

    target = load_target(
        args.target, args.problem or args.problem_file, goal=args.goal, events=args.events
    )
    robosim = isinstance(target, WorldTarget)
    if args.robot is not None:
        if not isinstance(target, WorldTarget):
            raise PlanBridgeError(
                f"--robot {args.robot}: a robot of its own process is for pyrobosim worlds only"
            )
        robots = target.robots()
        if args.robot.lower() not in robots:
            raise PlanBridgeError(
                f"--robot {args.robot}: no such robot in {target.name}; robots: {', '.join(robots)}"
            )
        args.robot = args.robot.lower()
    symbolic = not target.has_own_skills
    fail_rate = args.fail_rate if args.fail_rate is not None else (0.0 if symbolic else 0.1)
    setup = target.setup(seed=args.seed, fail_rate=fail_rate)
    if not symbolic:
        problems = setup.skills.check(target.task)
        if problems:
            raise PlanBridgeError("the skills do not fit the domain:\n  " + "\n  ".join(problems))
    world: Any = setup.world
    pacer = None
    if robosim:
        # A pyrobosim world paces itself: drives at pyrobosim's real-time factor 1/S,
        # the other actions wait S times their duration (RobosimWorld.time_scale).
        world.time_scale = args.time_scale
    elif not isinstance(world, SimulatedWorld):
        world = SimulatedWorld(target.task, seed=args.seed, fail_rate=fail_rate)
        symbolic = True
    if not symbolic and not robosim:
        pacer = Pacer(args.time_scale)
        pace(world, pacer)
    return _Robot(target, setup, world, fail_rate, symbolic, robosim, pacer)


def _meta(args: argparse.Namespace, robot: _Robot) -> dict[str, Any]:
    """What the robot's ``info`` service tells about its run."""
    from plan_bridge.missions.world_target import WorldTarget

    target = robot.target
    meta: dict[str, Any] = {
        "target": target.name,
        "problem": target.problem_path.name,
        "seed": args.seed,
        "fail_rate": robot.fail_rate,
        "time_scale": args.time_scale if not robot.symbolic else None,
        "action_time": args.action_time if robot.symbolic else None,
    }
    if isinstance(target, WorldTarget):
        meta.update(
            goal=target.goal_text,
            goal_name=target.goal_name,
            events=args.events,
            robots=target.robots(),
            robot=args.robot,
        )
    return meta


def run_robot_node(argv: Sequence[str] | None, make_server: ServerFactory) -> int:
    """Parse ``argv``, load the target and serve it with ``make_server``'s server; the
    exit status (2: the command line or the target is unfit)."""
    parser = _parser()
    args = parser.parse_args(argv)
    if args.problem and args.problem_file:
        parser.error("give the problem either as PROBLEM or as --problem, not both")
    if args.fail_rate is not None and not 0.0 <= args.fail_rate <= 1.0:
        parser.error(f"--fail-rate must be between 0 and 1, got {args.fail_rate}")
    if args.time_scale < 0:
        parser.error(f"--time-scale must be >= 0, got {args.time_scale}")
    try:
        robot = _load(args)
    except (PlanBridgeError, OSError) as exc:
        print(f"skill_server: {exc}", file=sys.stderr, flush=True)
        return 2
    profile = select_short_lease(args.lease)
    try:
        _serve(args, robot, make_server)
    finally:
        if robot.robosim:
            robot.world.close()
        if profile is not None:
            with contextlib.suppress(OSError):
                profile.unlink()
    return 0


def _serve(args: argparse.Namespace, robot: _Robot, make_server: ServerFactory) -> None:
    """Serve the robot's skills on a node until SIGINT/SIGTERM (or the parent exits)."""
    parent = os.getppid()
    rclpy.init()
    default_name = "skill_server" if args.robot is None else f"robot_{args.robot}"
    node = rclpy.create_node(args.node_name or default_name)

    def say(line: str) -> None:
        print(line, flush=True)

    skills = None if robot.symbolic else robot.setup.skills
    prefix = args.prefix.rstrip("/")
    bodies: Any = None
    if args.robot is not None:
        # One robot's node: its skill machines run here, its body is the world node's.
        from plan_bridge.robosim.skills import robosim_skills
        from plan_bridge.ros.body_link import RemoteBody

        skills = robosim_skills(robot.world, body=RemoteBody(node, prefix))
        prefix = f"{prefix}/{args.robot}"
    elif robot.robosim:
        # The world node: it serves its robots' bodies to robot nodes of their own.
        from plan_bridge.ros.body_link import BodyServer

        bodies = BodyServer(node, robot.world, prefix=prefix, log=say)
    server = make_server(
        node,
        robot.world,
        task=robot.target.task if robot.robosim else None,
        prefix=prefix,
        action_time=args.action_time,
        log=say,
        skills=skills,
        pacer=robot.pacer,
        concurrent=bool(robot.setup.concurrent) and not robot.symbolic and args.robot is None,
        meta=_meta(args, robot),
        robot=args.robot,
    )
    executor = MultiThreadedExecutor(num_threads=4)
    executor.add_node(node)
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    say("ready")
    try:
        while not stop.is_set() and rclpy.ok():
            executor.spin_once(timeout_sec=0.1)
            if args.exit_with_parent and os.getppid() != parent:
                say("parent exited")
                break
    except ExternalShutdownException:
        pass
    if args.robot is None:  # a robot's own node has no world: the world node counts
        say(f"faults {robot.world.faults_injected}")
    # Halt the skills, let the callbacks still running end (nothing spins any more),
    # then destroy: a service or action destroyed under its callback fails it.
    server.halt_all()
    wait_for_callbacks(executor, 5.0)
    executor.shutdown(timeout_sec=0)
    server.destroy()
    if bodies is not None:
        bodies.destroy()
    node.destroy_node()
    rclpy.try_shutdown()
