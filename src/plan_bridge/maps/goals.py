"""Goals in pyrobosim's task-planning vocabulary, checked against a world's names.

:func:`parse_goal` reads ``(At apple0 table0_tabletop)`` and the like into atoms of the
map domain over places (lower case): a spot's name (a room, a spawn, a doorway) stands
for its place, a location with one spawn for that spawn's place, ``(At OBJECT
LOCATION)`` for ``(Has LOCATION OBJECT)``. A goal no run can reach from the world as it
is (:func:`~plan_bridge.maps.blockers.goal_blockers`) is refused with the reason.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from plan_bridge.errors import PlanBridgeError
from plan_bridge.maps.model import WorldModel
from plan_bridge.pddl.constructs import did_you_mean
from plan_bridge.pddl.task import Fact

__all__ = ["GOAL_FORMS", "GoalError", "parse_goal", "parse_goal_forms"]

GOAL_FORMS = (
    "(At ROBOT ROOM|SPAWN|LOCATION|DOOR)",
    "(At OBJECT SPAWN|LOCATION)",
    "(Holding ROBOT OBJECT)",
    "(HandEmpty ROBOT)",
    "(IsOpen HALLWAY|LOCATION)",
    "(IsLocked HALLWAY|LOCATION)",
    "(Has LOCATION|SPAWN OBJECT)",
    "(Searched SPAWN)",
)
"""What a goal may say (a conjunction of these: ``(and ...)`` or several atoms)."""

_PREDICATES = {
    name.lower(): name
    for name in ("At", "Holding", "HandEmpty", "IsOpen", "IsLocked", "Has", "Searched")
}


class GoalError(PlanBridgeError):
    """A goal that does not fit the world (unknown name, wrong form)."""


def parse_goal(text: str, model: WorldModel) -> list[Fact]:
    """The goal atoms of ``text`` (pyrobosim's vocabulary, the world's names), checked,
    as lower-case atoms of the map domain. Raises :class:`GoalError` naming the atom,
    what is wrong and what is allowed, or what blocks the goal."""
    goal = parse_goal_forms(text, model)
    from plan_bridge.maps.blockers import goal_blockers

    blockers = goal_blockers(model, goal)
    if blockers:
        raise GoalError(
            f"goal {' '.join(text.split())} cannot be reached in {model.name}: "
            + "; ".join(blockers)
        )
    return [tuple(word.lower() for word in atom) for atom in goal]


def parse_goal_forms(text: str, model: WorldModel) -> list[Fact]:
    """The goal atoms of ``text`` in the world's names and spelling (``("At", "soda",
    "coffee_table_tabletop")``), checked against the world's names, not yet against
    what blocks them."""
    forms = _parse_forms(text)
    atoms: list[Any] = []
    for form in forms:
        if isinstance(form, list) and form and str(form[0]).lower() == "and":
            atoms.extend(form[1:])
        else:
            atoms.append(form)
    if not atoms:
        raise GoalError(f"goal {text!r} is empty; {_allowed()}")
    goal: list[Fact] = []
    for atom in atoms:
        fact = _goal_atom(atom, model)
        if fact not in goal:
            goal.append(fact)
    return goal


def _parse_forms(text: str) -> list[Any]:
    """Nested lists of words: ``(and (At a b))`` -> ``[["and", ["At", "a", "b"]]]``."""
    stack: list[list[Any]] = [[]]
    for token in re.findall(r"\(|\)|[^\s()]+", text.split(";", maxsplit=1)[0]):
        if token == "(":
            stack.append([])
        elif token == ")":
            if len(stack) == 1:
                raise GoalError(f"goal {text!r}: a ')' without its '('")
            done = stack.pop()
            stack[-1].append(done)
        else:
            stack[-1].append(token)
    if len(stack) != 1:
        raise GoalError(f"goal {text!r}: {len(stack) - 1} '(' not closed")
    return stack[0]


def _allowed() -> str:
    return "a goal is one or more of " + ", ".join(GOAL_FORMS)


def _goal_atom(atom: Any, model: WorldModel) -> Fact:
    predicate, args, shown = _goal_words(atom)
    words = _GoalWords(shown, args, [_kind(name, model, shown) for name in args])
    if predicate == "At":
        return _at_goal(words, model)
    if predicate == "Holding":
        words.need(0, ("robot",), GOAL_FORMS[2])
        words.need(1, ("object",), GOAL_FORMS[2])
    elif predicate == "HandEmpty":
        words.need(0, ("robot",), GOAL_FORMS[3])
    elif predicate in ("IsOpen", "IsLocked"):
        words.need(0, ("hallway", "location"), GOAL_FORMS[4 if predicate == "IsOpen" else 5])
    elif predicate == "Has":
        words.need(1, ("object",), GOAL_FORMS[6])
        if words.kinds[0] == "spawn":
            return ("At", args[1], _place(model, args[0]))
        words.need(0, ("location",), GOAL_FORMS[6])
    elif predicate == "Searched":
        words.need(0, ("spawn",), GOAL_FORMS[7])
        return ("Searched", _place(model, args[0]))
    return (predicate, *args)


def _place(model: WorldModel, spot: str) -> str:
    place = model.place_of(spot)
    assert place is not None, spot  # _kind said it is a spot
    return place


def _goal_words(atom: Any) -> tuple[str, list[str], str]:
    """The predicate (as the domain spells it), the arguments and the atom as shown in
    messages, after checking the atom's form, predicate and arity."""
    if isinstance(atom, list) and atom and str(atom[0]).lower() == "not":
        raise GoalError(
            f"goal atom {_show(atom)}: negated goals are not modelled (pyrobosim's goal "
            f"vocabulary has no negation, and the map domain no predicate for a closed "
            f"hallway or location): closing one cannot be a goal yet; {_allowed()}"
        )
    if not isinstance(atom, list) or not atom or any(isinstance(a, list) for a in atom):
        raise GoalError(
            f"goal atom {_show(atom)}: not an atom such as (At apple0 table0); {_allowed()}"
        )
    words = [str(a) for a in atom]
    shown = "(" + " ".join(words) + ")"
    predicate = _PREDICATES.get(words[0].lower())
    if predicate is None:
        hint = did_you_mean(words[0], _PREDICATES.values())
        raise GoalError(f"goal atom {shown}: unknown predicate {words[0]!r}{hint}; {_allowed()}")
    args = words[1:]
    arity = {"HandEmpty": 1, "IsOpen": 1, "IsLocked": 1, "Searched": 1}.get(predicate, 2)
    if len(args) != arity:
        forms = [f for f in GOAL_FORMS if f.startswith(f"({predicate} ")]
        raise GoalError(f"goal atom {shown}: {predicate} takes {arity} name(s): {', '.join(forms)}")
    return predicate, args, shown


@dataclass(frozen=True)
class _GoalWords:
    """A goal atom's arguments with what each names (robot, room, spawn...)."""

    shown: str
    args: list[str]
    kinds: list[str]

    def need(self, index: int, allowed: Sequence[str], form: str) -> None:
        if self.kinds[index] not in allowed:
            raise GoalError(
                f"goal atom {self.shown}: {self.args[index]} is a {self.kinds[index]}; "
                f"the form is {form}"
            )


def _at_goal(words: _GoalWords, model: WorldModel) -> Fact:
    """``(At ROBOT PLACE)`` or ``(At OBJECT PLACE)``; a location stands for its spawn."""
    args, kinds, shown = words.args, words.kinds, words.shown
    if args[0] not in {r.name for r in model.robots}:
        words.need(0, ("object",), GOAL_FORMS[1])
        if kinds[1] == "location":
            return ("Has", args[1], args[0])
        words.need(1, ("spawn",), GOAL_FORMS[1])
        return ("At", args[0], _place(model, args[1]))
    if kinds[1] == "location":
        spawns = model.gates[args[1]].spawns
        if len(spawns) != 1:
            raise GoalError(
                f"goal atom {shown}: location {args[1]} has the object spawns "
                f"{', '.join(spawns) or 'none'}; name the one the robot goes to"
            )
        return ("At", args[0], _place(model, spawns[0]))
    if kinds[1] == "hallway":
        a, b = model.halls[args[1]].ends
        raise GoalError(f"goal atom {shown}: a robot stands at one end of a hallway: {a} or {b}")
    words.need(1, ("room", "spawn", "door"), GOAL_FORMS[0])
    return ("At", args[0], _place(model, args[1]))


def _show(atom: Any) -> str:
    if isinstance(atom, list):
        return "(" + " ".join(_show(a) for a in atom) + ")"
    return str(atom)


def _kind(name: str, model: WorldModel, shown: str) -> str:
    if any(r.name == name for r in model.robots):
        return "robot"
    if name in model.items:
        return "object"
    if name in model.gates:
        return "hallway" if model.gates[name].kind == "hall" else "location"
    kind = model.spot_kinds.get(name)
    if kind is not None:
        return kind
    raise GoalError(
        f"goal atom {shown}: {name!r} is not a robot, room, hallway, location, object "
        f"spawn or object of {model.name}{did_you_mean(name, model.names)}"
    )
