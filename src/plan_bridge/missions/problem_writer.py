"""Write PDDL problems: the text of a problem, and the command line of a problem generator.

A domain's ``generate.py`` makes problems of any size from a seed. It computes the
objects, the initial facts and the goal, and this module writes them out::

    text = pddl_problem(
        "deliver-3", "delivery",
        objects=["r1 - robot", "office lab hall - room"],
        init=["(at r1 office)", *both_ways("office", "hall", "connected")],
        goal=["(at r1 lab)"],
        comment="3 rooms (generate.py --rooms 3 --seed 1)",
    )

The text is the same for the same arguments, byte for byte, so a generated problem
checked into ``problems/`` can be compared with a fresh one.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence

__all__ = ["both_ways", "generator_main", "pddl_problem"]


def both_ways(a: str, b: str, *predicates: str) -> list[str]:
    """The facts of symmetric relations between ``a`` and ``b``, both ways round.

    ``both_ways("hall", "lab", "connected", "clear")`` is ``["(connected hall lab)",
    "(connected lab hall)", "(clear hall lab)", "(clear lab hall)"]``. A predicate may
    carry leading arguments: ``both_ways("a", "b", "door-between d1")``.
    """
    return [fact for p in predicates for fact in (f"({p} {a} {b})", f"({p} {b} {a})")]


def pddl_problem(
    name: str,
    domain: str,
    *,
    objects: Sequence[str],
    init: Sequence[str],
    goal: Sequence[str],
    comment: str = "",
    compact: bool = False,
) -> str:
    """The PDDL text of a problem, ending with a newline.

    ``objects`` are the lines of the ``:objects`` section (``"pr2 - robot"``), ``init``
    and ``goal`` facts as PDDL text; the goal is their conjunction. ``comment`` becomes
    a ``;`` line at the top. The layout puts one object line and one fact per line;
    ``compact`` starts each section's first line after its keyword and writes the goal
    on one line.
    """
    head = [f"; {comment}"] if comment else []
    head += [f"(define (problem {name})", f"  (:domain {domain})"]
    if compact:
        lines = [
            *head,
            "  (:objects " + "\n            ".join(objects) + ")",
            "  (:init " + "\n         ".join(init) + ")",
            "  (:goal (and " + " ".join(goal) + ")))",
        ]
    else:
        declared = [f"    {line}" for line in objects]
        if declared:
            declared[-1] += ")"
        lines = [
            *head,
            "  (:objects" if declared else "  (:objects)",
            *declared,
            "  (:init",
            *(f"    {fact}" for fact in init),
            "  )",
            "  (:goal (and",
            *(f"    {fact}" for fact in goal),
            "  )))",
        ]
    return "\n".join(lines) + "\n"


def generator_main(
    parser: argparse.ArgumentParser,
    make: Callable[[argparse.Namespace], str],
    argv: Sequence[str] | None = None,
) -> int:
    """The ``main()`` of a problem generator: parse ``argv``, print ``make(args)``, return 0.

    A ``ValueError`` from ``make`` (arguments that make no problem) is reported as a
    usage error by ``parser`` (exit status 2).
    """
    args = parser.parse_args(argv)
    try:
        text = make(args)
    except ValueError as exc:
        parser.error(str(exc))
    sys.stdout.write(text)
    return 0
