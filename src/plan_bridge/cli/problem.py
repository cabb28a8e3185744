"""The ``problem`` subcommand of ``plan-bridge``: the PDDL problem generated from a
pyrobosim world and a goal (what ``run``, ``plan`` and ``check`` plan)."""

from __future__ import annotations

import argparse

from plan_bridge.cli.base import (
    EXIT_OK,
    Command,
    InputError,
    add_input_arguments,
    fail,
    resolve_input,
)


def _configure(parser: argparse.ArgumentParser) -> None:
    add_input_arguments(parser)


def _run(args: argparse.Namespace) -> int:
    from plan_bridge.errors import PlanBridgeError

    try:
        chosen = resolve_input(args)
    except InputError as exc:
        return fail(str(exc))
    if chosen.world is None:
        return fail(
            f"{args.target}: not a pyrobosim world; `plan-bridge problem` prints the problem "
            f"generated from WORLD.yaml (or a folder with world.yaml) and --goal; a PDDL "
            f"target's problem is its file ({chosen.problems[0]})"
        )
    from plan_bridge.missions.mission import load_target
    from plan_bridge.missions.world_target import WorldTarget

    try:
        target = load_target(args.target, chosen.problems[0], goal=args.goal)
    except PlanBridgeError as exc:
        return fail(str(exc))
    assert isinstance(target, WorldTarget)
    print(target.problem_text, end="")
    return EXIT_OK


COMMANDS = (
    Command(
        name="problem",
        help="print the PDDL problem generated from a pyrobosim world and a goal",
        description="Print the problem of the robosim domain (plan_bridge/robosim/domain.pddl) "
        "that a pyrobosim world (WORLD.yaml, or a folder with world.yaml) and a goal "
        '(--goal "(At apple0 table0_tabletop)", or a name of the folder\'s goals.yaml) give. '
        "Bad input: exit 2.",
        configure=_configure,
        run=_run,
    ),
)
