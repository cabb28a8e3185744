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
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO

from plan_bridge.errors import Terminated

__all__ = [
    "EXIT_BAD_INPUT",
    "EXIT_FAILED",
    "EXIT_INTERNAL",
    "EXIT_OK",
    "Command",
    "Findings",
    "PddlInput",
    "Terminated",
    "add_input_arguments",
    "add_probe_argument",
    "bounded",
    "check_input",
    "fail",
    "positive_seconds",
    "progress",
    "resolve_input",
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


# -- the PDDL input every command takes ----------------------------------------------


def add_input_arguments(parser: argparse.ArgumentParser, *, optional: bool = False) -> None:
    """``TARGET [PROBLEM] [--problem P]``: a domain folder (its ``domain.pddl`` and
    ``problems/``), or a domain file and a problem file."""
    parser.add_argument(
        "target",
        metavar="TARGET",
        nargs="?" if optional else None,
        help="a domain folder (domain.pddl + problems/) or a domain .pddl file",
    )
    parser.add_argument(
        "problem_file",
        metavar="PROBLEM",
        nargs="?",
        help="the problem .pddl file (same as --problem)",
    )
    parser.add_argument(
        "--problem",
        metavar="FILE",
        help="problem file, or the name of one in the folder's problems/ (default: the "
        "folder's first); required with a domain .pddl",
    )
    parser.add_argument(
        "--goal",
        metavar="GOAL",
        help='the goal to plan for, in place of the problem\'s (e.g. "(visited wp1)": '
        "ROSPlan-style problems leave (:goal (and)) to be filled at run time); for a "
        "pyrobosim world (WORLD.yaml or a folder with world.yaml), in pyrobosim's "
        'vocabulary, e.g. "(At apple0 table0_tabletop)" (see docs/sim.md)',
    )


def add_probe_argument(parser: argparse.ArgumentParser) -> None:
    """``--probe [SECONDS]``: look for the ROS 2 servers of the skill map (``check``,
    ``skills``)."""
    parser.add_argument(
        "--probe",
        nargs="?",
        type=float,
        const=3.0,
        default=None,
        metavar="SECONDS",
        help="also check that the ROS 2 server of every ros_action, ros_service and ros_topic "
        "entry of skills.toml is up with the type the map names, waiting up to SECONDS "
        "(default 3) for them; exit 1 when one is not",
    )


class InputError(ValueError):
    """The command line names PDDL input that does not exist or does not fit together."""


@dataclass(frozen=True)
class PddlInput:
    """The files a command reads: the domain and its problem(s)."""

    domain: Path
    problems: tuple[Path, ...]
    folder: Path | None = None
    world: Path | None = None
    """A pyrobosim world file: ``problems`` are its goals' names (or the file itself)."""


def resolve_input(args: argparse.Namespace, *, every_problem: bool = False) -> PddlInput:
    """The domain and problem files named by ``args`` (see :func:`add_input_arguments`).

    Merges ``PROBLEM`` into ``args.problem``. ``every_problem``: without a problem,
    a folder gives all of its ``problems/*.pddl`` (``check``), else the first one.
    Raises :class:`InputError` with what was expected.
    """
    positional = getattr(args, "problem_file", None)
    if positional is not None:
        if args.problem is not None and args.problem != positional:
            raise InputError(
                f"two problems given ({positional} and --problem {args.problem}); give one"
            )
        args.problem = positional
    target = Path(args.target)
    world = _world_input(args, target, every_problem)
    if world is not None:
        return world
    # A goal given at run time is for one problem: the one `run` would plan.
    every_problem = every_problem and getattr(args, "goal", None) is None
    if not target.exists():
        if target.suffix == ".pddl" or args.problem is not None:
            raise InputError(f"{target}: domain file not found; expected a PDDL domain file")
        raise InputError(
            f"{target}: no such file or folder; expected a domain folder (with domain.pddl "
            "and problems/) or a domain .pddl file followed by a problem .pddl file"
        )
    if not target.is_dir():
        if args.problem is None:
            raise InputError(f"{target}: a domain file needs a problem file: {target} PROBLEM.pddl")
        return PddlInput(target, (Path(args.problem),))
    domain = target / "domain.pddl"
    if not domain.is_file():
        raise InputError(f"{target}: a domain folder must contain domain.pddl")
    listed = tuple(sorted((target / "problems").glob("*.pddl")))
    if args.problem is None:
        if not listed:
            raise InputError(f"{target}: no problems/*.pddl; give one with --problem")
        return PddlInput(domain, listed if every_problem else listed[:1], target)
    problem = Path(args.problem)
    if not problem.exists():
        for candidate in (target / "problems" / problem, target / "problems" / f"{problem}.pddl"):
            if candidate.is_file():
                problem = candidate
                break
        else:
            names = ", ".join(p.stem for p in listed)
            raise InputError(
                f"{problem}: no such problem; problems of {target.name}: {names or 'none'}"
            )
    return PddlInput(domain, (problem,), target)


def _world_input(args: argparse.Namespace, target: Path, every_problem: bool) -> PddlInput | None:
    """A pyrobosim world target (its goals are checked when it loads), else None."""
    from plan_bridge.robosim.target_files import read_goals, world_file_of

    world = world_file_of(target)
    if world is None:
        return None
    from plan_bridge.robosim.target_files import DOMAIN_PATH

    goals = tuple(Path(name) for name in read_goals(target)) if target.is_dir() else ()
    if getattr(args, "goal", None) is not None or not goals:
        return PddlInput(DOMAIN_PATH, (world,), world.parent, world)
    if args.problem is not None:
        return PddlInput(DOMAIN_PATH, (Path(args.problem),), target, world)
    return PddlInput(DOMAIN_PATH, goals if every_problem else goals[:1], target, world)


class Findings(list[str]):
    """The warnings of :func:`check_input`, and its ``notes`` (printed as ``note: ...``)."""

    def __init__(self, warnings: Iterable[str] = (), notes: Iterable[str] = ()) -> None:
        super().__init__(warnings)
        self.notes = list(notes)

    def show(self) -> None:
        """Print the warnings and notes on stderr, one ``warning: ...`` or ``note: ...``
        a line."""
        for warning in self:
            progress(f"warning: {warning}")
        for note in self.notes:
            progress(f"note: {note}")


def check_input(domain: Path, problem: Path, goal: str | None = None) -> Findings:
    """The front end's verdict on one domain and problem, the same for every command:
    raises :class:`~plan_bridge.errors.PddlError` (exit 2) for bad or unsupported
    input, including features whose engines are not installed; returns the warnings
    (and, as a note, the goal of the problem that ``goal`` replaces).
    Imports no unified-planning. A pyrobosim world's problem is generated (and checked)
    when the target loads: nothing to check here."""
    from plan_bridge.robosim.target_files import DOMAIN_PATH

    if domain == DOMAIN_PATH and problem.suffix != ".pddl":
        return Findings()
    from plan_bridge.pddl.front_end import analyse_files

    notes: list[str] = []
    if goal is None:
        front = analyse_files(domain, problem)
    else:
        from plan_bridge.missions.given_goal import analyse_with_goal

        front, given = analyse_with_goal(domain, problem, goal)
        note = given.note()
        if note is not None:
            notes.append(note)
    front.require_engines()
    # Printed as "warning: FILE:LINE:COL: ...": the word once, in front.
    return Findings([w.replace(": warning: ", ": ", 1) for w in front.warnings], notes)
