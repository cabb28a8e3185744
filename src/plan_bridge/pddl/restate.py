"""A problem's PDDL text with another initial state and goal, everything else kept.

Replanning and the planner workers restate a problem read from PDDL for the state the
belief holds now: :func:`replace_init` rewrites the ``(:init ...)`` (and the ``(:goal
...)``) of the very text that was read, so every name stays as it was; unified-planning's
writer would take seconds on large problems and rename what it does not like.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence

from plan_bridge.pddl.source import is_number
from plan_bridge.pddl.source_text import SourceText, Token

__all__ = ["replace_init"]


def replace_init(
    problem: SourceText,
    facts: Iterable[Sequence[str]],
    numbers: Mapping[tuple[str, ...], float] | None = None,
    goal: Iterable[Sequence[str]] | None = None,
) -> str:
    """The problem text with its ``(:init ...)`` boolean facts replaced by ``facts``.

    Numeric assignments (``(= (total-cost) 0)``) and timed initial literals are
    kept: replanning changes what is true, not the costs of actions; ``numbers``
    (atom -> value) replaces the assignments of those atoms, or adds them. ``goal``
    (atoms) replaces the ``(:goal ...)`` by their conjunction.
    """
    numbers = dict(numbers or {})
    text = problem.text
    edits: list[tuple[int, int, str]] = []
    found = False
    for head, start, end in problem.sections():
        if head == ":goal" and goal is not None:
            body = " ".join("(" + " ".join(atom) + ")" for atom in goal)
            edits.append((start, end, f"(:goal (and {body}))"))
        if head != ":init":
            continue
        found = True
        kept = _kept_init_forms(problem, start, end, numbers)
        assigned = [
            f"(= ({' '.join(atom)}) {_number_text(value)})" for atom, value in numbers.items()
        ]
        body = " ".join(["(" + " ".join(fact) + ")" for fact in facts] + kept + assigned)
        edits.append((start, end, f"(:init {body})"))
    if not found:
        raise problem.error("the problem has no (:init ...) section", None)
    for start, end, replacement in sorted(edits, reverse=True):
        text = text[:start] + replacement + text[end:]
    return text


def _kept_init_forms(
    problem: SourceText, start: int, end: int, numbers: Mapping[tuple[str, ...], float]
) -> list[str]:
    """The numeric assignments (those of ``numbers``' atoms aside) and timed initial
    literals of the ``(:init ...)`` section between ``start`` and ``end``."""
    kept: list[str] = []
    keep = False
    depth = 0
    form_start = 0
    atom: tuple[str, ...] = ()
    tokens = [t for t in problem.tokens if start < t.offset < end - 1]
    for index, token in enumerate(tokens):
        if token.text == "(":
            if depth == 0:
                form_start = token.offset
                nxt = tokens[index + 1].text if index + 1 < len(tokens) else ""
                after = tokens[index + 2].text if index + 2 < len(tokens) else ""
                keep = nxt == "=" or (nxt == "at" and is_number(after))
                atom = _assigned_atom(tokens, index) if nxt == "=" else ()
            depth += 1
        elif token.text == ")":
            depth -= 1
            if depth == 0 and keep and atom not in numbers:
                kept.append(problem.text[form_start : token.offset + 1])
    return kept


def _assigned_atom(tokens: Sequence[Token], index: int) -> tuple[str, ...]:
    """The atom of the assignment ``(= (f a b) v)`` whose ``(`` is ``tokens[index]``
    (lower case; ``()`` when it is not of that shape)."""
    if index + 3 >= len(tokens) or tokens[index + 2].text != "(":
        return ()
    words: list[str] = []
    for token in tokens[index + 3 :]:
        if token.text == ")":
            return tuple(words)
        if token.text == "(":
            return ()
        words.append(token.text.lower())
    return ()


def _number_text(value: float) -> str:
    return f"{round(float(value), 6):g}"
