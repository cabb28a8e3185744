"""Constructs unified-planning 1.3 cannot read, named before it tries.

Run by :func:`~plan_bridge.pddl.source.check_source` on the tokens: requirement
flags (unknown ones with a suggestion; derived predicates and object fluents as
unsupported features) and ``(either ...)`` types (with the common supertype to use
instead) and ``(:derived ...)`` sections. Split from :mod:`~plan_bridge.pddl.source`
to keep modules short.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable

from plan_bridge.errors import PddlError
from plan_bridge.pddl.features import ADL, classify, known, requirements_hint
from plan_bridge.pddl.source_text import SourceText

__all__ = ["UP_REQUIREMENTS", "check_constructs", "did_you_mean"]

#: Requirement flags accepted by the unified-planning 1.3 PDDL grammar.
UP_REQUIREMENTS = ADL | frozenset(
    [
        ":fluents",
        ":numeric-fluents",
        ":adl",
        ":durative-actions",
        ":duration-inequalities",
        ":timed-initial-literals",
        ":timed-initial-effects",
        ":action-costs",
        ":hierarchy",
        ":method-preconditions",
        ":constraints",
        ":contingent",
        ":preferences",
        ":time",
        ":continuous-effects",
    ]
)

#: Real PDDL requirements that unified-planning 1.3 cannot read.
_KNOWN_UNSUPPORTED_REQUIREMENTS = {
    ":derived-predicates": "derived predicates (axioms)",
    ":object-fluents": "object-valued fluents",
}


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    close = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.6)
    return f" (did you mean {close[0]}?)" if close else ""


def check_constructs(source: SourceText) -> None:
    tokens = source.tokens
    for index, token in enumerate(tokens[:-1]):
        if token.text != "(":
            continue
        head = tokens[index + 1].text
        if head == "either":
            raise _either_error(source, index)
        if head == ":requirements":
            _check_requirements(source, index + 2)
        elif head == ":derived":
            raise source.error(
                "unsupported PDDL construct `(:derived ...)` (derived predicates): the "
                "unified-planning 1.3 PDDL reader cannot read it",
                token.offset,
                hint="compile the axioms away (e.g. into actions) before loading",
                feature="derived-predicates",
            )


def _check_requirements(source: SourceText, index: int) -> None:
    tokens = source.tokens
    while index < len(tokens) and tokens[index].text != ")":
        flag = tokens[index]
        if flag.text in _KNOWN_UNSUPPORTED_REQUIREMENTS:
            raise source.error(
                f"unsupported PDDL requirement {flag.text} "
                f"({_KNOWN_UNSUPPORTED_REQUIREMENTS[flag.text]}): the unified-planning 1.3 "
                "PDDL reader cannot read it",
                flag.offset,
                hint=requirements_hint(),
                feature=flag.text,
            )
        if flag.text not in UP_REQUIREMENTS and classify(flag.text) is None:
            raise source.error(
                f"unknown PDDL requirement {flag.text!r}"
                + did_you_mean(flag.text, [s.name for s in known() if s.name[0] == ":"]),
                flag.offset,
                hint=requirements_hint(),
            )
        index += 1


def _either_error(source: SourceText, index: int) -> PddlError:
    tokens = source.tokens
    members: list[str] = []
    position = index + 2
    while position < len(tokens) and tokens[position].text != ")":
        members.append(tokens[position].text)
        position += 1
    where = source.section_at(tokens[index].offset) or "the domain"
    hint = (
        "unified-planning 1.3 accepts only single type names after '-'. "
        "Declare a common supertype and use it instead"
    )
    common = _common_supertype(source, members)
    if common:
        hint += f": here `{common}` is a supertype of {', '.join(members)}"
    hint += ". (Fast Downward's own translator accepts `either`, but plan_bridge reads PDDL "
    hint += "through unified-planning.)"
    return source.error(
        f"unsupported PDDL construct `(either {' '.join(members)})` (either-types: a union "
        f"of types) in {where}; the unified-planning 1.3 PDDL reader rejects it",
        tokens[index].offset,
        hint=hint,
        feature="either-types",
    )


def _common_supertype(source: SourceText, members: list[str]) -> str | None:
    """The most specific declared type that all ``members`` inherit from."""
    parents: dict[str, str] = {}
    for head, start, end in source.sections():
        if head != ":types":
            continue
        words = [t.text for t in source.tokens if start < t.offset < end and t.text not in "()"]
        pending: list[str] = []
        position = 1  # skip ':types'
        while position < len(words):
            word = words[position]
            if word == "-" and position + 1 < len(words):
                for name in pending:
                    parents[name] = words[position + 1]
                pending = []
                position += 2
                continue
            pending.append(word)
            position += 1
    if not members:
        return None

    def ancestors(name: str) -> list[str]:
        chain = [name]
        while chain[-1] in parents and parents[chain[-1]] not in chain:
            chain.append(parents[chain[-1]])
        return chain

    candidates = ancestors(members[0])
    for member in members[1:]:
        others = set(ancestors(member))
        candidates = [c for c in candidates if c in others]
    return candidates[0] if candidates else None
