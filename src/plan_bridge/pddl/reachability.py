"""Delete-relaxation reachability: which goal atoms can never become true.

When a planner reports "no plan", the most useful explanation is a goal atom that
no sequence of actions can make true even if actions never delete anything. We
compute the relaxed-reachable atoms with a lifted fixpoint (join the preconditions
of each action against the atoms reached so far, add its add effects) instead of
grounding every action first: UP's grounders take 1-3 s on mid-sized benchmark
problems, the lifted fixpoint only touches reachable bindings.

The analysis over-approximates on purpose: preconditions that are not positive
atoms (negations, disjunctions, quantifiers, numeric comparisons) are treated as
satisfiable and conditional effects as firing. So an atom reported unreachable is
truly unreachable (sound), while a reachable atom may still be unreachable in the
real problem (then the planner's own verdict is all we can report).
"""

from __future__ import annotations

import time
from collections import defaultdict
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

from plan_bridge.pddl.task import Fact, PlanningTask, format_fact

__all__ = ["ReachabilityReport", "relaxed_unreachable_goals"]

# An argument pattern: ("?", parameter) | ("=", object) | ("*", type) for a
# quantified variable or an argument expression we do not analyse.
_Arg = tuple[str, str]
_Atom = tuple[str, tuple[_Arg, ...]]


@dataclass(frozen=True)
class _Schema:
    name: str
    parameters: tuple[tuple[str, str], ...]
    preconditions: tuple[_Atom, ...]
    adds: tuple[_Atom, ...]


@dataclass(frozen=True)
class ReachabilityReport:
    """Result of :func:`relaxed_unreachable_goals`.

    ``complete`` is False when the deadline stopped the analysis (then
    ``unreachable_goals`` is empty: nothing is claimed).
    """

    complete: bool
    unreachable_goals: tuple[Fact, ...] = ()
    reasons: dict[Fact, str] = field(default_factory=dict)
    reachable_atoms: int = 0

    def explanation(self) -> str:
        if not self.unreachable_goals:
            return ""
        lines = [
            f"goal atom {format_fact(goal)} is unreachable even ignoring delete effects: "
            f"{self.reasons.get(goal, 'no action can make it true')}"
            for goal in self.unreachable_goals
        ]
        return "; ".join(lines)


class _DeadlineError(Exception):
    pass


def relaxed_unreachable_goals(
    task: PlanningTask, *, timeout: float | None = 5.0
) -> ReachabilityReport:
    """Goal atoms of ``task`` that are unreachable under delete relaxation."""
    deadline = None if timeout is None else time.monotonic() + timeout
    schemas = [_schema_of(action) for action in task.problem.actions]
    always_true = {
        fluent.name
        for fluent, default in task.problem.fluents_defaults.items()
        if fluent.type.is_bool_type() and default.is_bool_constant() and default.is_true()
    }
    reached: dict[str, set[tuple[str, ...]]] = defaultdict(set)
    for fact in task.initial_facts:
        reached[fact[0]].add(fact[1:])
    try:
        _fixpoint(task, schemas, reached, deadline)
    except _DeadlineError:
        return ReachabilityReport(complete=False)
    unreachable = tuple(
        goal
        for goal in task.goal_facts
        if goal[0] not in always_true and goal[1:] not in reached.get(goal[0], set())
    )
    reasons = {goal: _reason(task, schemas, reached, goal) for goal in unreachable}
    return ReachabilityReport(
        complete=True,
        unreachable_goals=unreachable,
        reasons=reasons,
        reachable_atoms=sum(len(v) for v in reached.values()),
    )


def _schema_of(action: Any) -> _Schema:
    parameters = tuple((p.name, _type_name(p.type)) for p in action.parameters)
    preconditions: list[_Atom] = []
    pending = list(action.preconditions)
    while pending:
        node = pending.pop()
        if node.is_and():
            pending.extend(node.args)
        elif node.is_fluent_exp() and node.type.is_bool_type():
            args = tuple(_arg_pattern(arg) for arg in node.args)
            if all(kind != "*" for kind, _ in args):
                preconditions.append((node.fluent().name, args))
    adds: list[_Atom] = []
    for effect in action.effects:
        target = effect.fluent
        if not target.type.is_bool_type() or effect.value.is_false():
            continue
        forall = {variable.name: _type_name(variable.type) for variable in effect.forall}
        patterns: list[_Arg] = []
        for arg, declared in zip(target.args, target.fluent().signature, strict=True):
            pattern = _arg_pattern(arg)
            if pattern[0] == "*" and arg.is_variable_exp():
                pattern = ("*", forall.get(arg.variable().name, _type_name(declared.type)))
            elif pattern[0] == "*":
                pattern = ("*", _type_name(declared.type))
            patterns.append(pattern)
        adds.append((target.fluent().name, tuple(patterns)))
    # Most selective preconditions first keeps the joins small.
    preconditions.sort(key=lambda atom: -sum(kind == "=" for kind, _ in atom[1]))
    return _Schema(action.name, parameters, tuple(preconditions), tuple(adds))


def _arg_pattern(arg: Any) -> _Arg:
    if arg.is_parameter_exp():
        return ("?", arg.parameter().name)
    if arg.is_object_exp():
        return ("=", arg.object().name)
    return ("*", "")


def _type_name(up_type: Any) -> str:
    return str(up_type.name) if up_type.is_user_type() else str(up_type)


def _fixpoint(
    task: PlanningTask,
    schemas: list[_Schema],
    reached: dict[str, set[tuple[str, ...]]],
    deadline: float | None,
) -> None:
    fired: set[tuple[str, tuple[tuple[str, str], ...]]] = set()
    changed = True
    while changed:
        changed = False
        for schema in schemas:
            for binding in _bindings(task, schema, reached, deadline):
                key = (schema.name, tuple(sorted(binding.items())))
                if key in fired:
                    continue
                fired.add(key)
                for predicate, args in schema.adds:
                    for fact_args in _instantiate(task, schema, args, binding):
                        bucket = reached[predicate]
                        if fact_args not in bucket:
                            bucket.add(fact_args)
                            changed = True


def _bindings(
    task: PlanningTask,
    schema: _Schema,
    reached: dict[str, set[tuple[str, ...]]],
    deadline: float | None,
) -> Iterable[dict[str, str]]:
    types = dict(schema.parameters)
    partial: list[dict[str, str]] = [{}]
    for predicate, args in schema.preconditions:
        if deadline is not None and time.monotonic() > deadline:
            raise _DeadlineError
        facts = reached.get(predicate)
        if not facts:
            return []
        extended: list[dict[str, str]] = []
        for binding in partial:
            for fact in facts:
                candidate = _match(task, args, fact, binding, types)
                if candidate is not None:
                    extended.append(candidate)
        partial = extended
        if not partial:
            return []
    return partial


def _match(
    task: PlanningTask,
    args: tuple[_Arg, ...],
    fact: tuple[str, ...],
    binding: dict[str, str],
    types: dict[str, str],
) -> dict[str, str] | None:
    result = binding
    for (kind, value), obj in zip(args, fact, strict=True):
        if kind == "=":
            if value != obj:
                return None
        elif kind == "?":
            bound = result.get(value)
            if bound is None:
                wanted = types.get(value)
                if wanted is not None and wanted not in task.type_ancestors.get(
                    task.objects.get(obj, ""), frozenset({wanted})
                ):
                    return None
                if result is binding:
                    result = dict(binding)
                result[value] = obj
            elif bound != obj:
                return None
    return result


def _instantiate(
    task: PlanningTask, schema: _Schema, args: tuple[_Arg, ...], binding: dict[str, str]
) -> Iterable[tuple[str, ...]]:
    types = dict(schema.parameters)
    choices: list[tuple[str, ...]] = []
    for kind, value in args:
        if kind == "=":
            choices.append((value,))
        elif kind == "?" and value in binding:
            choices.append((binding[value],))
        else:
            # A parameter no precondition binds, or a forall variable: any object
            # of the declared type will do.
            type_name = types.get(value, "") if kind == "?" else value
            choices.append(task.objects_of_type(type_name) if type_name else tuple(task.objects))
    results: list[tuple[str, ...]] = [()]
    for options in choices:
        results = [(*prefix, option) for prefix in results for option in options]
    return results


def _reason(
    task: PlanningTask,
    schemas: list[_Schema],
    reached: dict[str, set[tuple[str, ...]]],
    goal: Fact,
) -> str:
    predicate, goal_args = goal[0], goal[1:]
    explanations: list[str] = []
    for schema in schemas:
        for add_predicate, args in schema.adds:
            if add_predicate != predicate:
                continue
            binding: dict[str, str] | None = {}
            for (kind, value), obj in zip(args, goal_args, strict=True):
                if binding is None:
                    break
                if kind == "=" and value != obj:
                    binding = None
                elif kind == "?":
                    if binding.get(value, obj) != obj:
                        binding = None
                    else:
                        binding[value] = obj
            if binding is None:
                continue
            blocked = _blocked_precondition(schema, reached, binding)
            explanations.append(
                f"{schema.name} could add it, but its precondition {blocked} never holds"
                if blocked
                else f"{schema.name} could add it, but its preconditions never hold together"
            )
    if not explanations:
        return f"it is false initially and no action adds `{predicate}`"
    return "it is false initially; " + "; ".join(explanations[:3])


def _blocked_precondition(
    schema: _Schema, reached: dict[str, set[tuple[str, ...]]], binding: dict[str, str]
) -> str | None:
    for predicate, args in schema.preconditions:
        shown = [binding.get(v, f"?{v}") if k == "?" else v for k, v in args]
        facts = reached.get(predicate, set())
        if not any(
            all(
                (k == "=" and v == obj) or (k == "?" and binding.get(v, obj) == obj)
                for (k, v), obj in zip(args, fact, strict=True)
            )
            for fact in facts
        ):
            return format_fact((predicate, *shown))
    return None
