"""The ``run`` and ``check`` subcommands of ``plan-bridge``.

Only argparse configuration happens at import time; everything heavy (unified-
planning, smach, the domain's code) is imported when a command runs.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
import time
from typing import TYPE_CHECKING, Any, TextIO

from plan_bridge.cli.base import (
    EXIT_FAILED,
    EXIT_OK,
    Command,
    InputError,
    Terminated,
    add_input_arguments,
    bounded,
    check_input,
    fail,
    positive_seconds,
    resolve_input,
)

if TYPE_CHECKING:
    from plan_bridge.missions.mission import Target
    from smach.introspection.events import Event

__all__ = ["ProgressPrinter"]

DEFAULT_FAIL_RATE = 0.2
"""High enough that the default run of a domain folder shows a fault and the recovery."""
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
#: Run options a resume takes from the journal unless given again (journals written
#: before they were recorded lack them).
RESUMED_UNLESS_GIVEN = ("time_scale",)


def _resume_arguments(
    args: argparse.Namespace,
) -> tuple[dict[str, Any], dict[str, Any] | None] | int:
    """Take the run's options from the journal's header; find the last checkpoint."""
    from smach.introspection.journal import read_journal, read_states

    if args.target is not None:
        return fail("with --resume, the target and options come from the journal: give no TARGET")
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
        log=None if args.quiet else sys.stderr,
        echo_robot=args.verbose,  # the robot's goals and skill states: with -v only
    )
    resources.callback(robot.close)
    return robot.open()


def _run_mission(args: argparse.Namespace, started: float, resources: Any = None) -> int:
    from dataclasses import replace

    from plan_bridge.execution.executive import Executive, ReplanPolicy
    from plan_bridge.planning.planner import Planner, get_planner
    from smach import SmachError
    from smach.introspection.journal import Journal

    checkpoint: dict[str, Any] | None = None
    if args.resume:
        resumed = _resume_arguments(args)
        if isinstance(resumed, int):
            return resumed
        _, checkpoint = resumed
    elif args.target is None:
        return fail("give a TARGET (a domain folder or a domain.pddl), or --resume RUN.jsonl")
    if not args.ros and (args.no_robot or args.ros_prefix):
        return fail("--no-robot and --ros-prefix need --ros")
    if args.ros and args.resume:
        return fail("--resume cannot be combined with --ros (the robot's world is not journaled)")
    try:
        policy = replace(
            ReplanPolicy.named(args.policy),
            max_replans=args.max_replans,
            planner_timeout=args.timeout,
        )
    except ValueError as exc:
        return fail(str(exc))
    try:
        # The same front-end verdict as `check` and `plan`, before anything heavy loads.
        chosen = resolve_input(args)
        input_warnings = check_input(chosen.domain, chosen.problems[0])
    except InputError as exc:
        return fail(str(exc))
    if not args.quiet:
        for warning in input_warnings:
            print(f"warning: {warning}", file=sys.stderr, flush=True)
    from plan_bridge.missions.mission import load_target
    from plan_bridge.planning.worker import default_pool

    planners: list[Planner] = []
    # A planner process parses the task while we parse it (prime); the planner name
    # is checked before our parse, so a wrong one is reported without waiting for it.
    target = load_target(
        args.target,
        args.problem,
        prime=default_pool(),
        before_parse=lambda: planners.append(get_planner(args.planner)),
    )
    planner = planners[0]
    symbolic = target.module is None or not hasattr(target.module, "setup")
    fail_rate = (
        args.fail_rate if args.fail_rate is not None else (0.0 if symbolic else DEFAULT_FAIL_RATE)
    )
    robot = None
    if args.ros:
        from plan_bridge.missions.mission import MissionSetup

        # The skills run on the robot node, against its world: nothing is simulated here.
        robot = _connect_robot(
            args, target, args.fail_rate if args.no_robot else fail_rate, resources
        )
        # A running robot (--no-robot) has its own seed and fault rate: those count.
        fail_rate = robot.robot_info.get("fail_rate", fail_rate)
        args.seed = robot.robot_info.get("seed", args.seed)
        setup = MissionSetup(skills=robot.skills(), concurrent=robot.concurrent)
    else:
        setup = target.setup(seed=args.seed, fail_rate=fail_rate)
    problems = setup.skills.check(target.task)
    if problems:
        return fail("the skills do not fit the domain:\n  " + "\n  ".join(problems))
    executive = Executive(
        target.task,
        setup.skills,
        planner,
        policy=policy,
        sense=setup.sense,
        concurrent=setup.concurrent or args.concurrent,
    )
    world = setup.world
    if robot is None and hasattr(world, "time_scale"):
        default_scale = VIEWER_TIME_SCALE if args.viewer is not None else 0.0
        world.time_scale = default_scale if args.time_scale is None else args.time_scale
        # A temporal plan plays its timeline at the world's pace.
        executive.time_scale = float(world.time_scale)
    from plan_bridge.execution.temporal import TimelineRecorder

    timeline = TimelineRecorder()
    executive.add_listener(timeline)
    if checkpoint is not None:
        if checkpoint.get("world") is not None and hasattr(world, "restore"):
            world.restore(checkpoint["world"])
            world.abandon_running()  # steps in progress stopped with the process
        executive.resume_from(checkpoint["state"])
    out = sys.stderr
    if not args.quiet:
        verb = "resuming" if args.resume else "run"
        skills_text = "symbolic skills" if symbolic else "domain skills"
        if robot is not None:
            skills_text = f"{robot.robot_info.get('mode')} on the robot node /{robot.prefix}"
        print(
            f"plan-bridge {verb}: {target.name}, problem {target.problem_path.name} "
            f"({skills_text}, seed {args.seed}, "
            f"fail rate {fail_rate:g}, planner {planner.name})",
            file=out,
            flush=True,
        )
        executive.add_listener(ProgressPrinter(out, verbose=args.verbose))
    journal = None
    journal_path = args.resume or args.journal
    if journal_path:
        run_options = {key: getattr(args, key) for key in (*RESUMABLE, *RESUMED_UNLESS_GIVEN)}
        run_options.update(
            target=str(args.target), problem=str(target.problem_path), fail_rate=fail_rate
        )
        if robot is not None:
            # The robot's world lives in its process: checkpoints hold no world snapshot.
            run_options["ros"] = robot.prefix
        journal = Journal(
            journal_path,
            executive,
            header={**run_options, "run": run_options},
            append=bool(args.resume),
        )
        if args.resume:
            journal.write_raw("resumed", checkpoint=checkpoint is not None)
        active_journal = journal

        def write_checkpoint(state: dict[str, Any]) -> None:
            snap = world.snapshot() if hasattr(world, "snapshot") else None
            active_journal.write_state("checkpoint", state=state, world=snap)

        executive.checkpoint = write_checkpoint
    viewer = None
    if args.viewer is not None or args.control:
        from smach.introspection import serve

        viewer = serve(executive, port=args.viewer or 0)
    console = None
    if args.control or args.breakpoints or args.start_paused:
        from plan_bridge.execution.control import OperatorConsole

        console = OperatorConsole(
            executive, journal=journal, breakpoints=args.breakpoints, paused=args.start_paused
        )
        if args.control and viewer is not None:
            from smach.introspection.control_api import enable_controls

            url = enable_controls(viewer, console.controller, actions=console.viewer_actions())
            print(f"control: {url}", file=sys.stderr, flush=True)
    interrupted: KeyboardInterrupt | None = None
    try:
        outcome = executive.execute()
    except KeyboardInterrupt as exc:
        interrupted = exc  # Ctrl-C or SIGTERM: not an end, a resume continues the run
        raise
    except SmachError as exc:
        # A skill broke its contract (undeclared key, bad outcome, exception): the
        # message names the state path; the mission failed.
        outcome = None
        executive.report.explanation = str(exc)
        print(f"plan-bridge: mission failed: {exc}", file=sys.stderr, flush=True)
    finally:
        if console is not None:
            console.close()
        if viewer is not None and resources is not None:
            resources.callback(viewer.close)  # after the wait below, or on an error
        elif viewer is not None:
            viewer.close()
        report = executive.report
        if journal is not None:
            if interrupted is None:
                journal.write_record("summary", **report.to_json())
            else:
                by = "SIGTERM" if isinstance(interrupted, Terminated) else "SIGINT"
                journal.write_raw("interrupted", signal=by)
            journal.close()
    faults = getattr(world, "faults_injected", None)
    robot_info = robot.info() if robot is not None else None
    if robot_info is not None:
        faults = robot_info.get("faults_injected")
    if args.json:
        data: dict[str, Any] = {
            "target": target.name,
            "problem": target.problem_path.name,
            "seed": args.seed,
            "fail_rate": fail_rate,
            "planner": planner.name,
            **report.to_json(),
        }
        if timeline.temporal:
            data["makespan_planned"] = timeline.makespan_planned
            executed = timeline.makespan_executed
            data["makespan_executed"] = None if executed is None else round(executed, 4)
        if faults is not None:
            data["faults_injected"] = faults
        if hasattr(world, "sim_time"):
            data["sim_time_s"] = round(float(world.sim_time), 3)
        if robot is not None:
            data["ros"] = {
                "prefix": robot.prefix,
                "robot": "started" if robot.start_robot else "connected",
                "robot_info": robot_info,
            }
            if robot_info is not None:
                data["sim_time_s"] = robot_info.get("sim_time")
        print(json.dumps(data, indent=None))
    if not args.quiet:
        print(_summary(outcome, report, faults), file=out, flush=True)
    if viewer is not None and resources is not None:
        # The mission is over, the page is not: keep it for whoever is looking.
        print(
            f"viewer: {viewer.url} - the mission ended; still serving it, Ctrl-C to stop",
            file=sys.stderr,
            flush=True,
        )
        with contextlib.suppress(KeyboardInterrupt):
            viewer.wait()
    return EXIT_OK if report.goal_reached else EXIT_FAILED


def _summary(outcome: str | None, report: Any, faults: int | None) -> str:
    fault_text = f", {faults} faults injected" if faults is not None else ""
    return (
        f"summary: {outcome}{' (goal reached)' if report.goal_reached else ' (goal NOT reached)'}; "
        f"{report.actions_executed} actions ({report.actions_failed} failed){fault_text}; "
        f"{report.retries} retries, {report.variants_tried} skill variants, "
        f"{report.continues} continues, "
        f"{report.repairs} repairs ({report.repair_attempts} tried), "
        f"{report.replans} replans ({report.holds} held the plan); "
        f"{report.planner_calls} planner calls, {report.plans_reused} plans reused, "
        f"planning {report.planning_time_s:.2f} s, execution {report.execution_time_s:.2f} s, "
        f"total {report.total_time_s:.2f} s"
        + (f"\n  reason: {report.explanation}" if not report.goal_reached else "")
    )


class ProgressPrinter:
    """Prints one line per step, per plan and per recovery; ``verbose``: also the
    states each step enters and every decision of the executive."""

    #: Decisions printed only with ``verbose``: what was considered and not done.
    CONSIDERED = frozenset({"repair-skipped", "repair-rejected"})

    def __init__(self, stream: TextIO, *, verbose: bool = False) -> None:
        self.stream = stream
        self.verbose = verbose
        self.total = 0

    def __call__(self, event: Event) -> None:
        from plan_bridge.execution.events import ExecutiveDecision, PlanComputed, StepFinished
        from smach.introspection.events import StateEntered

        write = self.stream.write
        if isinstance(event, PlanComputed):
            # A replan's reason is on its [replan] line already.
            reason = event.reason if event.reason == "initial plan" or self.verbose else "new plan"
            if event.status == "solved":
                self.total = len(event.steps)
                write(
                    f"[plan] {reason}: {len(event.steps)} steps "
                    f"({event.planner}, {event.planning_time_s:.2f} s)\n"
                )
            else:
                write(f"[plan] {reason}: {event.status}: {event.explanation}\n")
        elif isinstance(event, ExecutiveDecision):
            if not self.verbose and event.decision in self.CONSIDERED:
                return
            write(f"[{event.decision}] {event.reason}\n")
        elif isinstance(event, StepFinished):
            write(
                f"  step {event.index}: {event.action} -> {event.outcome}"
                f"{'' if event.outcome == event.skill_outcome or not event.skill_outcome else f' (skill: {event.skill_outcome})'}"
                f" [{event.duration_s * 1000:.0f} ms]\n"
            )
        elif self.verbose and isinstance(event, StateEntered) and "/SKILL/" in event.path:
            write(f"    {event.path}\n")
        else:
            return
        self.stream.flush()


def _configure_check(parser: argparse.ArgumentParser) -> None:
    add_input_arguments(parser)


def _check(args: argparse.Namespace) -> int:
    from plan_bridge.errors import PlanBridgeError
    from plan_bridge.missions.mission import load_target

    try:
        chosen = resolve_input(args, every_problem=True)
    except InputError as exc:
        return fail(str(exc))
    single = len(chosen.problems) == 1
    problems_found: list[str] = []
    name = ""
    for problem in chosen.problems:
        try:
            warnings = check_input(chosen.domain, problem)
            loaded = load_target(args.target, problem)
            setup = loaded.setup(seed=0, fail_rate=0.0)
        except PlanBridgeError as exc:
            if single:
                # One problem: the same message and exit code as `plan` and `run`.
                return fail(str(exc))
            problems_found.append(str(exc))
            continue
        name = loaded.name
        for warning in warnings:
            print(f"warning: {warning}", file=sys.stderr)
        for line in setup.skills.check(loaded.task):
            problems_found.append(f"{problem.name}: {line}")
        print(
            f"{problem.name}: {len(loaded.task.actions)} actions, {len(loaded.task.objects)} objects, "
            f"{len(loaded.task.goal_facts)} goal atoms",
            file=sys.stderr,
        )
        from plan_bridge.planning.engines import engines_for, problem_kind

        try:
            engines = engines_for(loaded.task)  # raises when no installed engine fits
        except PlanBridgeError as exc:
            return fail(f"{problem.name}: {exc}")
        print(
            f"{problem.name}: {problem_kind(loaded.task).name} problem, planned by "
            f"{' then '.join(engines)} (--planner auto)"
        )
    if problems_found:
        return fail(f"{len(problems_found)} problem(s):\n  " + "\n  ".join(problems_found))
    print(f"{name}: OK ({len(chosen.problems)} problem(s) checked)")
    return EXIT_OK


COMMANDS = (
    Command("run", "plan and execute a mission in the simulated world", _configure_run, _run),
    Command(
        "check",
        "validate PDDL (a folder, or DOMAIN PROBLEM), skill bindings and outcome mappings",
        _configure_check,
        _check,
    ),
)
