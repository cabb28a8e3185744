"""What every ``plan-bridge`` subcommand module shares: :class:`Command`, exit codes,
error and progress output, argparse value types.

A subcommand module defines ``COMMANDS = (Command(...), ...)`` and imports only this
module; the table of subcommands is in :mod:`plan_bridge.cli` (nothing here imports
it back). Exit codes: 0 success, 1 no plan / mission failed, 2 bad input (a
one-paragraph error on stderr, never a traceback), 3 internal error. Progress goes to
stderr, results to stdout. Nothing heavy is imported here.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, TextIO

__all__ = [
    "EXIT_BAD_INPUT",
    "EXIT_FAILED",
    "EXIT_INTERNAL",
    "EXIT_OK",
    "Command",
    "bounded",
    "fail",
    "positive_seconds",
    "progress",
]

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
