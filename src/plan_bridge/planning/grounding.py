"""Grounding for the warm search: lifted actions compiled once, instantiated on demand.

A :class:`LiftedModel` is compiled once per base problem (a unified-planning
``Problem``) in the planner worker. It accepts the classical fragment the shipped
missions use: typed objects (type hierarchies too), preconditions and goals that are
conjunctions of atoms, negated atoms, equalities and negated equalities, and
unconditional add and delete effects; no numbers and no metric (the search looks
for short plans, and a problem with action costs asks for cheap ones). Anything else raises :class:`UnsupportedProblemError`, and the caller leaves
the problem to Fast Downward.

:meth:`LiftedModel.ground` instantiates the actions that are reachable from a state
under delete relaxation (a fixpoint that joins each action's positive preconditions
against the atoms reached so far) into a :class:`GroundTask` of bit masks. Relaxed
reachability is a closure (monotone and idempotent), so a grounding made from state
``s0`` serves every state inside the atoms reachable from ``s0`` that agrees with
``s0`` on the static atoms (those no action changes): :meth:`GroundTask.covers` says
when, and a replan then needs no grounding at all.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

__all__ = ["Atom", "GroundTask", "LiftedModel", "Operator", "UnsupportedProblemError"]

Atom = tuple[str, ...]
"""A ground atom: predicate, then object names."""

# An argument of a lifted atom: a parameter index, or an object name (a constant).
_Arg = int | str
_Pattern = tuple[str, tuple[_Arg, ...]]


class UnsupportedProblemError(Exception):
    """The problem is outside what the warm search handles (its message says why)."""


class GroundingLimitError(UnsupportedProblemError):
    """Grounding would exceed its operator limit or deadline: the problem is too big."""


@dataclass(frozen=True)
class _Literals:
    """A conjunction: positive and negative atoms, equalities and inequalities."""

    positive: tuple[_Pattern, ...] = ()
    negative: tuple[_Pattern, ...] = ()
    equal: tuple[tuple[_Arg, _Arg], ...] = ()
    unequal: tuple[tuple[_Arg, _Arg], ...] = ()
    never: bool = False
    """The conjunction holds a literal ``false``."""


@dataclass(frozen=True)
class _Action:
    name: str
    domains: tuple[frozenset[str], ...]
    """The objects each parameter ranges over (its type and subtypes)."""
    ordered_domains: tuple[tuple[str, ...], ...]
    pre: _Literals
    join: tuple[_Pattern, ...]
    """The positive preconditions in join order (most constants first)."""
    adds: tuple[_Pattern, ...]
    deletes: tuple[_Pattern, ...]
    orders: dict[int | None, list[tuple[int, _Pattern, int | None]]] = field(
        default_factory=dict, compare=False, hash=False
    )
    """Join orders by the literal joined first (filled by :func:`_join_order`)."""


@dataclass(frozen=True)
class Operator:
    """A ground action as bit masks over the task's fluent atoms."""

    name: str
    arguments: tuple[str, ...]
    pre: int
    neg: int
    add: int
    delete: int
    pre_facts: tuple[int, ...]
    add_facts: tuple[int, ...]


@dataclass(frozen=True)
class GroundTask:
    """The reachable ground actions of a problem from one state (see the module doc)."""

    facts: tuple[Atom, ...]
    """The fluent atoms reachable from the state, indexed by bit."""
    index: dict[Atom, int]
    operators: tuple[Operator, ...]
    statics: frozenset[Atom]
    """The state's atoms of static predicates (true throughout a search)."""
    static_predicates: frozenset[str]
    reached: frozenset[Atom]

    def covers(self, state: Iterable[Atom]) -> bool:
        """Whether this grounding holds every action reachable from ``state``."""
        statics = self.static_predicates
        fluent: list[Atom] = []
        static: set[Atom] = set()
        for atom in state:
            (static.add(atom) if atom[0] in statics else fluent.append(atom))
        return static == self.statics and all(atom in self.index for atom in fluent)

    def bits(self, atoms: Iterable[Atom]) -> int:
        """The state of the fluent ``atoms`` (statics are left out)."""
        mask = 0
        for atom in atoms:
            bit = self.index.get(atom)
            if bit is not None:
                mask |= 1 << bit
        return mask

    def goal(self, positive: Iterable[Atom], negative: Iterable[Atom]) -> tuple[int, int] | None:
        """Goal masks (atoms that must hold, atoms that must not), or None when a
        positive goal atom is unreachable (or a static one is violated)."""
        must, must_not = 0, 0
        for atom in positive:
            if atom[0] in self.static_predicates:
                if atom not in self.statics:
                    return None
                continue
            bit = self.index.get(atom)
            if bit is None:
                return None
            must |= 1 << bit
        for atom in negative:
            if atom[0] in self.static_predicates:
                if atom in self.statics:
                    return None
                continue
            bit = self.index.get(atom)
            if bit is not None:
                must_not |= 1 << bit
        return must, must_not


class LiftedModel:
    """The actions and goal of a classical problem, compiled for grounding."""

    def __init__(self, problem: Any) -> None:
        self.types: dict[str, frozenset[str]] = {}
        self._problem = problem
        if problem.quality_metrics:
            # Costs, makespan...: the search looks for short plans, not cheap ones.
            raise UnsupportedProblemError("the problem has a metric (e.g. action costs)")
        numeric = [f.name for f in problem.fluents if not f.type.is_bool_type()]
        if numeric:
            raise UnsupportedProblemError(f"numeric fluents ({', '.join(numeric)})")
        for fluent, default in problem.fluents_defaults.items():
            if fluent.type.is_bool_type() and default.is_bool_constant() and default.is_true():
                raise UnsupportedProblemError(f"predicate {fluent.name} is true by default")
        actions = []
        for action in problem.actions:
            if hasattr(action, "duration") or not hasattr(action, "preconditions"):
                raise UnsupportedProblemError(f"action {action.name} is not instantaneous")
            actions.append(self._compile_action(action))
        self.actions: tuple[_Action, ...] = tuple(actions)
        changed = {p for a in self.actions for p, _ in (*a.adds, *a.deletes)}
        self.static_predicates = frozenset(
            f.name for f in problem.fluents if f.type.is_bool_type() and f.name not in changed
        )
        goal = self.literals(problem.goals, {})
        if goal.equal or goal.unequal or goal.never:
            raise UnsupportedProblemError("the goal compares objects")
        self.goal_positive: tuple[Atom, ...] = tuple(_ground_atom(p) for p in goal.positive)
        self.goal_negative: tuple[Atom, ...] = tuple(_ground_atom(p) for p in goal.negative)

    # -- compiling -------------------------------------------------------------
    def _objects(self, up_type: Any) -> frozenset[str]:
        key = str(up_type)
        cached = self.types.get(key)
        if cached is None:
            if not up_type.is_user_type():
                raise UnsupportedProblemError(f"parameter of type {up_type}")
            cached = frozenset(obj.name for obj in self._problem.objects(up_type))
            self.types[key] = cached
        return cached

    def _compile_action(self, action: Any) -> _Action:
        names = {p.name: i for i, p in enumerate(action.parameters)}
        domains = tuple(self._objects(p.type) for p in action.parameters)
        pre = self.literals(action.preconditions, names)
        adds: list[_Pattern] = []
        deletes: list[_Pattern] = []
        for effect in action.effects:
            fluent = effect.fluent
            if not fluent.type.is_bool_type():
                raise UnsupportedProblemError(f"action {action.name} changes a number")
            if effect.is_conditional() or effect.forall or not effect.value.is_bool_constant():
                raise UnsupportedProblemError(f"action {action.name} has a conditional effect")
            pattern = _pattern(fluent, names)
            (adds if effect.value.bool_constant_value() else deletes).append(pattern)
        join = tuple(sorted(pre.positive, key=lambda p: -sum(isinstance(a, str) for a in p[1])))
        return _Action(
            action.name,
            domains,
            tuple(tuple(sorted(d)) for d in domains),
            pre,
            join,
            tuple(adds),
            tuple(deletes),
        )

    def literals(self, conditions: Iterable[Any], names: dict[str, int]) -> _Literals:
        """Compile a conjunction of literals (raises :class:`UnsupportedProblemError`)."""
        positive: list[_Pattern] = []
        negative: list[_Pattern] = []
        equal: list[tuple[_Arg, _Arg]] = []
        unequal: list[tuple[_Arg, _Arg]] = []
        never = False
        pending = list(conditions)
        while pending:
            node = pending.pop()
            negated = node.is_not()
            inner = node.arg(0) if negated else node
            if inner.is_and() and not negated:
                pending.extend(inner.args)
            elif inner.is_bool_constant():
                never = never or (inner.bool_constant_value() == negated)
            elif inner.is_equals():
                pair = (_argument(inner.arg(0), names), _argument(inner.arg(1), names))
                (unequal if negated else equal).append(pair)
            elif inner.is_fluent_exp() and inner.type.is_bool_type():
                (negative if negated else positive).append(_pattern(inner, names))
            else:
                raise UnsupportedProblemError(f"condition {node} is not a literal")
        return _Literals(tuple(positive), tuple(negative), tuple(equal), tuple(unequal), never)

    # -- grounding -------------------------------------------------------------
    def ground(
        self,
        state: Iterable[Atom],
        *,
        max_operators: int = 20_000,
        deadline: float | None = None,
    ) -> GroundTask:
        """The actions reachable from ``state`` under delete relaxation.

        Raises :class:`GroundingLimitError` past ``max_operators`` or ``deadline``.
        """
        reached: dict[str, set[tuple[str, ...]]] = {}
        for atom in state:
            reached.setdefault(atom[0], set()).add(atom[1:])
        statics = frozenset(
            (predicate, *args)
            for predicate, bucket in reached.items()
            if predicate in self.static_predicates
            for args in bucket
        )
        fired: set[tuple[int, tuple[str, ...]]] = set()
        ground: list[tuple[_Action, tuple[str, ...]]] = []
        # Semi-naive: after a first full round, a round only joins bindings that use
        # an atom that was new in the round before (``delta``).
        delta: dict[str, set[tuple[str, ...]]] | None = None
        while delta is None or delta:
            added: dict[str, set[tuple[str, ...]]] = {}
            for number, action in enumerate(self.actions):
                for binding in self._bindings(action, reached, delta):
                    key = (number, binding)
                    if key in fired or not _holds_statically(action, binding, statics):
                        continue
                    fired.add(key)
                    ground.append((action, binding))
                    for predicate, args in action.adds:
                        atom_args = _substitute(args, binding)
                        bucket = reached.setdefault(predicate, set())
                        if atom_args not in bucket:
                            bucket.add(atom_args)
                            added.setdefault(predicate, set()).add(atom_args)
                if len(ground) > max_operators:
                    raise GroundingLimitError(f"more than {max_operators} ground actions")
                if deadline is not None and time.monotonic() > deadline:
                    raise GroundingLimitError("grounding ran out of time")
            delta = added
        return self._task(ground, reached, statics)

    def _bindings(
        self,
        action: _Action,
        reached: dict[str, set[tuple[str, ...]]],
        delta: dict[str, set[tuple[str, ...]]] | None,
    ) -> Iterator[tuple[str, ...]]:
        """The bindings of ``action`` whose positive preconditions are reached (with
        ``delta``: those that use at least one atom of ``delta``)."""
        if delta is None:
            partials = [self._join(action, reached, None, ())]
        else:
            partials = [
                self._join(action, reached, first, delta[predicate])
                for first, (predicate, _) in enumerate(action.join)
                if predicate in delta
            ]
        for partial in partials:
            for binding in partial:
                free = [i for i, value in enumerate(binding) if value is None]
                if not free:
                    yield tuple(str(value) for value in binding)
                    continue
                for values in itertools.product(*(action.ordered_domains[i] for i in free)):
                    complete = list(binding)
                    for i, value in zip(free, values, strict=True):
                        complete[i] = value
                    yield tuple(str(value) for value in complete)

    def _join(
        self,
        action: _Action,
        reached: dict[str, set[tuple[str, ...]]],
        first: int | None,
        first_facts: Iterable[tuple[str, ...]],
    ) -> list[list[str | None]]:
        """Partial bindings satisfying the positive preconditions (a hash join per
        literal on an argument bound before it); literal ``first`` only joins
        ``first_facts``."""
        partial: list[list[str | None]] = [[None] * len(action.domains)]
        for number, (predicate, args), key in _join_order(action, first):
            facts = first_facts if number == first else reached.get(predicate, ())
            if key is None:
                pairs: Iterable[tuple[list[str | None], tuple[str, ...]]] = (
                    (binding, fact) for binding in partial for fact in facts
                )
            else:
                table: dict[str, list[tuple[str, ...]]] = {}
                for fact in facts:
                    table.setdefault(fact[key], []).append(fact)
                wanted = args[key]
                pairs = (
                    (binding, fact)
                    for binding in partial
                    for fact in table.get(
                        wanted if isinstance(wanted, str) else str(binding[wanted]), ()
                    )
                )
            partial = [
                extended
                for binding, fact in pairs
                if (extended := _match(args, fact, binding, action.domains)) is not None
            ]
            if not partial:
                break
        return partial

    def _task(
        self,
        ground: Sequence[tuple[_Action, tuple[str, ...]]],
        reached: dict[str, set[tuple[str, ...]]],
        statics: frozenset[Atom],
    ) -> GroundTask:
        facts = sorted(
            (predicate, *args)
            for predicate, bucket in reached.items()
            if predicate not in self.static_predicates
            for args in bucket
        )
        index = {atom: bit for bit, atom in enumerate(facts)}
        operators = []
        # In name order, not discovery order (which follows set iteration, hence the
        # hash seed): the search breaks ties by operator order, so its plans depend
        # neither on the process nor on the grounding a state was covered by.
        for action, binding in sorted(ground, key=lambda entry: (entry[0].name, entry[1])):
            pre_facts = tuple(
                index[(p, *_substitute(a, binding))]
                for p, a in action.pre.positive
                if p not in self.static_predicates
            )
            neg = _mask(index, action.pre.negative, binding, self.static_predicates)
            add_facts = tuple(index[(p, *_substitute(a, binding))] for p, a in action.adds)
            add = sum(1 << bit for bit in set(add_facts))
            operators.append(
                Operator(
                    action.name,
                    binding,
                    sum(1 << bit for bit in set(pre_facts)),
                    neg,
                    add,
                    _mask(index, action.deletes, binding, frozenset()),
                    tuple(sorted(set(pre_facts))),
                    tuple(sorted(set(add_facts))),
                )
            )
        return GroundTask(
            tuple(facts),
            index,
            tuple(operators),
            statics,
            self.static_predicates,
            frozenset(index),
        )


def _join_order(action: _Action, first: int | None) -> list[tuple[int, _Pattern, int | None]]:
    """The positive preconditions in join order: ``first`` (if any), then greedily the
    one with the most bound arguments; each with the position of a bound argument to
    hash on (None: nothing bound yet). Cached on the action."""
    cached = action.orders.get(first)
    if cached is not None:
        return cached
    left = list(range(len(action.join)))
    bound: set[int] = set()
    order: list[tuple[int, _Pattern, int | None]] = []
    while left:
        if first is not None and first in left:
            number = first
        else:
            number = max(
                left,
                key=lambda n: sum(isinstance(a, str) or a in bound for a in action.join[n][1]),
            )
        left.remove(number)
        predicate, args = action.join[number]
        key = next((i for i, a in enumerate(args) if isinstance(a, str) or a in bound), None)
        order.append((number, (predicate, args), key))
        bound.update(a for a in args if isinstance(a, int))
    action.orders[first] = order
    return order


def _argument(node: Any, names: dict[str, int]) -> _Arg:
    if node.is_parameter_exp():
        return names[node.parameter().name]
    if node.is_object_exp():
        return str(node.object().name)
    raise UnsupportedProblemError(f"argument {node} is neither a parameter nor an object")


def _pattern(node: Any, names: dict[str, int]) -> _Pattern:
    return (node.fluent().name, tuple(_argument(arg, names) for arg in node.args))


def _ground_atom(pattern: _Pattern) -> Atom:
    predicate, args = pattern
    return (predicate, *(str(a) for a in args))


def _substitute(args: tuple[_Arg, ...], binding: tuple[str, ...]) -> tuple[str, ...]:
    return tuple(binding[a] if isinstance(a, int) else a for a in args)


def _match(
    args: tuple[_Arg, ...],
    fact: tuple[str, ...],
    binding: list[str | None],
    domains: tuple[frozenset[str], ...],
) -> list[str | None] | None:
    extended: list[str | None] | None = None
    for arg, obj in zip(args, fact, strict=True):
        if isinstance(arg, str):
            if arg != obj:
                return None
            continue
        current = (extended or binding)[arg]
        if current is None:
            if obj not in domains[arg]:
                return None
            if extended is None:
                extended = list(binding)
            extended[arg] = obj
        elif current != obj:
            return None
    return extended if extended is not None else binding


def _holds_statically(action: _Action, binding: tuple[str, ...], statics: frozenset[Atom]) -> bool:
    """Equalities, inequalities and negated static atoms of the precondition."""
    pre = action.pre
    if pre.never:
        return False

    def value(arg: _Arg) -> str:
        return binding[arg] if isinstance(arg, int) else arg

    if any(value(a) != value(b) for a, b in pre.equal):
        return False
    if any(value(a) == value(b) for a, b in pre.unequal):
        return False
    return not any((p, *_substitute(args, binding)) in statics for p, args in pre.negative)


def _mask(
    index: dict[Atom, int],
    patterns: Iterable[_Pattern],
    binding: tuple[str, ...],
    skip: frozenset[str],
) -> int:
    """The bits of the patterns' atoms that are indexed (others are never true)."""
    mask = 0
    for predicate, args in patterns:
        if predicate in skip:
            continue
        bit = index.get((predicate, *_substitute(args, binding)))
        if bit is not None:
            mask |= 1 << bit
    return mask
