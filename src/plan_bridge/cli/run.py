"""The ``run`` subcommand of ``plan-bridge`` (``check`` is in :mod:`.check`).

Only argparse configuration happens at import time; everything heavy (unified-
planning, smach, the domain's code) is imported when a command runs.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
import time
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

from plan_bridge.cli.base import (
    EXIT_FAILED,
    EXIT_OK,
    Command,
    InputError,
    add_input_arguments,
    bounded,
    check_input,
    fail,
    positive_seconds,
    resolve_input,
)
from plan_bridge.cli.progress import ProgressPrinter
from plan_bridge.cli.progress import summary_text as _summary
from plan_bridge.missions.runner import DEFAULT_FAIL_RATE

if TYPE_CHECKING:
    from plan_bridge.missions.runner import Mission, MissionOptions
    from plan_bridge.missions.target import MissionSetup, Target
    from plan_bridge.planning.types import Planner

__all__ = ["ProgressPrinter"]

VIEWER_TIME_SCALE = 0.1
"""Wall seconds per simulated second of a simulated mission shown in the viewer."""


_probability = bounded(float, 0.0, 1.0, "a probability between 0 and 1")
_non_negative_int = bounded(int, 0, float("inf"), "a whole number >= 0")


def _breakpoint(text: str) -> str:
    from smach.control import ControlError, check_pattern

    try:
        return check_pattern(text)
    except ControlError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _configure_run(parser: argparse.ArgumentParser) -> None:
    add_input_arguments(parser, optional=True)
    parser.add_argument(
        "--planner",
        default="auto",
        help="unified-planning engine (default: auto: Fast Downward for classical "
        "problems, Kairos or TAMER for temporal and numeric ones)",
    )
    parser.add_argument(
        "--seed", type=_non_negative_int, default=0, help="seed of the simulated faults (default 0)"
    )
    parser.add_argument(
        "--fail-rate",
        type=_probability,
        default=None,
        help=f"probability that an action fails in the simulated world (default: {DEFAULT_FAIL_RATE} for "
        "domain folders with skills, 0 for symbolic skills)",
    )
    parser.add_argument(
        "--max-replans",
        type=_non_negative_int,
        default=10,
        help="planner calls after the first (default 10)",
    )
    parser.add_argument(
        "--policy", default="full", help="recovery policy: full, no-replan, retry-only, replan-only"
    )
    parser.add_argument(
        "--timeout",
        type=positive_seconds,
        default=60.0,
        help="hard limit of one planner call, seconds",
    )
    parser.add_argument(
        "--concurrent", action="store_true", help="run independent steps concurrently"
    )
    parser.add_argument("--journal", metavar="FILE", help="write every event as JSON lines to FILE")
    parser.add_argument(
        "--events",
        metavar="EVENTS.yaml",
        help="with a pyrobosim world: changes of the world at simulated times (a hallway "
        "closed, an object moved; see docs/sim.md)",
    )
    orders = parser.add_argument_group("orders over time", "see docs/orders.md")
    orders.add_argument(
        "--orders",
        metavar="ORDERS.yaml",
        help="serve the orders of ORDERS.yaml as they arrive (simulated seconds; Poisson "
        "streams drawn from --seed) instead of the target's goal; the run ends when every "
        "order is done, failed, refused or cancelled",
    )
    orders.add_argument(
        "--orders-open",
        action="store_true",
        help="also take orders sent while the mission runs (plan-bridge control URL order "
        "GOAL, the viewer, ROS 2); the run goes on until stopped",
    )
    parser.add_argument(
        "--snapshot",
        metavar="FILE.svg|.png",
        help="with a pyrobosim world: when the run ends, write a picture of it (map, paths "
        "driven, final poses; see docs/sim.md)",
    )
    parser.add_argument(
        "--viewer",
        nargs="?",
        const=0,
        type=_non_negative_int,
        metavar="PORT",
        help="serve the live viewer on 127.0.0.1 while the mission runs and after it, until "
        "Ctrl-C (default port: any free one); the simulated world runs at --time-scale",
    )
    parser.add_argument(
        "--time-scale",
        type=bounded(float, 0.0, 1e6, "seconds >= 0"),
        default=None,
        metavar="S",
        help="wall seconds per simulated second of the simulated world (default: "
        f"{VIEWER_TIME_SCALE} with --viewer, else 0: as fast as it goes); with --ros, of the "
        "robot started here (default 0.01)",
    )
    parser.add_argument(
        "-v",
        "--verbose",
        action="store_true",
        help="also print the states each step enters (with --ros: the robot's own lines)",
    )
    control = parser.add_argument_group("runtime control", "see docs/control.md")
    control.add_argument(
        "--control",
        action="store_true",
        help="serve the viewer with control buttons and print a control URL (with a per-run "
        "token) for the page and for `plan-bridge control`",
    )
    control.add_argument(
        "--break",
        dest="breakpoints",
        action="append",
        type=_breakpoint,
        default=[],
        metavar="PATTERN",
        help="pause before entering states matching PATTERN (a path or glob); repeatable",
    )
    control.add_argument(
        "--start-paused", action="store_true", help="hold the first state until resumed"
    )
    parser.add_argument(
        "--resume",
        metavar="RUN.jsonl",
        help="continue a run that was killed, from its journal (TARGET and options come from it)",
    )
    parser.add_argument(
        "--json", action="store_true", help="print one JSON object with the results"
    )
    parser.add_argument("--quiet", action="store_true", help="no progress output")
    ros = parser.add_argument_group(
        "across processes (ROS 2)", "see docs/ros.md, 'Missions across processes'"
    )
    ros.add_argument(
        "--ros",
        action="store_true",
        help="run the skills on a robot node over ROS 2; the node is started here as a "
        "subprocess (python -m plan_bridge.ros.skill_server) unless --no-robot",
    )
    ros.add_argument(
        "--no-robot",
        action="store_true",
        help="with --ros: start no robot node; connect to the one already running (on this "
        "machine or another, same ROS_DOMAIN_ID) under --ros-prefix",
    )
    ros.add_argument(
        "--ros-prefix",
        metavar="NAME",
        help="with --ros: the robot's action and service prefix (default: robot with "
        "--no-robot, robot_PID for a robot started here)",
    )


def _run(args: argparse.Namespace) -> int:
    from plan_bridge.errors import PlanBridgeError

    started = time.monotonic()
    try:
        with contextlib.ExitStack() as resources:
            return _run_mission(args, started, resources)
    except PlanBridgeError as exc:
        return fail(str(exc))
    except OSError as exc:
        return fail(f"{getattr(exc, 'filename', '') or ''}: {exc.strerror or exc}")


RESUMABLE = (
    "target",
    "problem",
    "seed",
    "fail_rate",
    "planner",
    "policy",
    "max_replans",
    "timeout",
    "concurrent",
)
#: Run options a resume takes from the journal when it has them (journals written
#: before they were recorded lack them: then they are off).
RESUMED_IF_RECORDED = ("orders", "orders_open")
#: Run options a resume takes from the journal unless given again (journals written
#: before they were recorded lack them).
RESUMED_UNLESS_GIVEN = ("time_scale",)
#: What a pyrobosim world's run needs besides the target (None for other targets):
#: its goal (the text, so that a goals.yaml edited since does not change the run)
#: and its events file; a PDDL problem's run, the goal given with --goal (None: the
#: file's). Taken from the journal; journals written before lack them.
RESUMED_WORLD = ("goal", "events")


def _resume_arguments(
    args: argparse.Namespace,
) -> tuple[dict[str, Any], dict[str, Any] | None] | int:
    """Take the run's options from the journal's header; find the last checkpoint."""
    from smach.introspection.journal import read_journal, read_states

    if args.target is not None:
        return fail("with --resume, the target and options come from the journal: give no TARGET")
    given = [f"--{key}" for key in RESUMED_WORLD if getattr(args, key) is not None]
    if given:
        return fail(
            f"with --resume, the goal and events of the run come from the journal: "
            f"give no {' or '.join(given)}"
        )
    try:
        header, records = read_journal(args.resume)
    except (OSError, ValueError) as exc:
        return fail(f"{args.resume}: cannot read the journal: {exc}")
    run = header.get("run")
    if not isinstance(run, dict) or any(k not in run for k in RESUMABLE):
        return fail(
            f"{args.resume}: not a journal of 'plan-bridge run --journal' (no run options in its header)"
        )
    for key in RESUMABLE:
        setattr(args, key, run[key])
    for key in RESUMED_UNLESS_GIVEN:
        if getattr(args, key) is None and run.get(key) is not None:
            setattr(args, key, run[key])
    for key in RESUMED_IF_RECORDED:
        if key in run:
            setattr(args, key, run[key])
    for key in RESUMED_WORLD:
        setattr(args, key, run.get(key))
    if run.get("ros"):
        return fail(
            f"{args.resume}: a run with --ros cannot be resumed: the robot's world lives in its "
            f"own process and the journal holds no snapshot of it"
        )
    if any(r.get("kind") == "summary" for r in records):
        return fail(f"{args.resume}: that run already finished (the journal has its summary)")
    try:
        checkpoints = read_states(records, "checkpoint")
    except (ValueError, TypeError, KeyError) as exc:
        return fail(f"{args.resume}: its checkpoints cannot be read: {exc}")
    return run, checkpoints[-1] if checkpoints else None


def _is_world(target: Target) -> bool:
    from plan_bridge.missions.world_target import WorldTarget

    return isinstance(target, WorldTarget)


def _world_options(args: argparse.Namespace, target: Target) -> dict[str, Any]:
    """The journal's record of a pyrobosim run's goal and events (see RESUMED_WORLD)."""
    from plan_bridge.missions.world_target import WorldTarget

    if not isinstance(target, WorldTarget):
        # A PDDL problem's goal given with --goal is resumed by its text too.
        return {**dict.fromkeys(RESUMED_WORLD), "goal": target.given_goal}
    return {
        # A goal of goals.yaml is resumed by its text, under its name.
        "problem": target.goal_name or str(target.problem_path),
        "goal": target.goal_text,
        "events": None if args.events is None else str(args.events),
    }


def _connect_robot(
    args: argparse.Namespace, target: Target, fail_rate: float | None, resources: Any
) -> Any:
    """Start (or find) the robot node of ``--ros`` and connect to it."""
    from plan_bridge.ros.connection import RobotConnection

    robot = RobotConnection(
        target,
        prefix=args.ros_prefix,
        start_robot=not args.no_robot,
        seed=args.seed,
        fail_rate=fail_rate,
        time_scale=0.01 if args.time_scale is None else args.time_scale,
        # A pyrobosim world's events happen in the robot's process, on its clock.
        events=args.events,
        log=None if args.quiet else sys.stderr,
        echo_robot=args.verbose,  # the robot's goals and skill states: with -v only
        robot_nodes=_is_world(target),  # a pyrobosim world: a node per robot
    )
    resources.callback(robot.close)
    return robot.open()


def _run_mission(args: argparse.Namespace, started: float, resources: Any = None) -> int:
    from plan_bridge.missions.runner import prepare_mission

    resumed = _resume_point(args)
    if isinstance(resumed, int):
        return resumed
    checkpoint = resumed
    refusal = _refused_options(args) or _input_verdict(args)
    if refusal is not None:
        return refusal
    target, planner = _load_target(args)
    if args.snapshot and not _is_world(target):
        return fail(f"--snapshot draws pyrobosim worlds only; {target.name} is not one")
    start = _start_mission(args, target, resources)
    mission = prepare_mission(target, start.options, setup=start.setup, planner=planner)
    executive = mission.executive
    if start.robot is not None:
        # The mission's problem as a knowledge base, PlanSys2-style services on the
        # executive's node (/knowledge/add_problem_goal, ...; docs/planning.md).
        start.robot.serve_knowledge(mission.attach_knowledge())
        from plan_bridge.orders.order_executive import OrderExecutive

        if isinstance(executive, OrderExecutive):
            # Orders over ROS 2: /orders/submit, cancel, list, the status topic (docs/orders.md).
            start.robot.serve_orders(executive.desk())
            executive.robots_gone = start.robot.robots_gone  # its orders go to others
    if checkpoint is not None:
        mission.resume(checkpoint)
    if not args.quiet:
        verb = "resuming" if args.resume else "run"
        print(
            f"plan-bridge {verb}: {target.name}, {target.problem_label} "
            f"({start.skills_text}, seed {args.seed}, "
            f"fail rate {mission.fail_rate:g}, planner {mission.planner.name})",
            file=sys.stderr,
            flush=True,
        )
        executive.add_listener(ProgressPrinter(sys.stderr, verbose=args.verbose))
    journal = _open_journal(args, mission, target, checkpoint, start.robot)
    viewer = _serve_viewer(args, mission, journal, resources)
    outcome = mission.run()
    _report_run(args, mission, target, outcome)
    if viewer is not None and resources is not None:
        # The mission is over, the page is not: keep it for whoever is looking, with
        # the run's last events folded before saying so.
        viewer.catch_up()
        print(
            f"viewer: {viewer.url} - the mission ended; still serving it, Ctrl-C to stop",
            file=sys.stderr,
            flush=True,
        )
        with contextlib.suppress(KeyboardInterrupt):
            viewer.wait()
    return EXIT_OK if executive.report.goal_reached else EXIT_FAILED


def _resume_point(args: argparse.Namespace) -> dict[str, Any] | int | None:
    """The checkpoint a ``--resume`` continues from (None: from the start), or the exit
    code when the run cannot start."""
    if args.resume:
        resumed = _resume_arguments(args)
        if isinstance(resumed, int):
            return resumed
        return resumed[1]
    if args.target is None:
        return fail("give a TARGET (a domain folder or a domain.pddl), or --resume RUN.jsonl")
    return None


def _refused_options(args: argparse.Namespace) -> int | None:
    """The exit code for options that do not go together (None: they do)."""
    if not args.ros and (args.no_robot or args.ros_prefix):
        return fail("--no-robot and --ros-prefix need --ros")
    if args.ros and args.resume:
        return fail("--resume cannot be combined with --ros (the robot's world is not journaled)")
    if args.ros and args.no_robot and args.events:
        return fail(
            "--events with --no-robot: the world's events happen in the robot's process; give "
            "them to the robot node (python -m plan_bridge.ros.skill_server ... --events FILE)"
        )
    if args.snapshot:
        from plan_bridge.robosim.picture import picture_problem

        problem = picture_problem(args.snapshot) or (
            "--snapshot cannot be combined with --ros (the world lives in the robot's process)"
            if args.ros
            else None
        )
        if problem:
            return fail(problem)
    return None


def _input_verdict(args: argparse.Namespace) -> int | None:
    """The same front-end verdict as `check` and `plan`, before anything heavy loads:
    the exit code when the input is refused, else None (its warnings printed)."""
    try:
        chosen = resolve_input(args)
        pddl_goal = args.goal if chosen.world is None else None  # a world's: checked on load
        input_warnings = check_input(chosen.domain, chosen.problems[0], pddl_goal)
    except InputError as exc:
        return fail(str(exc))
    if not args.quiet:
        input_warnings.show()
    return None


def _load_target(args: argparse.Namespace) -> tuple[Target, Planner]:
    from plan_bridge.missions.mission import load_target
    from plan_bridge.planning.planner import get_planner
    from plan_bridge.planning.worker import default_pool

    planners: list[Planner] = []
    # A planner process parses the task while we parse it (prime); the planner name
    # is checked before our parse, so a wrong one is reported without waiting for it.
    target = load_target(
        args.target,
        args.problem,
        prime=default_pool(),
        before_parse=lambda: planners.append(get_planner(args.planner)),
        goal=args.goal,
        events=args.events,
    )
    return target, planners[0]


@dataclass
class _Start:
    """What a mission starts with: its options, its skills and world (None: simulated
    here), how its skills are described, and the robot node of ``--ros``."""

    options: MissionOptions
    setup: MissionSetup | None
    skills_text: str
    robot: Any = None


def _start_mission(args: argparse.Namespace, target: Target, resources: Any) -> _Start:
    from plan_bridge.missions.runner import MissionOptions
    from plan_bridge.missions.target import MissionSetup

    default_scale = VIEWER_TIME_SCALE if args.viewer is not None else 0.0
    options = MissionOptions(
        seed=args.seed,
        fail_rate=args.fail_rate,
        planner=args.planner,
        policy=args.policy,
        max_replans=args.max_replans,
        planner_timeout=args.timeout,
        concurrent=args.concurrent,
        time_scale=default_scale if args.time_scale is None else args.time_scale,
        orders=args.orders,
        orders_open=args.orders_open,
    )
    fail_rate = options.fail_rate_for(target)
    skills_text = "domain skills" if target.has_own_skills else "symbolic skills"
    if target.skill_map_path is not None:
        from plan_bridge.skills.ros.entries import runs_on_ros

        ros = target.folder is not None and runs_on_ros(target.folder)
        # A map that binds actions to ROS 2: those run on the robot's servers.
        skills_text += f" and {'ROS 2 servers of ' if ros else ''}{target.skill_map_path.name}"
    if not args.ros:
        return _Start(options, None, skills_text)
    # The skills run on the robot node, against its world: nothing is simulated here.
    robot = _connect_robot(args, target, args.fail_rate if args.no_robot else fail_rate, resources)
    # A running robot (--no-robot) has its own seed and fault rate: those count.
    fail_rate = robot.robot_info.get("fail_rate", fail_rate)
    args.seed = robot.robot_info.get("seed", args.seed)
    return _Start(
        replace(options, seed=args.seed, fail_rate=fail_rate),
        MissionSetup(
            skills=robot.skills(),
            world=robot.world(),
            concurrent=robot.concurrent,
            task_view=target.task_view,
            planner_for=target.planner_for,
        ),
        robot.describe(),
        robot,
    )


def _open_journal(
    args: argparse.Namespace,
    mission: Mission,
    target: Target,
    checkpoint: dict[str, Any] | None,
    robot: Any,
) -> Any:
    """The journal of ``--journal`` (or the resumed one's), with the run's options in
    its header; None without one."""
    journal_path = args.resume or args.journal
    if not journal_path:
        return None
    run_options = {
        key: getattr(args, key) for key in (*RESUMABLE, *RESUMED_UNLESS_GIVEN, *RESUMED_IF_RECORDED)
    }
    run_options.update(
        target=str(args.target), problem=str(target.problem_path), fail_rate=mission.fail_rate
    )
    run_options.update(_world_options(args, target))
    if robot is not None:
        # The robot's world lives in its process: checkpoints hold no world snapshot.
        run_options["ros"] = robot.prefix
    journal = mission.record(
        journal_path, header=run_options, exact={"run": run_options}, append=bool(args.resume)
    )
    if args.resume:
        journal.write_raw("resumed", checkpoint=checkpoint is not None)
    return journal


def _serve_viewer(args: argparse.Namespace, mission: Mission, journal: Any, resources: Any) -> Any:
    """The live viewer of ``--viewer``/``--control`` (None without) and the operator
    console of ``--control``, ``--break`` and ``--start-paused``."""
    executive = mission.executive
    viewer = None
    if args.viewer is not None or args.control:
        from smach.introspection import serve

        viewer = serve(executive, port=args.viewer or 0)
        # Closed after the wait below (the finished mission stays on the page), or on an error.
        if resources is not None:
            resources.callback(viewer.close)
        else:
            mission.on_close(viewer.close)
    if args.control or args.breakpoints or args.start_paused:
        from plan_bridge.execution.control import OperatorConsole

        console = OperatorConsole(
            executive, journal=journal, breakpoints=args.breakpoints, paused=args.start_paused
        )
        mission.on_close(console.close)
        if args.control and viewer is not None:
            from plan_bridge.orders.order_executive import OrderExecutive
            from smach.introspection.control_api import enable_controls

            actions = console.viewer_actions()
            if isinstance(executive, OrderExecutive):
                # Orders sent while it runs: order, cancel, orders (docs/orders.md).
                actions.update(executive.desk().actions())
            url = enable_controls(viewer, console.controller, actions=actions)
            print(f"control: {url}", file=sys.stderr, flush=True)
    return viewer


def _report_run(
    args: argparse.Namespace, mission: Mission, target: Target, outcome: str | None
) -> None:
    """The run's error, figures (``--json``), summary and picture (``--snapshot``)."""
    if mission.error is not None:
        print(f"plan-bridge: mission failed: {mission.error}", file=sys.stderr, flush=True)
    report = mission.executive.report
    figures = mission.figures()
    if args.json:
        print(json.dumps(figures, indent=None))
    if not args.quiet:
        print(
            _summary(outcome, report, figures.get("faults_injected")), file=sys.stderr, flush=True
        )
    if args.snapshot:
        from plan_bridge.robosim.picture import picture_title, write_picture
        from plan_bridge.robosim.world import RobosimWorld

        if isinstance(mission.world, RobosimWorld):
            goal = getattr(target, "goal_text", "")
            title = picture_title(target.name, goal, outcome or "stopped", figures)
            written = write_picture(mission.world, args.snapshot, title)
            print(f"picture: {written}", file=sys.stderr, flush=True)
    if args.quiet and not report.goal_reached:
        # No silent end: why the mission stopped (the summary says it without --quiet).
        print(f"plan-bridge: goal not reached: {report.explanation}", file=sys.stderr)


COMMANDS = (
    Command("run", "plan and execute a mission in the simulated world", _configure_run, _run),
)
