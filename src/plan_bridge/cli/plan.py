"""The ``plan`` subcommand of ``plan-bridge``: plan a domain folder, or DOMAIN + PROBLEM,
and print the plan."""

from __future__ import annotations

import argparse
import json
from typing import TYPE_CHECKING

from plan_bridge.cli.base import (
    EXIT_FAILED,
    EXIT_OK,
    Command,
    InputError,
    PddlInput,
    add_input_arguments,
    check_input,
    fail,
    positive_seconds,
    progress,
    resolve_input,
)

if TYPE_CHECKING:
    from plan_bridge.pddl.task import PlanningTask
    from plan_bridge.planning.types import Planner, PlanResult

# -- plan ------------------------------------------------------------------------


def _configure_plan(parser: argparse.ArgumentParser) -> None:
    add_input_arguments(parser)
    parser.add_argument(
        "--planner",
        default="auto",
        metavar="NAME",
        help="unified-planning engine: auto (default: Fast Downward for classical "
        "problems, Kairos or TAMER for temporal and numeric ones, the next engine when "
        "one fails), fast-downward, fast-downward-opt, pyperplan, kairos, tamer or any "
        "installed one-shot planner",
    )
    parser.add_argument(
        "--timeout",
        type=positive_seconds,
        default=60.0,
        metavar="S",
        help="hard wall-clock limit for the planner in seconds (default 60)",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")


def _run_plan(args: argparse.Namespace) -> int:
    from plan_bridge.errors import PddlError, PlanBridgeError

    try:
        # The front end first (no unified-planning import): bad input is reported in
        # a fraction of a second, with the same verdict as `check` and `run`.
        chosen = resolve_input(args)
        domain, problem = chosen.domain, chosen.problems[0]
        goal = args.goal if chosen.world is None else None  # a world's goal: checked on load
        check_input(domain, problem, goal).show()
    except (InputError, PlanBridgeError) as exc:
        return fail(str(exc))

    from plan_bridge.planning.types import PlanStatus

    try:
        progress(f"loading {domain} and {problem}...")
        task, planner, goal = _load(args, chosen, goal)
        shown = _engines_shown(planner, task)
    except PlanBridgeError as exc:
        return fail(str(exc))
    progress(f"planning with {shown} (timeout {args.timeout:g} s)...")
    try:
        result = planner.solve(task, timeout=args.timeout)
    except PddlError as exc:
        return fail(str(exc))  # bad input found by the planner process: still exit 2
    except PlanBridgeError as exc:
        return fail(str(exc), EXIT_FAILED)

    if args.json:
        payload = result.to_json()
        payload["domain"] = str(domain)
        payload["problem"] = str(problem)
        if args.goal is not None:
            payload["goal"] = goal or " ".join(args.goal.split())
        print(json.dumps(payload, indent=None))
    else:
        _print_result(result)
    return EXIT_OK if result.status is PlanStatus.SOLVED else EXIT_FAILED


def _load(
    args: argparse.Namespace, chosen: PddlInput, goal: str | None
) -> tuple[PlanningTask, Planner, str | None]:
    """The task, the planner and the goal given at run time (on one line, comments
    blanked: as `run` shows it)."""
    from plan_bridge.pddl.task import load_task
    from plan_bridge.planning.planner import get_planner
    from plan_bridge.planning.worker import default_pool

    domain, problem = chosen.domain, chosen.problems[0]
    planners: list[Planner] = []

    # A planner process parses the task while we parse it (prime); the planner
    # name is checked before our parse, so a wrong one is reported at once.
    def choose() -> None:
        planners.append(get_planner(args.planner))

    if chosen.world is not None:  # a pyrobosim world: the task of its map, as run plans it
        from plan_bridge.missions.mission import load_target

        target = load_target(
            args.target, problem, goal=args.goal, prime=default_pool(), before_parse=choose
        )
        task, planners[0] = target.task, target.planner_for(planners[0])
    elif goal is not None:  # the goal given at run time, in place of the problem's
        from plan_bridge.missions.given_goal import load_task_with_goal

        task, given = load_task_with_goal(
            domain, problem, goal, prime=default_pool(), before_parse=choose
        )
        goal = given.goal
    else:
        task = load_task(domain, problem, prime=default_pool(), before_parse=choose)
    return task, planners[0], goal


def _engines_shown(planner: Planner, task: PlanningTask) -> str:
    """The engine that plans first, with the others for ``auto``."""
    from plan_bridge.planning.engines import AutoPlanner, problem_kind

    if not isinstance(planner, AutoPlanner):
        return planner.name
    engines = planner.engines(task)
    shown = engines[0]
    if not problem_kind(task).classical:
        rest = f"; then {', '.join(engines[1:])} if it fails" if engines[1:] else ""
        shown += f" ({problem_kind(task).name} problem{rest})"
    return shown


def _print_result(result: PlanResult) -> None:
    for warning in result.warnings:
        progress(f"warning: {warning}")
    if not result.solved:
        print(
            f"{result.status.value}: no plan after {result.planning_time_s:.2f} s with "
            f"{result.planner}: {result.explanation}"
        )
        return
    width = len(str(len(result.actions)))
    for number, step in enumerate(result.actions, start=1):
        timing = (
            f"{step.start:>8.3f}: " if step.start is not None else ""
        )  # temporal plans: start time, then [duration]
        length = f" [{step.duration:g}]" if step.duration is not None else ""
        print(f"{number:>{width}}. {timing}{step}{length}")
    makespan = "" if result.makespan is None else f", makespan {result.makespan:g} s"
    print(
        f"solved: {len(result.actions)} actions in {result.planning_time_s:.2f} s "
        f"with {result.planner}{makespan}"
    )


COMMANDS = (
    Command(
        name="plan",
        help="plan a PDDL problem and print the plan",
        description="Plan a domain folder (FOLDER [--problem P]) or DOMAIN.pddl PROBLEM.pddl "
        "with a unified-planning engine under a hard time limit and print the plan (exit 0), "
        "or why there is none (exit 1). Bad input: exit 2.",
        configure=_configure_plan,
        run=_run_plan,
    ),
)
