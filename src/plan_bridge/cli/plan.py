"""The ``plan`` subcommand of ``plan-bridge``: plan a domain folder, or DOMAIN + PROBLEM,
and print the plan."""

from __future__ import annotations

import argparse
import json

from plan_bridge.cli.base import (
    EXIT_FAILED,
    EXIT_OK,
    Command,
    InputError,
    add_input_arguments,
    check_input,
    fail,
    positive_seconds,
    progress,
    resolve_input,
)

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
        findings = check_input(domain, problem, goal)
        for warning in findings:
            progress(f"warning: {warning}")
        for note in findings.notes:
            progress(f"note: {note}")
    except (InputError, PlanBridgeError) as exc:
        return fail(str(exc))

    from plan_bridge.pddl.task import load_task
    from plan_bridge.planning.planner import Planner, PlanStatus, get_planner
    from plan_bridge.planning.worker import default_pool

    planners: list[Planner] = []
    try:
        progress(f"loading {domain} and {problem}...")
        # A planner process parses the task while we parse it (prime); the planner
        # name is checked before our parse, so a wrong one is reported at once.
        if chosen.world is not None:  # a pyrobosim world: the generated problem
            from plan_bridge.missions.mission import load_target

            task = load_target(
                args.target,
                problem,
                goal=args.goal,
                prime=default_pool(),
                before_parse=lambda: planners.append(get_planner(args.planner)),
            ).task
        elif goal is not None:  # the goal given at run time, in place of the problem's
            from plan_bridge.missions.given_goal import load_task_with_goal

            task, given = load_task_with_goal(
                domain,
                problem,
                goal,
                prime=default_pool(),
                before_parse=lambda: planners.append(get_planner(args.planner)),
            )
            goal = given.goal  # on one line, comments blanked: as `run` shows it
        else:
            task = load_task(
                domain,
                problem,
                prime=default_pool(),
                before_parse=lambda: planners.append(get_planner(args.planner)),
            )
    except PlanBridgeError as exc:
        return fail(str(exc))
    planner = planners[0]
    from plan_bridge.planning.engines import AutoPlanner, problem_kind

    shown = planner.name
    if isinstance(planner, AutoPlanner):
        try:
            engines = planner.engines(task)
        except PlanBridgeError as exc:
            return fail(str(exc))
        shown = engines[0]
        if not problem_kind(task).classical:
            rest = f"; then {', '.join(engines[1:])} if it fails" if engines[1:] else ""
            shown += f" ({problem_kind(task).name} problem{rest})"
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
        for warning in result.warnings:
            progress(f"warning: {warning}")
        if result.solved:
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
        else:
            print(
                f"{result.status.value}: no plan after {result.planning_time_s:.2f} s with "
                f"{result.planner}: {result.explanation}"
            )
    return EXIT_OK if result.status is PlanStatus.SOLVED else EXIT_FAILED


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
