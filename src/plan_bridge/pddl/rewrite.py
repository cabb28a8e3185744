"""PDDL text rewritten for the unified-planning 1.3 reader, with a map back to positions.

UP 1.3's grammar rejects valid PDDL that real files contain: empty sections
(``(:functions)``, ``(:constants)``), sections in another order than its own, a
problem without ``(:init ...)``, an object named like a type, ``?duration`` in a
durative action's effect. :func:`rewrite` produces an equivalent text UP accepts,
and a :class:`Rewritten` that maps every offset of it back to the original text,
so an error UP reports in the rewritten text is shown at the user's line and column.
"""

from __future__ import annotations

import bisect
from collections.abc import Sequence
from dataclasses import dataclass, field

from plan_bridge.pddl.sexpr import Form

__all__ = ["DOMAIN_ORDER", "PROBLEM_ORDER", "Edit", "Rewritten", "rewrite"]

#: The section order of UP 1.3's grammar (actions of both kinds may interleave).
DOMAIN_ORDER = {
    ":requirements": 0,
    ":types": 1,
    ":constants": 2,
    ":predicates": 3,
    ":functions": 4,
    ":task": 5,
    ":method": 6,
    ":action": 7,
    ":durative-action": 7,
    ":process": 8,
    ":event": 9,
}
PROBLEM_ORDER = {
    ":domain": 0,
    ":requirements": 1,
    ":objects": 2,
    ":htn": 3,
    ":init": 4,
    ":goal": 5,
    ":constraints": 6,
    ":metric": 7,
}


@dataclass(frozen=True)
class Edit:
    """Replace ``text[start:end]`` by ``replacement``."""

    start: int
    end: int
    replacement: str


@dataclass
class Rewritten:
    """A rewritten text and, per piece, where it came from in the original."""

    text: str
    starts: list[int] = field(default_factory=list)
    """Start offset of each piece in :attr:`text`."""
    origins: list[tuple[int, bool]] = field(default_factory=list)
    """(original offset, copied) of each piece; inserted text maps to its anchor."""

    @property
    def changed(self) -> bool:
        return len(self.starts) != 1 or self.origins[0] != (0, True)

    def original_offset(self, offset: int) -> int:
        if not self.starts:
            return offset
        index = max(0, bisect.bisect_right(self.starts, offset) - 1)
        origin, copied = self.origins[index]
        return origin + (offset - self.starts[index]) if copied else origin


class _Builder:
    def __init__(self, original: str, edits: Sequence[Edit]) -> None:
        self.original = original
        self.edits = sorted(edits, key=lambda e: e.start)
        self.parts: list[str] = []
        self.result = Rewritten("")
        self.length = 0

    def _piece(self, text: str, origin: int, copied: bool) -> None:
        if not text:
            return
        self.result.starts.append(self.length)
        self.result.origins.append((origin, copied))
        self.parts.append(text)
        self.length += len(text)

    def copy(self, start: int, end: int) -> None:
        position = start
        for edit in self.edits:
            if edit.start < max(start, position) or edit.end > end:
                continue  # outside this range, or inside an edit made already
            self._piece(self.original[position : edit.start], position, True)
            self._piece(edit.replacement, edit.start, False)
            position = edit.end
        self._piece(self.original[position:end], position, True)

    def insert(self, text: str, anchor: int) -> None:
        self._piece(text, anchor, False)

    def done(self) -> Rewritten:
        self.result.text = "".join(self.parts)
        return self.result


def rewrite(
    text: str,
    define: Form,
    sections: Sequence[Form],
    order: dict[str, int],
    edits: Sequence[Edit] = (),
    added: Sequence[tuple[str, str]] = (),
) -> Rewritten:
    """``text`` with ``edits`` applied, ``sections`` sorted into ``order`` and the
    ``added`` (keyword, text) sections inserted at their place (a missing ``(:init)``)."""
    entries: list[tuple[str, Form | str]] = [(s.head, s) for s in sections]
    entries += [(head, added_text) for head, added_text in added]
    ranked = sorted(entries, key=lambda e: order.get(e[0], len(order)))
    if not edits and not added and ranked == entries:
        return Rewritten(text, [0], [(0, True)])
    builder = _Builder(text, edits)
    if not sections:
        builder.copy(0, define.end - 1)
        for _, added_text in added:
            builder.insert(" " + added_text, define.end - 1)
        builder.copy(define.end - 1, len(text))
        return builder.done()
    first = sections[0].offset
    builder.copy(0, first)
    if ranked == entries:
        builder.copy(first, sections[-1].end)
    else:
        for _, entry in ranked:
            if isinstance(entry, Form):
                builder.copy(entry.offset, entry.end)
                builder.insert("\n", entry.end)
            else:
                builder.insert(entry + "\n", first)
    builder.copy(sections[-1].end, len(text))
    return builder.done()
