"""PDDL text as a tree of positioned forms.

:func:`read_tree` turns the tokens of a :class:`~plan_bridge.pddl.source.SourceText`
(already checked for balanced parentheses and bounded nesting by
:func:`~plan_bridge.pddl.source.check_source`) into :class:`Form` and :class:`Atom`
nodes that know the character offset they start at, so every later check can say
``file:line:column``. The build is iterative (no recursion limit to hit) and linear
in the number of tokens.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import NamedTuple

from plan_bridge.pddl.source_text import SourceText, paused_gc

__all__ = ["Atom", "Form", "Node", "read_tree", "walk"]


class Atom(NamedTuple):
    """A word: a name, a ``?variable``, a ``:keyword`` or a number (lower case).

    A tuple, not a dataclass: a 10 MB problem has millions of them."""

    text: str
    offset: int

    @property
    def end(self) -> int:
        return self.offset + len(self.text)


@dataclass(slots=True)
class Form:
    """A parenthesised list; ``offset`` is that of its ``(``, ``end`` is after its ``)``."""

    offset: int
    end: int = -1
    items: list[Atom | Form] = field(default_factory=list)

    @property
    def head(self) -> str:
        """The text of the first item when it is an atom (``"and"``, ``":action"``), else ``""``."""
        if self.items and isinstance(self.items[0], Atom):
            return self.items[0].text
        return ""

    @property
    def is_empty(self) -> bool:
        return not self.items

    def atoms(self) -> list[Atom]:
        return [item for item in self.items if isinstance(item, Atom)]


Node = Atom | Form


def read_tree(source: SourceText) -> Form:
    """The top-level ``(define ...)`` form of ``source``."""
    with paused_gc():
        return _read_tree(source)


def _read_tree(source: SourceText) -> Form:
    stack: list[Form] = [Form(-1)]
    items = stack[-1].items
    for text, offset in source.tokens:
        if text == "(":
            form = Form(offset)
            items.append(form)
            stack.append(form)
            items = form.items
        elif text == ")":
            if len(stack) == 1:
                raise source.error("unbalanced parentheses: this ')' has no matching '('", offset)
            stack.pop().end = offset + 1
            items = stack[-1].items
        else:
            items.append(Atom(text, offset))
    if len(stack) != 1:
        raise source.error("unbalanced parentheses: a '(' is never closed", stack[-1].offset)
    top = stack[0].items
    if not top or not isinstance(top[0], Form):
        raise source.error(
            f"expected (define ({source.kind} NAME) ...)", top[0].offset if top else None
        )
    return top[0]


def walk(node: Node) -> Iterator[Node]:
    """Every node below ``node`` (itself included), depth first, without recursion."""
    pending: list[Node] = [node]
    while pending:
        current = pending.pop()
        yield current
        if isinstance(current, Form):
            pending.extend(reversed(current.items))
