"""A PDDL problem's goal given at run time (``--goal``), as ROSPlan's knowledge base
fills one when a mission starts.

ROSPlan-style problems leave ``(:goal (and))`` to be filled at run time;
``plan-bridge run DOMAIN PROBLEM --goal "(visited wp1)"`` plans for the given goal
instead of the file's. :func:`problem_with_goal` writes the goal into the problem's
text (its ``(:goal ...)`` section replaced, or added when there is none) and checks
it against the domain and the problem's objects before anything else: an undeclared
predicate or object, a wrong number of arguments or a wrong type is an error at
``--goal:1:COLUMN`` naming what is declared. Several formulas are their conjunction:
``--goal "(visited wp1) (visited wp2)"``.

The problem's other lines keep their numbers (the goal is written on one line, then
as many line breaks as the replaced section had), so every other finding of the
front end is still at its place in the file. Nothing here imports unified-planning.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from plan_bridge.errors import PddlError
from plan_bridge.pddl.checks import Usage, check_problem
from plan_bridge.pddl.diagnostics import Diagnostics
from plan_bridge.pddl.model import read_domain, read_problem
from plan_bridge.pddl.source import (
    DEFAULT_MAX_BYTES,
    DEFAULT_MAX_DEPTH,
    SourceText,
    check_source,
    read_source,
)

if TYPE_CHECKING:
    from plan_bridge.pddl.front_end import FrontEnd
    from plan_bridge.pddl.task import PlanningTask, Primer

__all__ = [
    "GOAL_SOURCE",
    "GivenGoal",
    "analyse_with_goal",
    "load_task_with_goal",
    "problem_with_goal",
]

GOAL_SOURCE = "--goal"
"""The name errors in the given goal are reported under: ``--goal:1:7: ...``."""

_COMMENT = re.compile(r";.*")

_EXAMPLE = 'e.g. --goal "(visited wp1)" or --goal "(and (visited wp1) (visited wp2))"'


@dataclass(frozen=True)
class GivenGoal:
    """A problem with the goal given at run time."""

    source: SourceText
    """The problem's text with the given goal (named like the problem file)."""
    goal: str
    """The given goal, on one line."""
    replaced: str
    """The problem's own goal that the given one replaced, on one line; ``""`` when it
    was empty (``(:goal (and))``) or absent."""

    def note(self) -> str | None:
        """What to tell the user when a goal of the file was replaced, else None."""
        if not self.replaced:
            return None
        shown = self.replaced if len(self.replaced) <= 200 else self.replaced[:197] + "..."
        return f"--goal replaces the goal of {Path(self.source.path).name}: {shown}"


def problem_with_goal(domain: SourceText, problem: SourceText, goal: str) -> GivenGoal:
    """``problem`` with ``goal`` as its goal, the goal checked against ``domain`` and
    ``problem`` (both must have passed :func:`~plan_bridge.pddl.source.check_source`).

    Raises :class:`PddlError` at ``--goal:1:COLUMN`` for a goal that is not one or more
    formulas, or names what the domain or the problem does not declare.
    """
    # On one line, comments blanked (one would hide the rest of the line).
    one_line = " ".join(_COMMENT.sub(lambda m: " " * len(m[0]), row) for row in goal.splitlines())
    given = SourceText(one_line, GOAL_SOURCE, "problem")
    forms = _top_level_forms(given)
    body = one_line.strip() if forms == 1 else f"(and {one_line.strip()})"
    shift = 0 if forms == 1 else len("(and ")
    section = next(((s, e) for head, s, e in problem.sections() if head == ":goal"), None)
    if section is None:
        # No (:goal ...) at all: added before the problem's closing parenthesis.
        end = problem.tokens[-1].offset
        start, replaced, breaks = end, "", ""
        added = " (:goal "
    else:
        start, end = section
        old = problem.text[start:end]
        replaced = "" if _is_empty_goal(problem, start, end) else _one_line(problem, start, end)
        breaks = "\n" * old.count("\n")
        added = "(:goal "
    text = problem.text[:start] + added + body + ")" + breaks + problem.text[end:]
    source = SourceText(text, problem.path, "problem")
    # Offsets in the new problem's goal are those in the given text plus ``origin``.
    begin = start + len(added)
    origin = begin + shift - (len(one_line) - len(one_line.lstrip()))
    _check_goal(domain, source, given, origin, (begin, begin + len(body)))
    return GivenGoal(source, " ".join(one_line.split()), replaced)


def _top_level_forms(given: SourceText) -> int:
    """The number of formulas of the given goal; raises :class:`PddlError` unless it is
    one or more balanced ``(...)`` forms."""
    depth = 0
    forms = 0
    for token in given.tokens:
        if token.text == "(":
            forms += depth == 0
            depth += 1
        elif token.text == ")":
            if depth == 0:
                raise given.error(
                    "unbalanced parentheses: this ')' has no matching '('", token.offset, _EXAMPLE
                )
            depth -= 1
        elif depth == 0:
            raise given.error(
                f"expected a goal formula (...), found {token.text!r}", token.offset, _EXAMPLE
            )
    if depth:
        opened = [t.offset for t in given.tokens if t.text == "("]
        raise given.error("unbalanced parentheses: a '(' is never closed", opened[-1], _EXAMPLE)
    if not forms:
        raise given.error("the goal is empty", None, _EXAMPLE)
    return forms


def _is_empty_goal(problem: SourceText, start: int, end: int) -> bool:
    """Whether the section ``(:goal ...)`` at ``start`` holds nothing but ``(and)``s."""
    words = [t.text for t in problem.tokens if start < t.offset < end and t.text not in ("(", ")")]
    return all(word in (":goal", "and") for word in words)


def _one_line(problem: SourceText, start: int, end: int) -> str:
    """The text of a section, comments dropped, on one line."""
    tokens = [t for t in problem.tokens if start <= t.offset < end]
    return " ".join(t.text for t in tokens).replace("( ", "(").replace(" )", ")")


def _check_goal(
    domain: SourceText,
    problem: SourceText,
    given: SourceText,
    origin: int,
    span: tuple[int, int],
) -> None:
    """Raise the errors found in the given goal (at ``span`` of ``problem``), at their
    places in ``given``."""

    def inside(offset: int | None) -> bool:
        return offset is not None and span[0] <= offset < span[1]

    def moved(offset: int | None) -> int | None:
        if offset is None:
            return None
        return min(max(offset - origin, 0), max(len(given.text) - 1, 0))

    try:
        check_source(problem)
    except PddlError as exc:
        if exc.path != problem.path or exc.line is None:
            raise
        offset = problem.offset_of(exc.line, exc.column or 1)
        if not inside(offset):
            raise
        raise given.error(
            exc.explanation,
            moved(offset),
            exc.hint,
            feature=getattr(exc, "feature", None),
            supporting_engines=tuple(getattr(exc, "supporting_engines", ())),
        ) from None
    diags = Diagnostics()
    domain_model = read_domain(domain, diags)
    if diags.errors:
        return  # the domain's own errors: reported by the front end, at their places
    problem_model = read_problem(problem, diags)
    check_problem(domain_model, problem_model, diags, Usage())
    found = [
        dataclasses.replace(d, source=given, offset=moved(d.offset))
        for d in diags.errors
        if d.source is problem and inside(d.offset)
    ]
    Diagnostics(found).raise_errors()


def analyse_with_goal(
    domain: str | Path,
    problem: str | Path,
    goal: str,
    *,
    max_bytes: int = DEFAULT_MAX_BYTES,
    max_depth: int = DEFAULT_MAX_DEPTH,
) -> tuple[FrontEnd, GivenGoal]:
    """:func:`~plan_bridge.pddl.front_end.analyse_files` of the problem with ``goal``."""
    from plan_bridge.pddl.front_end import analyse

    domain_source, given = _read_with_goal(domain, problem, goal, max_bytes, max_depth)
    return analyse(domain_source, given.source), given


def load_task_with_goal(
    domain: str | Path,
    problem: str | Path,
    goal: str,
    *,
    prime: Primer | None = None,
    before_parse: Callable[[], object] | None = None,
) -> tuple[PlanningTask, GivenGoal]:
    """:func:`~plan_bridge.pddl.task.load_task` of the problem with ``goal``."""
    from plan_bridge.pddl.task import load_task_from_text

    domain_source, given = _read_with_goal(
        domain, problem, goal, DEFAULT_MAX_BYTES, DEFAULT_MAX_DEPTH
    )
    task = load_task_from_text(
        domain_source.text,
        given.source.text,
        domain_name=domain_source.path,
        problem_name=given.source.path,
        prime=prime,
        before_parse=before_parse,
    )
    return dataclasses.replace(task, domain_path=Path(domain), problem_path=Path(problem)), given


def _read_with_goal(
    domain: str | Path, problem: str | Path, goal: str, max_bytes: int, max_depth: int
) -> tuple[SourceText, GivenGoal]:
    domain_source = read_source(domain, "domain", max_bytes=max_bytes)
    check_source(domain_source, max_depth=max_depth)
    problem_source = read_source(problem, "problem", max_bytes=max_bytes)
    check_source(problem_source, max_depth=max_depth)
    return domain_source, problem_with_goal(domain_source, problem_source, goal)
