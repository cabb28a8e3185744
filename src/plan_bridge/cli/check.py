"""The ``check`` subcommand of ``plan-bridge``: the front end's verdict, the skill
bindings and the engines that would plan, for every problem of a target, without
planning. Split from :mod:`~plan_bridge.cli.run`, whose input check it shares
(:func:`~plan_bridge.cli.base.check_input`). With ``--probe``, also whether the ROS 2
servers of the folder's skill map are up (exit 1 when one is not: the map is fine,
the robot is not ready)."""

from __future__ import annotations

import argparse
import sys

from plan_bridge.cli.base import (
    EXIT_FAILED,
    EXIT_OK,
    Command,
    InputError,
    add_input_arguments,
    add_probe_argument,
    check_input,
    fail,
    resolve_input,
)


def _configure_check(parser: argparse.ArgumentParser) -> None:
    add_input_arguments(parser)
    add_probe_argument(parser)


def _check(args: argparse.Namespace) -> int:
    from plan_bridge.errors import PlanBridgeError
    from plan_bridge.missions.mission import load_target

    try:
        chosen = resolve_input(args, every_problem=True)
    except InputError as exc:
        return fail(str(exc))
    single = len(chosen.problems) == 1
    problems_found: list[str] = []
    unready: list[str] = []
    name = ""
    for problem in chosen.problems:
        try:
            pddl_goal = args.goal if chosen.world is None else None  # a world's: checked on load
            warnings = check_input(chosen.domain, problem, pddl_goal)
            loaded = load_target(args.target, problem, goal=args.goal)
            setup = loaded.setup(seed=0, fail_rate=0.0)
        except PlanBridgeError as exc:
            if single:
                # One problem: the same message and exit code as `plan` and `run`.
                return fail(str(exc))
            problems_found.append(str(exc))
            continue
        name = loaded.name
        warnings.show()
        noted: list[str] = []
        for line in setup.skills.check(loaded.task, noted):
            problems_found.append(f"{problem.name}: {line}")
        for line in noted:
            print(f"warning: {problem.name}: {line}", file=sys.stderr)
        if args.probe is not None and problem == chosen.problems[-1]:
            from plan_bridge.skills.ros.probe import print_probe

            unready = print_probe(setup.extra.get("skill_map"), loaded.task, args.probe)
        print(
            f"{problem.name}: {len(loaded.task.actions)} actions, {len(loaded.task.objects)} objects, "
            f"{len(loaded.task.goal_facts)} goal atoms"
            + (" (given with --goal)" if loaded.given_goal is not None else ""),
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
    if unready:
        return fail(
            f"{len(unready)} ROS server(s) of the skill map not ready:\n  " + "\n  ".join(unready),
            EXIT_FAILED,
        )
    return EXIT_OK


COMMANDS = (
    Command(
        "check",
        "validate PDDL (a folder, or DOMAIN PROBLEM), skill bindings and outcome mappings",
        _configure_check,
        _check,
    ),
)
