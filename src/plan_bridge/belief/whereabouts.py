"""Where things are, and where they are not: the belief's knowledge of places.

A thing is at one place (``(at THING PLACE)``) or held (``(holding ROBOT THING)``).
When a robot looks at a place and a thing is not there, the belief learns that it is
not; when the thing was believed there, it is now **lost**: the belief has it nowhere
(closed world: not a guess) and says where it is not, with ``(absent THING PLACE)``
facts (:data:`ABSENT`). Seeing a thing somewhere puts it there and nowhere else, and
forgets where it was not. A search (:mod:`plan_bridge.maps.search`) looks for a lost
thing in the places it may be, minus those.

:func:`locate` turns a batch of observations into the batch the belief applies: it adds
what follows from "a thing is at one place" (seen at P: not at its old place, not
held, no longer absent anywhere) and the absences of the things the batch leaves lost.
The belief does this when it is made with ``whereabouts=True`` (worlds with a map).
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Sequence

from plan_bridge.belief.facts import Observation
from plan_bridge.pddl.task import Fact

__all__ = ["ABSENT", "absences", "locate", "lost", "places_of"]

ABSENT = "absent"
"""``(absent THING PLACE)``: the thing was looked for at the place and was not there."""


def places_of(facts: Iterable[Fact]) -> tuple[dict[str, set[str]], dict[str, str]]:
    """Thing -> the places the facts have it at, and thing -> the robot holding it."""
    at: dict[str, set[str]] = {}
    held: dict[str, str] = {}
    for fact in facts:
        if fact[0] == "at" and len(fact) == 3:
            at.setdefault(fact[1], set()).add(fact[2])
        elif fact[0] == "holding" and len(fact) == 3:
            held[fact[2]] = fact[1]
    return at, held


def lost(facts: Collection[Fact], things: Iterable[str]) -> list[str]:
    """Those of ``things`` the facts have neither at a place nor held."""
    at, held = places_of(facts)
    return [thing for thing in things if thing not in at and thing not in held]


def absences(facts: Iterable[Fact], thing: str) -> list[str]:
    """The places ``thing`` was looked for and not found, sorted."""
    return sorted(f[2] for f in facts if f[0] == ABSENT and len(f) == 3 and f[1] == thing)


def locate(facts: Collection[Fact], observations: Sequence[Observation]) -> list[Observation]:
    """``observations`` and what follows from them for where things are (see the
    module's doc), for a belief holding ``facts``."""
    at, held = places_of(facts)
    seen_at: dict[str, str] = {}
    seen_not: list[tuple[str, str]] = []
    for fact, truth in observations:
        if fact[0] == "at" and len(fact) == 3 and isinstance(truth, bool):
            if truth:
                seen_at[fact[1]] = fact[2]
            else:
                seen_not.append((fact[1], fact[2]))
    if not seen_at and not seen_not:
        return list(observations)
    given = {fact for fact, _ in observations}
    out = list(observations)
    for thing, place in seen_at.items():
        # At one place: not where it was believed, not held, absent nowhere.
        out += [(("at", thing, old), False) for old in at.get(thing, ()) if old != place]
        holder = held.get(thing)
        if holder is not None and ("holding", holder, thing) not in given:
            out.append((("holding", holder, thing), False))
        out += [((ABSENT, thing, p), False) for p in absences(facts, thing)]
    # A thing the batch leaves nowhere is lost: it is absent from where it was looked for.
    for thing, place in seen_not:
        if thing in seen_at:
            continue
        left = at.get(thing, set()) - {p for t, p in seen_not if t == thing}
        still_held = thing in held and (("holding", held[thing], thing), False) not in out
        if not left and not still_held:
            out.append(((ABSENT, thing, place), True))
    return out
