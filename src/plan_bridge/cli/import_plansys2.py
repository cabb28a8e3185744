"""The ``import`` subcommand of ``plan-bridge``: a PDDL problem from a PlanSys2 terminal
``commands`` file.

``plan-bridge import plansys2 COMMANDS_FILE --domain DOMAIN.pddl [-o PROBLEM.pddl]``
reads the commands PlanSys2's terminal takes, one per line, into a
:class:`~plan_bridge.pddl.knowledge.KnowledgeBase` of the domain and writes its
problem (to stdout without ``-o``)::

    # comments start with '#' (or ';'), anywhere on a line; blank lines are skipped
    set instance leia robot
    set predicate (robot_at leia kitchen)
    set function (= (battery leia) 100)
    set goal (and (robot_at leia bathroom))
    remove predicate (robot_at leia kitchen)
    remove function (battery leia)
    remove instance leia          # as PlanSys2: its facts, values and goal atoms go too
    remove goal                   # the empty goal
    quit                          # the rest of the file is not read

``set goal`` replaces the goal, as PlanSys2's does. A predicate may be written
without parentheses (``set predicate battery_low leia``, as in some PlanSys2 files).
The terminal's ``get``, ``run`` and ``check`` commands have no problem to build: they
are skipped with a warning. Every change is checked against the domain; the first
line that does not fit ends the import with ``COMMANDS_FILE:LINE: what is wrong, what
is allowed`` and exit status 2.
"""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from plan_bridge.cli.base import EXIT_OK, Command, fail, progress

if TYPE_CHECKING:
    from plan_bridge.pddl.knowledge import KnowledgeBase

__all__ = ["COMMANDS", "apply_command"]

#: The largest commands file read (bytes).
MAX_BYTES = 5_000_000
_IGNORED = ("get", "run", "check", "help")
_COMMANDS = (
    "set instance NAME TYPE, set predicate (ATOM), set function (= (ATOM) NUMBER), "
    "set goal (and (ATOM) ...), remove instance NAME, remove predicate (ATOM), remove "
    "function (ATOM), remove goal, quit (get, run and check are skipped)"
)


class CommandError(ValueError):
    """A command line that cannot be carried out (the message says what is allowed)."""


def apply_command(knowledge: KnowledgeBase, line: str, *, source: str = "api") -> str | None:
    """Carry out one line of a PlanSys2 commands file on ``knowledge``.

    Returns ``"quit"`` at the end of the commands, a warning for a skipped command,
    else None. Raises :class:`CommandError` for a line that is not a command and
    :class:`~plan_bridge.pddl.knowledge.KnowledgeError` for a change the knowledge base
    refuses (both ValueErrors).
    """
    text = re.split(r"[#;]", line, maxsplit=1)[0].strip()
    if not text:
        return None
    words = text.split()
    verb, what = words[0].lower(), words[1].lower() if len(words) > 1 else ""
    rest = text.split(None, 2)[2] if len(words) > 2 else ""
    if verb in ("quit", "exit") and len(words) == 1:
        return "quit"
    if verb in _IGNORED:
        return f"'{text}' skipped: the import builds the problem only"
    change = _CHANGES.get(what)
    if verb not in ("set", "remove") or change is None:
        raise CommandError(f"unknown command {text!r}; commands: {_COMMANDS}")
    change(knowledge, _Line(text, verb == "set", rest, source))
    return None


@dataclass(frozen=True)
class _Line:
    """A ``set ...`` or ``remove ...`` command: the text, which of the two, what follows
    ``set WHAT`` and where the line is (for the knowledge base's record)."""

    text: str
    is_set: bool
    rest: str
    source: str


def _instance(knowledge: KnowledgeBase, line: _Line) -> None:
    names = line.rest.split()
    if line.is_set and len(names) == 3 and names[1] == "-":
        names = [names[0], names[2]]
    if len(names) != (2 if line.is_set else 1):
        usage = "set instance NAME TYPE" if line.is_set else "remove instance NAME"
        raise CommandError(
            f"{line.text!r}: expected {usage}, e.g. {usage.replace('NAME', 'leia').replace('TYPE', 'robot')}"
        )
    if line.is_set:
        knowledge.add_instance(names[0], names[1], source=line.source)
    else:
        knowledge.remove_instance(names[0], cascade=True, source=line.source)


def _predicate(knowledge: KnowledgeBase, line: _Line) -> None:
    from plan_bridge.pddl.knowledge import goal_atoms

    rest = line.rest
    if not rest:
        verb = "set" if line.is_set else "remove"
        raise CommandError(
            f"{line.text!r}: expected {verb} predicate (ATOM), e.g. (robot_at leia kitchen)"
        )
    atoms = goal_atoms(rest) if rest.startswith("(") else [tuple(rest.lower().split())]
    if line.is_set:
        knowledge.add_facts(atoms, source=line.source)
    else:
        knowledge.remove_facts(atoms, source=line.source)


def _function(knowledge: KnowledgeBase, line: _Line) -> None:
    from plan_bridge.pddl.knowledge import function_atom, value_assignments

    if line.is_set:
        knowledge.set_values(value_assignments(line.rest), source=line.source)
    else:
        knowledge.remove_value(function_atom(line.rest), source=line.source)


def _goal(knowledge: KnowledgeBase, line: _Line) -> None:
    if line.is_set:
        if not line.rest:
            raise CommandError(f"{line.text!r}: expected set goal (and (ATOM) ...)")
        knowledge.set_goal(line.rest, source=line.source)
    elif line.rest:
        knowledge.remove_goal(line.rest, source=line.source)
    else:
        knowledge.clear_goal(source=line.source)


#: What ``set WHAT`` and ``remove WHAT`` change.
_CHANGES: dict[str, Callable[[KnowledgeBase, _Line], None]] = {
    "instance": _instance,
    "predicate": _predicate,
    "function": _function,
    "goal": _goal,
}


def _configure(parser: argparse.ArgumentParser) -> None:
    systems = parser.add_subparsers(dest="system", metavar="SYSTEM", required=True)
    plansys2 = systems.add_parser(
        "plansys2",
        help="a PlanSys2 terminal commands file",
        description="Read a PlanSys2 terminal commands file (set instance/predicate/function/"
        "goal, remove ..., comments after '#') against DOMAIN and write the PDDL problem. "
        "Bad input: exit 2 with FILE:LINE: what is wrong, what is allowed.",
    )
    plansys2.add_argument("commands", metavar="COMMANDS_FILE", help="the commands file")
    plansys2.add_argument(
        "--domain", required=True, metavar="DOMAIN.pddl", help="the PDDL domain of the problem"
    )
    plansys2.add_argument(
        "-o", "--output", metavar="PROBLEM.pddl", help="write the problem here (default: stdout)"
    )
    plansys2.add_argument(
        "--name",
        metavar="NAME",
        help="the problem's name (default: the commands file's name, else 'problem')",
    )


def _run(args: argparse.Namespace) -> int:
    from plan_bridge.errors import PlanBridgeError
    from plan_bridge.pddl.knowledge import KnowledgeBase

    path = Path(args.commands)
    try:
        if path.stat().st_size > MAX_BYTES:
            return fail(f"{path}: larger than {MAX_BYTES} bytes; is it a commands file?")
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        return fail(f"{path}: cannot read the commands file: {exc}")
    name = args.name or _problem_name(path)
    try:
        knowledge = KnowledgeBase(args.domain, name=name)
    except PlanBridgeError as exc:  # the domain (a PddlError), or the name
        return fail(str(exc))
    for number, line in enumerate(lines, start=1):
        where = f"{path}:{number}"
        try:
            said = apply_command(knowledge, line, source=f"{path.name}:{number}")
        except ValueError as exc:
            return fail(f"{where}: {exc}")
        if said == "quit":
            break
        if said is not None:
            progress(f"{where}: warning: {said}")
    text = knowledge.problem_pddl(
        comment=f"imported from {path.name} by plan-bridge import plansys2"
    )
    if args.output is None:
        sys.stdout.write(text)
        return EXIT_OK
    try:
        Path(args.output).write_text(text, encoding="utf-8")
    except OSError as exc:
        return fail(f"{args.output}: cannot write the problem: {exc}")
    progress(
        f"plan-bridge import: wrote {args.output} ({len(knowledge.instances)} instances, "
        f"{len(knowledge.facts)} facts, {len(knowledge.values)} values, "
        f"{len(knowledge.goal)} goal atoms)"
    )
    return EXIT_OK


def _problem_name(path: Path) -> str:
    name = re.sub(r"[^a-z0-9_-]+", "-", path.stem.lower()).strip("-")
    return name if re.fullmatch(r"[a-z][a-z0-9_-]*", name) else "problem"


COMMANDS = (
    Command(
        name="import",
        help="write the PDDL problem of another planning system's files (plansys2)",
        description="Import a problem from another planning system: `plan-bridge import "
        "plansys2 COMMANDS_FILE --domain DOMAIN.pddl [-o PROBLEM.pddl]` reads a PlanSys2 "
        "terminal commands file. Bad input: exit 2.",
        configure=_configure,
        run=_run,
    ),
)
