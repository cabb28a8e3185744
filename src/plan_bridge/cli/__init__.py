"""The ``plan-bridge`` command line: the table of subcommands and :func:`main`.

Each subcommand module (:mod:`~plan_bridge.cli.check` ... ) defines
``COMMANDS = (Command(...), ...)`` and imports only :mod:`plan_bridge.cli.base`;
this module is the one place that lists them (:data:`MODULES`), so nothing imports
the CLI back. Subcommand modules import nothing heavy at import time:
``plan-bridge --help`` answers in well under 0.3 s, and bad input is reported before
unified-planning (~0.5 s to import) is even loaded.
"""

from __future__ import annotations

import argparse
import importlib
import os
import signal
import sys
import threading
from collections.abc import Iterator, Sequence
from contextlib import contextmanager, suppress
from types import FrameType

from plan_bridge.cli.base import EXIT_BAD_INPUT, EXIT_INTERNAL, Command, Terminated
from smach.exceptions import MissingExtraError

__all__ = ["MODULES", "Terminated", "build_parser", "commands", "main"]

#: The subcommand modules, in the order ``plan-bridge --help`` lists their commands.
MODULES = (
    "plan_bridge.cli.run",
    "plan_bridge.cli.check",
    "plan_bridge.cli.control",
    "plan_bridge.cli.plan",
    "plan_bridge.cli.problem",
    "plan_bridge.cli.import_plansys2",
    "plan_bridge.cli.skills",
    "plan_bridge.cli.view",
    "plan_bridge.cli.study",
)


def commands() -> dict[str, Command]:
    """Every subcommand by name (importing the modules of :data:`MODULES`)."""
    table: dict[str, Command] = {}
    for module in MODULES:
        for command in importlib.import_module(module).COMMANDS:
            table[command.name] = command
    return table


def build_parser(
    argv: Sequence[str] | None = None, table: dict[str, Command] | None = None
) -> argparse.ArgumentParser:
    """The ``plan-bridge`` parser.

    With ``argv``, only the subcommand it names gets its arguments (configuring
    ``view`` imports smach): ``plan-bridge --help`` then lists the subcommands
    without configuring any of them. Without ``argv``, every subcommand is configured.
    """
    named = None if argv is None else next((a for a in argv if not a.startswith("-")), "")
    # argparse exits with 2 on usage errors, which is our "bad input" code.
    parser = argparse.ArgumentParser(
        prog="plan-bridge",
        description="Plan PDDL goals with unified-planning engines and run the plans as "
        "SMACH state machines.",
        epilog="exit codes: 0 success, 1 no plan / failure, 2 bad input",
    )
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for command in (table or commands()).values():
        sub = subparsers.add_parser(
            command.name,
            help=command.help,
            description=command.description or command.help,
        )
        if named is None or named == command.name:
            command.configure(sub)
    return parser


def _terminate(signum: int, frame: FrameType | None) -> None:
    raise Terminated(f"signal {signum}")


@contextmanager
def _sigterm_as_interrupt() -> Iterator[None]:
    """Within the block, SIGTERM (``kill``, systemd, a container stop) raises
    :class:`Terminated` in the main thread instead of killing the process outright."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, _terminate)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _exit_interrupted(signum: int, frame: FrameType | None) -> None:
    for stream in (sys.stdout, sys.stderr):
        with suppress(OSError, ValueError):
            stream.flush()
    os._exit(130)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``plan-bridge`` console script."""
    if argv is None:
        # The process's entry point. Once the command is done, the process shuts down
        # (the planner workers stop, at exit): a Ctrl-C then ends it at once and
        # quietly, with the status of an interrupt, not with a traceback.
        try:
            return main(sys.argv[1:])
        finally:
            if threading.current_thread() is threading.main_thread():
                signal.signal(signal.SIGINT, _exit_interrupted)
    argv = list(argv)
    table = commands()
    args = build_parser(argv, table).parse_args(argv)
    try:
        with _sigterm_as_interrupt():
            return table[args.command].run(args)
    except Terminated:
        print("plan-bridge: terminated", file=sys.stderr)
        return 128 + signal.SIGTERM
    except KeyboardInterrupt:
        print("plan-bridge: interrupted", file=sys.stderr)
        return 130
    except MissingExtraError as exc:  # e.g. --ros without the ros extra
        print(f"plan-bridge: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
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
