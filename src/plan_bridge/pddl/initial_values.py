"""Numeric fluents that are read but never given an initial value.

The formula walk of :mod:`~plan_bridge.pddl.checks` records every read of a numeric
fluent (:class:`~plan_bridge.pddl.checks.Read`: in a precondition, condition,
duration, effect or the goal, with the reading action's static preconditions and
inequalities). :func:`check_initial_values` grounds the reads over the problem's
objects and warns, on the problem's ``(:init`` line, for the instances ``(:init ...)``
leaves undefined, naming the problem line and the line of what reads them. The
planner layer finds :data:`NO_INITIAL_VALUE` in that warning to name it when
planning then fails.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

from plan_bridge.pddl.checks import Read, Usage
from plan_bridge.pddl.diagnostics import Diagnostics
from plan_bridge.pddl.model import DomainModel, Entry, ProblemModel
from plan_bridge.pddl.sexpr import Atom, Form

__all__ = ["NO_INITIAL_VALUE", "check_initial_values"]

#: In the warning about a numeric fluent read but never given a value.
NO_INITIAL_VALUE = "no initial value"

#: Ground instances looked at per problem when checking initial values (bounds the
#: check on problems with hundreds of thousands of objects).
_MAX_INSTANCES = 200_000


def check_initial_values(
    domain: DomainModel, problem: ProblemModel, diags: Diagnostics, usage: Usage
) -> None:
    """Warn for each numeric fluent that a condition, effect, duration or the goal
    reads but ``(:init ...)`` never gives a value: PDDL leaves it undefined."""
    if not usage.reads:
        return
    init = problem.init.items[1:] if problem.init is not None else []
    defined: dict[str, set[tuple[str, ...]]] = {}
    for fact in init:
        if isinstance(fact, Form) and fact.head == "=" and len(fact.items) == 3:
            target = fact.items[1]
            if isinstance(target, Form) and target.head:
                defined.setdefault(target.head, set()).add(_names(target))
    grounder = _Grounder(domain, problem)
    metric = problem.metric.items[1:] if problem.metric is not None else []
    for function, reads in usage.reads.items():
        if function == "total-cost" and any(
            isinstance(m, Form) and m.head == "total-cost" for m in metric
        ):
            continue  # unified-planning reads it as the actions' costs
        undefined = grounder.undefined(reads, defined.get(function, set()))
        if undefined.first is not None:
            _warn(problem, diags, function, undefined, undefined.first)


def _names(form: Form) -> tuple[str, ...]:
    """The names after the head: the arguments of a ground atom."""
    return tuple(a.text for a in form.items[1:] if isinstance(a, Atom))


@dataclass
class _Undefined:
    """The ground instances of one function that are read but have no initial value."""

    count: int = 0
    first: Read | None = None
    """The first read of one of them, for the message."""
    shown: list[tuple[str, ...]] = field(default_factory=list)
    """The first three, for the message."""

    def add(self, combination: tuple[str, ...], read: Read) -> None:
        self.count += 1
        self.first = self.first or read
        if len(self.shown) < 3:
            self.shown.append(combination)


class _Grounder:
    """Grounds reads over the problem's objects, :data:`_MAX_INSTANCES` at most in all."""

    def __init__(self, domain: DomainModel, problem: ProblemModel) -> None:
        self.domain = domain
        self.names = {**domain.constants, **problem.objects}
        self.facts: dict[str, list[tuple[str, ...]]] = {}
        if problem.init is not None:
            for fact in problem.init.items[1:]:
                if isinstance(fact, Form) and fact.head in domain.predicates:
                    self.facts.setdefault(fact.head, []).append(_names(fact))
        self.budget = _MAX_INSTANCES
        self._of_type: dict[str, list[str]] = {}

    def objects_of(self, kind: str) -> list[str]:
        if kind not in self._of_type:
            self._of_type[kind] = [
                n for n, e in self.names.items() if self.domain.is_subtype(e.type, kind)
            ]
        return self._of_type[kind]

    def undefined(self, reads: list[Read], given: set[tuple[str, ...]]) -> _Undefined:
        """The instances ``reads`` may read that are not in ``given``."""
        found = _Undefined()
        patterns: set[tuple[tuple[tuple[bool, str], ...], int]] = set()
        seen: set[tuple[str, ...]] = set()
        for read in reads:
            pattern = _pattern(read, self.names)
            if pattern is None or (pattern, id(read.guards)) in patterns:
                continue
            patterns.add((pattern, id(read.guards)))
            pools = [self.objects_of(kind) if var else [kind] for var, kind in pattern]
            allowed = _guard_filters(read, self.facts)
            for combination in itertools.product(*pools):
                self.budget -= 1
                if self.budget < 0:
                    break
                if combination in given or combination in seen:
                    continue
                if all(test(combination) for test in allowed):
                    seen.add(combination)
                    found.add(combination, read)
        return found


def _warn(
    problem: ProblemModel, diags: Diagnostics, function: str, undefined: _Undefined, first: Read
) -> None:
    count, missing = undefined.count, undefined.shown
    shown = [f"{function}({', '.join(args)})" if args else function for args in missing]
    listed = ", ".join(shown) + (f" and {count - len(shown)} more" if count > len(shown) else "")
    init_at = problem.init.offset if problem.init is not None else problem.tree.offset
    init_line = problem.source.line_col(init_at)[0]
    read_line = first.source.line_col(first.offset)[0]
    example = f"(= ({' '.join([function, *missing[0]])}) VALUE)"
    diags.warning(
        problem.source,
        init_at,
        f"{listed} {'has' if count == 1 else 'have'} {NO_INITIAL_VALUE} "
        f"({problem.source.path}:{init_line}); {first.reader} reads "
        f"{'it' if count == 1 else 'them'} ({first.source.path}:{read_line})",
        f"add {example} to (:init ...). PDDL leaves a fluent without an initial value "
        "undefined: a condition that reads it is false and an effect that changes it "
        "cannot apply, and some engines (TAMER) refuse the problem",
    )


def _pattern(read: Read, names: Mapping[str, Entry]) -> tuple[tuple[bool, str], ...] | None:
    """Per argument of a read, (True, type) for a variable or (False, name) for an
    object or constant; ``None`` when an argument is neither."""
    pattern: list[tuple[bool, str]] = []
    for arg in read.args:
        if isinstance(arg, Form):
            return None
        if arg.text.startswith("?"):
            kind = read.scope.get(arg.text)
            if kind is None:
                return None
            pattern.append((True, kind))
        elif arg.text in names:
            pattern.append((False, arg.text))
        else:
            return None
    return tuple(pattern)


def _guard_filters(
    read: Read, facts: Mapping[str, list[tuple[str, ...]]]
) -> list[Callable[[tuple[str, ...]], bool]]:
    """Tests a ground instance of ``read`` (its arguments' objects) must pass to be read
    at all: a static precondition holds for them initially, an inequality holds."""
    position: dict[str, int] = {}
    for index, arg in enumerate(read.args):
        if isinstance(arg, Atom) and arg.text.startswith("?"):
            position.setdefault(arg.text, index)
    tests: list[Callable[[tuple[str, ...]], bool]] = []
    for guard in read.guards:
        if guard.head == "not":
            inner = guard.items[1]
            assert isinstance(inner, Form)
            left, right = inner.items[1], inner.items[2]
            if not (isinstance(left, Atom) and isinstance(right, Atom)):
                continue
            if left.text in position and right.text in position:
                tests.append(_differ((position[left.text], position[right.text]), None))
            elif left.text in position and not right.text.startswith("?"):
                tests.append(_differ((position[left.text],), right.text))
            continue
        args = guard.items[1:]
        bound = [
            (j, position[a.text])
            for j, a in enumerate(args)
            if isinstance(a, Atom) and a.text in position
        ]
        fixed = [
            (j, a.text) for j, a in enumerate(args) if isinstance(a, Atom) and a.text[:1] != "?"
        ]
        if not bound:
            continue
        table = {
            tuple(fact[j] for j, _ in bound)
            for fact in facts.get(guard.head, ())
            if len(fact) == len(args) and all(fact[j] == name for j, name in fixed)
        }
        tests.append(_listed(tuple(i for _, i in bound), table))
    return tests


def _differ(indices: tuple[int, ...], name: str | None) -> Callable[[tuple[str, ...]], bool]:
    """Instances whose two arguments (or one and ``name``) differ."""
    if name is None:
        return lambda c: c[indices[0]] != c[indices[1]]
    return lambda c: c[indices[0]] != name


def _listed(
    indices: tuple[int, ...], table: set[tuple[str, ...]]
) -> Callable[[tuple[str, ...]], bool]:
    """Instances whose arguments at ``indices`` make a row of ``table``."""
    return lambda c: tuple(c[i] for i in indices) in table
