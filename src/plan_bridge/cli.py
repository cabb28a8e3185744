"""The ``plan-bridge`` command line.

Subcommands live in a registry (:data:`COMMANDS`): each is a :class:`Command`
with a function that adds its arguments and a function that runs it and returns
the exit code. A new subcommand (``run``, ``check``) is one more
``register(Command(...))`` call.

Exit codes: 0 success, 1 no plan / mission failed, 2 bad input (a one-paragraph
error on stderr, never a traceback). Progress goes to stderr, results to stdout.

This module imports nothing heavy at import time: ``plan-bridge --help`` must
answer in well under 0.3 s, and bad input must be reported before
unified-planning (~0.5 s to import) is even loaded.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, TextIO

__all__ = ["COMMANDS", "Command", "main", "register"]

EXIT_OK = 0
EXIT_FAILED = 1
EXIT_BAD_INPUT = 2
EXIT_INTERNAL = 3


@dataclass(frozen=True)
class Command:
    """A subcommand: ``configure`` adds its arguments, ``run`` returns the exit code."""

    name: str
    help: str
    configure: Callable[[argparse.ArgumentParser], None]
    run: Callable[[argparse.Namespace], int]
    description: str = ""


COMMANDS: dict[str, Command] = {}


def register(command: Command) -> Command:
    """Add a subcommand to ``plan-bridge`` (replacing one of the same name)."""
    COMMANDS[command.name] = command
    return command


def build_parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The ``plan-bridge`` parser.

    With ``argv``, only the subcommand it names gets its arguments (configuring
    ``view`` imports smach): ``plan-bridge --help`` then lists the subcommands
    without importing any of them. Without ``argv``, every subcommand is configured.
    """
    named = None if argv is None else next((a for a in argv if not a.startswith("-")), "")
    # Subcommands live in their own modules, which register them on import.
    from plan_bridge import mission_commands, study, view_command  # noqa: F401

    # argparse exits with 2 on usage errors, which is our "bad input" code.
    parser = argparse.ArgumentParser(
        prog="plan-bridge",
        description="Plan PDDL goals with unified-planning engines and run the plans as "
        "SMACH state machines.",
        epilog="exit codes: 0 success, 1 no plan / failure, 2 bad input",
    )
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for command in COMMANDS.values():
        sub = subparsers.add_parser(
            command.name,
            help=command.help,
            description=command.description or command.help,
        )
        if named is None or named == command.name:
            command.configure(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``plan-bridge`` console script."""
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(argv)
    args = parser.parse_args(argv)
    command = COMMANDS[args.command]
    try:
        return command.run(args)
    except KeyboardInterrupt:
        print("plan-bridge: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:
        # A bug of ours or of a domain's code: say what and where, not a traceback
        # (set PLAN_BRIDGE_DEBUG=1 to get one).
        if os.environ.get("PLAN_BRIDGE_DEBUG"):
            raise
        origin = exc.__traceback__
        while origin is not None and origin.tb_next is not None:
            origin = origin.tb_next
        where = (
            f" at {origin.tb_frame.f_code.co_filename}:{origin.tb_lineno}"
            if origin is not None
            else ""
        )
        print(
            f"plan-bridge: internal error: {type(exc).__name__}: {exc}{where}\n"
            f"  (this is a bug; PLAN_BRIDGE_DEBUG=1 shows the traceback)",
            file=sys.stderr,
        )
        return EXIT_INTERNAL


def progress(message: str, stream: TextIO | None = None) -> None:
    """A progress line on stderr (stdout is reserved for results)."""
    print(message, file=stream or sys.stderr, flush=True)


def fail(message: str, code: int = EXIT_BAD_INPUT) -> int:
    print(f"plan-bridge: error: {message}", file=sys.stderr, flush=True)
    return code


def bounded(
    kind: Callable[[str], float], low: float, high: float, what: str, *, open_low: bool = False
) -> Callable[[str], Any]:
    """An argparse type: ``kind(text)`` within [low, high] (or (low, high]), named ``what``."""

    def parse(text: str) -> Any:
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}") from None
        # `not (...)` also refuses NaN.
        if not ((low < value) if open_low else (low <= value)) or not value <= high:
            raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}")
        return value

    return parse


positive_seconds = bounded(
    float, 0.0, sys.float_info.max, "a positive number of seconds", open_low=True
)


# -- plan ------------------------------------------------------------------------


def _configure_plan(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("domain", metavar="DOMAIN.pddl", help="PDDL domain file")
    parser.add_argument("problem", metavar="PROBLEM.pddl", help="PDDL problem file")
    parser.add_argument(
        "--planner",
        default="fast-downward",
        metavar="NAME",
        help="unified-planning engine: fast-downward (default), fast-downward-opt, "
        "pyperplan, pyperplan-opt or any installed one-shot planner",
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
    from plan_bridge.errors import PlanBridgeError
    from plan_bridge.source import check_source, read_source

    try:
        # Cheap checks first: bad input is reported before unified-planning loads.
        for path, kind in ((args.domain, "domain"), (args.problem, "problem")):
            check_source(read_source(path, kind))
    except PlanBridgeError as exc:
        return fail(str(exc))

    from plan_bridge.domain import load_task
    from plan_bridge.planning import PlanStatus, UPPlanner, get_planner
    from plan_bridge.worker import default_pool

    planners: list[UPPlanner] = []
    try:
        progress(f"loading {args.domain} and {args.problem}...")
        # A planner process parses the task while we parse it (prime); the planner
        # name is checked before our parse, so a wrong one is reported at once.
        task = load_task(
            args.domain,
            args.problem,
            prime=default_pool(),
            before_parse=lambda: planners.append(get_planner(args.planner)),
        )
    except PlanBridgeError as exc:
        return fail(str(exc))
    planner = planners[0]
    progress(f"planning with {planner.name} (timeout {args.timeout:g} s)...")
    try:
        result = planner.solve(task, timeout=args.timeout)
    except PlanBridgeError as exc:
        return fail(str(exc), EXIT_FAILED)

    if args.json:
        payload = result.to_json()
        payload["domain"] = str(args.domain)
        payload["problem"] = str(args.problem)
        print(json.dumps(payload, indent=None))
    else:
        for warning in result.warnings:
            progress(f"warning: {warning}")
        if result.solved:
            width = len(str(len(result.actions)))
            for number, step in enumerate(result.actions, start=1):
                print(f"{number:>{width}}. {step}")
            print(
                f"solved: {len(result.actions)} actions in {result.planning_time_s:.2f} s "
                f"with {result.planner}"
            )
        else:
            print(
                f"{result.status.value}: no plan after {result.planning_time_s:.2f} s with "
                f"{result.planner}: {result.explanation}"
            )
    return EXIT_OK if result.status is PlanStatus.SOLVED else EXIT_FAILED


register(
    Command(
        name="plan",
        help="plan a PDDL problem and print the plan",
        description="Plan DOMAIN.pddl + PROBLEM.pddl with a unified-planning engine under a "
        "hard time limit and print the plan (exit 0), or why there is none (exit 1).",
        configure=_configure_plan,
        run=_run_plan,
    )
)


if __name__ == "__main__":
    # Run as a script, this file is __main__, not plan_bridge.cli, where the commands
    # register themselves: hand over to the real module.
    from plan_bridge.cli import main as _main

    sys.exit(_main())
