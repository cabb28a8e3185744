"""What actions mean on a set of facts: preconditions and effects, evaluated in Python.

The executive checks a step's preconditions against the belief before dispatching it,
applies its effects when its skill succeeds, simulates the rest of a plan to decide
whether it is still valid, and regresses goals through plans for repair. Doing that
with unified-planning's simulator would cost far more per step than the skill
dispatch itself, so each lifted action is compiled once into Python closures over
a set of ground facts (closed world), and each ground action is cached.

Supported: conjunction, disjunction, negation, implication, equivalence, equality of
objects, existential and universal quantifiers, conditional and universally
quantified effects. Numeric effects (``increase total-cost``) are ignored: they only
carry plan costs. Numeric conditions are not supported and are reported as such.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from plan_bridge.errors import PlanBridgeError, UnsupportedFeatureError
from plan_bridge.pddl.task import Fact, PlanningTask, format_fact
from plan_bridge.planning.planner import PlanStep

__all__ = ["ActionModel", "GroundAction", "PlanCheck"]

Binding = Mapping[str, str]
Facts = Collection[Fact]
Condition = Callable[[Binding, Facts], bool]
Term = Callable[[Binding], str]


def _type_name(up_type: Any) -> str:
    return str(getattr(up_type, "name", None) or "object")


class _Compiler:
    """Turns unified-planning expressions into closures (one compiler per task)."""

    def __init__(self, task: PlanningTask) -> None:
        self.task = task

    def objects(self, up_type: Any) -> tuple[str, ...]:
        name = _type_name(up_type)
        if name == "object" and name not in self.task.type_ancestors:
            return tuple(self.task.objects)
        return self.task.objects_of_type(name)

    def term(self, node: Any) -> Term:
        if node.is_parameter_exp():
            key = node.parameter().name
            return lambda b: b[key]
        if node.is_variable_exp():
            key = node.variable().name
            return lambda b: b[key]
        if node.is_object_exp():
            value = node.object().name.lower()
            return lambda b: value
        raise UnsupportedFeatureError(
            f"the expression {node} is not an object term",
            feature="non-object terms",
        )

    def atom(self, node: Any) -> Callable[[Binding], Fact]:
        name = node.fluent().name.lower()
        terms = [self.term(arg) for arg in node.args]
        if not terms:
            fact = (name,)
            return lambda b: fact
        return lambda b: (name, *(t(b) for t in terms))

    def condition(self, node: Any) -> Condition:
        if node.is_bool_constant():
            value = bool(node.bool_constant_value())
            return lambda b, f: value
        if node.is_fluent_exp():
            if not node.type.is_bool_type():
                raise self._numeric(node)
            atom = self.atom(node)
            return lambda b, f: atom(b) in f
        if node.is_and():
            parts = [self.condition(a) for a in node.args]
            return lambda b, f: all(p(b, f) for p in parts)
        if node.is_or():
            parts = [self.condition(a) for a in node.args]
            return lambda b, f: any(p(b, f) for p in parts)
        if node.is_not():
            inner = self.condition(node.arg(0))
            return lambda b, f: not inner(b, f)
        if node.is_implies():
            lhs, rhs = self.condition(node.arg(0)), self.condition(node.arg(1))
            return lambda b, f: (not lhs(b, f)) or rhs(b, f)
        if node.is_iff():
            lhs, rhs = self.condition(node.arg(0)), self.condition(node.arg(1))
            return lambda b, f: lhs(b, f) == rhs(b, f)
        if node.is_equals():
            left, right = node.arg(0), node.arg(1)
            if not left.type.is_user_type():
                raise self._numeric(node)
            lt, rt = self.term(left), self.term(right)
            return lambda b, f: lt(b) == rt(b)
        if node.is_exists() or node.is_forall():
            names = [v.name for v in node.variables()]
            domains = [self.objects(v.type) for v in node.variables()]
            body = self.condition(node.arg(0))
            quantifier = any if node.is_exists() else all

            def quantified(b: Binding, f: Facts) -> bool:
                return quantifier(
                    body({**b, **dict(zip(names, combo, strict=True))}, f)
                    for combo in itertools.product(*domains)
                )

            return quantified
        raise self._numeric(node)

    def render(self, node: Any) -> Callable[[Binding], str]:
        """PDDL text of a condition with the parameters bound: ``(item-at cup hall)``."""
        if node.is_fluent_exp() and node.type.is_bool_type():
            atom = self.atom(node)
            return lambda b: format_fact(atom(b))
        ops = {"is_and": "and", "is_or": "or", "is_not": "not", "is_implies": "imply"}
        for test, word in ops.items():
            if getattr(node, test)():
                parts = [self.render(a) for a in node.args]
                return lambda b: f"({word} {' '.join(p(b) for p in parts)})"
        if node.is_equals() and node.arg(0).type.is_user_type():
            lt, rt = self.term(node.arg(0)), self.term(node.arg(1))
            return lambda b: f"(= {lt(b)} {rt(b)})"
        text = str(node)
        return lambda b: text

    @staticmethod
    def _numeric(node: Any) -> UnsupportedFeatureError:
        return UnsupportedFeatureError(
            f"the condition {node} is not supported by plan_bridge's executor (numeric "
            f"conditions and functions cannot be checked against a belief of facts)",
            feature="numeric conditions",
        )


@dataclass(frozen=True)
class _Effect:
    atom: Callable[[Binding], Fact]
    add: bool
    predicate: str
    condition: Condition | None
    forall: tuple[tuple[str, tuple[str, ...]], ...]


@dataclass
class _LiftedAction:
    name: str
    parameters: tuple[str, ...]
    precondition_parts: tuple[tuple[Callable[[Binding], str], Condition], ...]
    effects: tuple[_Effect, ...]
    strips_preconditions: tuple[Callable[[Binding], Fact], ...] | None


@dataclass
class GroundAction:
    """One action with its arguments bound; evaluates against sets of facts."""

    step: PlanStep
    _lifted: _LiftedAction = field(repr=False)
    _binding: dict[str, str] = field(repr=False)

    @property
    def name(self) -> str:
        return self.step.action

    @property
    def arguments(self) -> tuple[str, ...]:
        return self.step.arguments

    @property
    def binding(self) -> dict[str, str]:
        """Parameter name -> object name."""
        return dict(self._binding)

    def applicable(self, facts: Facts) -> bool:
        b = self._binding
        return all(cond(b, facts) for _, cond in self._lifted.precondition_parts)

    def unmet_preconditions(self, facts: Facts) -> list[str]:
        """The precondition parts that do not hold, as text with the arguments bound."""
        b = self._binding
        return [text(b) for text, cond in self._lifted.precondition_parts if not cond(b, facts)]

    def effects(self, facts: Facts) -> tuple[set[Fact], set[Fact]]:
        """(added, deleted) facts when applied in ``facts`` (conditions read ``facts``)."""
        adds: set[Fact] = set()
        dels: set[Fact] = set()
        for effect in self._lifted.effects:
            bindings: Iterable[Binding]
            if effect.forall:
                names = [n for n, _ in effect.forall]
                bindings = (
                    {**self._binding, **dict(zip(names, combo, strict=True))}
                    for combo in itertools.product(*(objs for _, objs in effect.forall))
                )
            else:
                bindings = (self._binding,)
            for b in bindings:
                if effect.condition is None or effect.condition(b, facts):
                    (adds if effect.add else dels).add(effect.atom(b))
        return adds, dels

    def apply(self, facts: Facts) -> frozenset[Fact]:
        """The state after this action (PDDL semantics: deletes first, then adds)."""
        adds, dels = self.effects(facts)
        return frozenset((set(facts) - dels) | adds)

    def precondition_atoms(self) -> frozenset[Fact] | None:
        """The positive atoms of a STRIPS precondition; None if not STRIPS."""
        atoms = self._lifted.strips_preconditions
        if atoms is None:
            return None
        return frozenset(a(self._binding) for a in atoms)

    def relevant_atoms(
        self, facts: Facts, effects: tuple[set[Fact], set[Fact]] | None = None
    ) -> set[Fact]:
        """Atoms a skill should report on: STRIPS preconditions and effects.

        Pass ``effects`` when they were computed already for ``facts``.
        """
        adds, dels = effects if effects is not None else self.effects(facts)
        return set(self.precondition_atoms() or ()) | adds | dels


@dataclass(frozen=True)
class PlanCheck:
    """The result of simulating a plan from a state."""

    valid: bool
    final_state: frozenset[Fact]
    failed_index: int | None = None
    unmet: tuple[str, ...] = ()
    goal_reached: bool = False

    @property
    def reason(self) -> str:
        if self.failed_index is not None:
            return f"step {self.failed_index} has unmet preconditions: {', '.join(self.unmet)}"
        if not self.goal_reached:
            return "the plan ends without reaching the goal"
        return "valid"


class ActionModel:
    """The actions of a task, compiled once; ground actions are cached."""

    def __init__(self, task: PlanningTask) -> None:
        self.task = task
        self._compiler = _Compiler(task)
        self._lifted: dict[str, _LiftedAction] = {}
        self._ground: dict[tuple[str, tuple[str, ...]], GroundAction] = {}

    def _lift(self, name: str) -> _LiftedAction:
        lifted = self._lifted.get(name)
        if lifted is not None:
            return lifted
        try:
            action = self.task.problem.action(name)
        except Exception as exc:
            raise PlanBridgeError(
                f"unknown action {name!r}; actions: {', '.join(sorted(self.task.actions))}"
            ) from exc
        c = self._compiler
        parts: list[tuple[Callable[[Binding], str], Condition]] = []
        strips: list[Callable[[Binding], Fact]] | None = []
        for pre in action.preconditions:
            conjuncts = pre.args if pre.is_and() else [pre]
            for conjunct in conjuncts:
                parts.append((c.render(conjunct), c.condition(conjunct)))
                if strips is not None:
                    if conjunct.is_fluent_exp() and conjunct.type.is_bool_type():
                        strips.append(c.atom(conjunct))
                    else:
                        strips = None
        effects = []
        for effect in action.effects:
            if not effect.fluent.type.is_bool_type():
                continue  # numeric effects only carry costs
            value = effect.value
            if not value.is_bool_constant():
                raise UnsupportedFeatureError(
                    f"action {name}: effect {effect} assigns a computed value",
                    feature="non-constant boolean effects",
                )
            condition = c.condition(effect.condition) if effect.is_conditional() else None
            forall = tuple((v.name, c.objects(v.type)) for v in effect.forall)
            effects.append(
                _Effect(
                    c.atom(effect.fluent),
                    bool(value.bool_constant_value()),
                    effect.fluent.fluent().name.lower(),
                    condition,
                    forall,
                )
            )
        lifted = _LiftedAction(
            name=name,
            parameters=tuple(p.name for p in action.parameters),
            precondition_parts=tuple(parts),
            effects=tuple(effects),
            strips_preconditions=tuple(strips) if strips is not None else None,
        )
        self._lifted[name] = lifted
        return lifted

    def ground(self, step: PlanStep) -> GroundAction:
        key = (step.action, step.arguments)
        ground = self._ground.get(key)
        if ground is None:
            lifted = self._lift(step.action)
            if len(step.arguments) != len(lifted.parameters):
                raise PlanBridgeError(
                    f"{step}: action {step.action} takes {len(lifted.parameters)} arguments "
                    f"({', '.join(lifted.parameters)}), got {len(step.arguments)}"
                )
            binding = dict(zip(lifted.parameters, step.arguments, strict=True))
            ground = GroundAction(step, lifted, binding)
            self._ground[key] = ground
        return ground

    def addable_predicates(self) -> frozenset[str]:
        """Predicates some action can make true (others can only be observed)."""
        cached = getattr(self, "_addable", None)
        if cached is None:
            cached = frozenset(
                e.predicate for name in self.task.actions for e in self._lift(name).effects if e.add
            )
            self._addable = cached
        return cached

    def goal_holds(self, facts: Facts) -> bool:
        return self.unmet_goals(facts) == []

    def unmet_goals(self, facts: Facts) -> list[str]:
        """Goal conditions that do not hold in ``facts``, as text."""
        goals = getattr(self, "_goals", None)
        if goals is None:
            goals = []
            for goal in self.task.problem.goals:
                for conjunct in goal.args if goal.is_and() else [goal]:
                    goals.append(
                        (self._compiler.render(conjunct)({}), self._compiler.condition(conjunct))
                    )
            self._goals = goals
        return [text for text, cond in goals if not cond({}, facts)]

    def check_plan(self, steps: Sequence[PlanStep], facts: Facts) -> PlanCheck:
        """Simulate ``steps`` from ``facts``: does every step apply and the goal hold?"""
        state = set(facts)  # one copy, updated in place: plans can be long, states big
        for index, step in enumerate(steps):
            ground = self.ground(step)
            if not ground.applicable(state):
                unmet = tuple(ground.unmet_preconditions(state))
                return PlanCheck(False, frozenset(state), index, unmet)
            adds, dels = ground.effects(state)
            state -= dels
            state |= adds
        reached = self.goal_holds(state)
        return PlanCheck(reached, frozenset(state), None, (), reached)

    def regress(self, steps: Sequence[PlanStep]) -> frozenset[Fact] | None:
        """Atoms that must hold before ``steps`` for them to reach the goal (STRIPS only).

        None when the goal or a precondition is not a conjunction of positive atoms.
        """
        goal = self.task.goal_facts
        if not self.task.goal_is_conjunctive:
            return None
        needed: set[Fact] = set(goal)
        for step in reversed(steps):
            ground = self.ground(step)
            pre = ground.precondition_atoms()
            if pre is None or any(
                e.condition is not None or e.forall for e in ground._lifted.effects
            ):
                return None
            adds = {e.atom(ground._binding) for e in ground._lifted.effects if e.add}
            needed = (needed - adds) | set(pre)
        return frozenset(needed)
