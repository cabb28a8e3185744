"""What actions mean on a set of facts: preconditions and effects, evaluated in Python.

The executive checks a step's preconditions against the belief before dispatching it,
applies its effects when its skill succeeds, simulates the rest of a plan to decide
whether it is still valid, and regresses goals through plans for repair. Doing that
with unified-planning's simulator would cost far more per step than the skill
dispatch itself, so each lifted action is compiled once into Python closures over
a set of ground facts (closed world), and each ground action is cached.

Supported: conjunction, disjunction, negation, implication, equivalence, equality of
objects, existential and universal quantifiers, conditional and universally
quantified effects; numeric fluents (``(battery ?r)``) in comparisons, arithmetic
(+ - * /) and effects (assign, increase, decrease), read from and written to the
numbers a state carries (:func:`~plan_bridge.belief.values_of`). A
comparison with an undefined numeric value is false. ``total-cost`` is left out: it
only carries plan costs.

Durative actions are grounded too (:class:`GroundAction` ``.durative``): their at-start
conditions are the action's preconditions, over-all conditions its invariant
(:meth:`GroundAction.unmet_invariant`), at-end conditions are checked before the
at-end effects (:meth:`GroundAction.unmet_at_end`); :meth:`GroundAction.start_effects`
and :meth:`GroundAction.end_effects` are the two halves, and :meth:`GroundAction.effects`
their composition (start, then end), which is what sequential simulation, plan
checks and repair use.

(Over 600 lines: the compiler of UP expressions into closures and the ground
actions that evaluate them share private closure types and caches; split, each half
would export the other's internals.)
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from plan_bridge.belief import FactSnapshot, values_of
from plan_bridge.errors import PlanBridgeError, UnsupportedFeatureError
from plan_bridge.pddl.task import Fact, PlanningTask, format_fact
from plan_bridge.planning.types import PlanStep

__all__ = ["ActionModel", "GroundAction", "PlanCheck"]

Binding = Mapping[str, str]
Facts = Collection[Fact]
Condition = Callable[[Binding, Facts], bool]
Term = Callable[[Binding], str]
Value = Callable[[Binding, Facts], float]
Values = dict[Fact, float]
#: The metric's fluent: it only carries plan costs, the belief does not track it.
COST_FLUENT = "total-cost"


class _SimState(set[Fact]):
    """A state being simulated: facts plus the numeric values (``values``)."""

    values: Values


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

    def number(self, node: Any) -> Value:
        """A numeric expression; raises ``KeyError`` on an undefined fluent value."""
        if node.is_int_constant() or node.is_real_constant():
            constant = float(node.constant_value())
            return lambda b, f: constant
        if node.is_fluent_exp():
            atom = self.atom(node)
            return lambda b, f: values_of(f)[atom(b)]
        operators: dict[str, Callable[[float, float], float]] = {
            "is_plus": lambda x, y: x + y,
            "is_minus": lambda x, y: x - y,
            "is_times": lambda x, y: x * y,
            "is_div": lambda x, y: x / y,
        }
        for test, operator in operators.items():
            if getattr(node, test)():
                parts = [self.number(a) for a in node.args]

                def combined(
                    b: Binding,
                    f: Facts,
                    parts: list[Value] = parts,
                    op: Callable[[float, float], float] = operator,
                ) -> float:
                    value = parts[0](b, f)
                    for part in parts[1:]:
                        value = op(value, part(b, f))
                    return value

                return combined
        raise UnsupportedFeatureError(
            f"the numeric expression {node} is not supported by plan_bridge's executor",
            feature="numeric expressions",
        )

    def comparison(self, node: Any, test: Callable[[float, float], bool]) -> Condition:
        left, right = self.number(node.arg(0)), self.number(node.arg(1))

        def compare(b: Binding, f: Facts) -> bool:
            try:
                return test(left(b, f), right(b, f))
            except (KeyError, ZeroDivisionError):
                return False  # an undefined value makes the comparison false

        return compare

    def condition(self, node: Any) -> Condition:
        if node.is_le():
            return self.comparison(node, lambda x, y: x <= y)
        if node.is_lt():
            return self.comparison(node, lambda x, y: x < y)
        if node.is_equals():
            return self._equality(node)
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
        if node.is_exists() or node.is_forall():
            return self._quantified(node)
        raise self._numeric(node)

    def _equality(self, node: Any) -> Condition:
        """``(= A B)``: of two numbers (within 1e-9), or of two objects."""
        left, right = node.arg(0), node.arg(1)
        if not left.type.is_user_type():
            return self.comparison(node, lambda x, y: abs(x - y) <= 1e-9)
        lt, rt = self.term(left), self.term(right)
        return lambda b, f: lt(b) == rt(b)

    def _quantified(self, node: Any) -> Condition:
        """``exists`` or ``forall`` over the objects of the variables' types."""
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
        words = {"is_le": "<=", "is_lt": "<", "is_equals": "="}
        for test, word in words.items():
            if getattr(node, test)():
                left, right = self.render_number(node.arg(0)), self.render_number(node.arg(1))
                return lambda b: f"({word} {left(b)} {right(b)})"
        text = str(node)
        return lambda b: text

    def render_number(self, node: Any) -> Callable[[Binding], str]:
        if node.is_fluent_exp():
            atom = self.atom(node)
            return lambda b: format_fact(atom(b))
        if node.is_int_constant() or node.is_real_constant():
            text = f"{float(node.constant_value()):g}"
            return lambda b: text
        words = {"is_plus": "+", "is_minus": "-", "is_times": "*", "is_div": "/"}
        for test, word in words.items():
            if getattr(node, test)():
                parts = [self.render_number(a) for a in node.args]
                return lambda b: f"({word} {' '.join(p(b) for p in parts)})"
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


@dataclass(frozen=True)
class _NumericEffect:
    atom: Callable[[Binding], Fact]
    kind: str
    """``assign``, ``increase`` or ``decrease``."""
    value: Value
    condition: Condition | None
    forall: tuple[tuple[str, tuple[str, ...]], ...]


Parts = tuple[tuple[Callable[[Binding], str], Condition], ...]


@dataclass(frozen=True)
class _Phase:
    """The effects that happen at one time point of an action."""

    effects: tuple[_Effect, ...] = ()
    numeric: tuple[_NumericEffect, ...] = ()


@dataclass
class _LiftedAction:
    name: str
    parameters: tuple[str, ...]
    precondition_parts: Parts
    """For a durative action: its at-start conditions."""
    effects: tuple[_Effect, ...]
    """Every boolean effect (both time points of a durative action)."""
    strips_preconditions: tuple[Callable[[Binding], Fact], ...] | None
    phases: tuple[_Phase, ...] = ()
    """One phase for an instantaneous action; start and end for a durative one."""
    invariant_parts: Parts = ()
    end_parts: Parts = ()
    durative: bool = False


def _bindings(
    binding: Binding, forall: tuple[tuple[str, tuple[str, ...]], ...]
) -> Iterable[Binding]:
    if not forall:
        return (binding,)
    names = [n for n, _ in forall]
    return (
        {**binding, **dict(zip(names, combo, strict=True))}
        for combo in itertools.product(*(objs for _, objs in forall))
    )


def _phase_effects(
    phase: _Phase, binding: Binding, facts: Facts
) -> tuple[set[Fact], set[Fact], Values]:
    """(added, deleted, new numeric values) of one phase applied in ``facts``."""
    adds: set[Fact] = set()
    dels: set[Fact] = set()
    for effect in phase.effects:
        for b in _bindings(binding, effect.forall):
            if effect.condition is None or effect.condition(b, facts):
                (adds if effect.add else dels).add(effect.atom(b))
    values: Values = {}
    if phase.numeric:
        current = values_of(facts)
        for numeric in phase.numeric:
            for b in _bindings(binding, numeric.forall):
                if numeric.condition is not None and not numeric.condition(b, facts):
                    continue
                atom = numeric.atom(b)
                try:
                    amount = numeric.value(b, facts)
                    if numeric.kind == "assign":
                        values[atom] = amount
                    else:
                        old = values.get(atom, current[atom])
                        values[atom] = old + amount if numeric.kind == "increase" else old - amount
                except (KeyError, ZeroDivisionError):
                    continue  # an undefined value stays undefined
    return adds, dels, values


def _after(facts: Facts, adds: set[Fact], dels: set[Fact], values: Values) -> FactSnapshot:
    return FactSnapshot((set(facts) - dels) | adds, {**values_of(facts), **values})


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

    @property
    def durative(self) -> bool:
        """Whether this is a durative action (start and end effects, an invariant)."""
        return self._lifted.durative

    def applicable(self, facts: Facts) -> bool:
        """Whether the action can start in ``facts``: its preconditions hold (for a
        durative action: the at-start conditions, and the over-all conditions in the
        state its at-start effects make)."""
        if not self.startable(facts):
            return False
        return not self._lifted.invariant_parts or not self.unmet_invariant(self._started(facts))

    def startable(self, facts: Facts) -> bool:
        """Whether the at-start conditions hold in ``facts`` (all preconditions of an
        instantaneous action). Unlike :meth:`applicable`, the over-all conditions are
        not asked for: in PDDL 2.1 they must hold only after the start, so an action
        starting at the same instant may still establish them (the door another robot
        begins to hold)."""
        b = self._binding
        return all(cond(b, facts) for _, cond in self._lifted.precondition_parts)

    def unmet_preconditions(self, facts: Facts) -> list[str]:
        """The precondition parts that do not hold, as text with the arguments bound
        (over-all conditions that would not hold once started: ``over all: ...``)."""
        b = self._binding
        unmet = [text(b) for text, cond in self._lifted.precondition_parts if not cond(b, facts)]
        if self._lifted.invariant_parts:
            unmet += [f"over all: {c}" for c in self.unmet_invariant(self._started(facts))]
        return unmet

    def _started(self, facts: Facts) -> Facts:
        adds, dels, values = self.start_effects(facts)
        return _after(facts, adds, dels, values) if adds or dels or values else facts

    def unmet_invariant(self, facts: Facts) -> list[str]:
        """The over-all conditions of a durative action that do not hold in ``facts``."""
        b = self._binding
        return [text(b) for text, cond in self._lifted.invariant_parts if not cond(b, facts)]

    def unmet_at_end(self, facts: Facts) -> list[str]:
        """The at-end conditions of a durative action that do not hold in ``facts``."""
        b = self._binding
        return [text(b) for text, cond in self._lifted.end_parts if not cond(b, facts)]

    def start_effects(self, facts: Facts) -> tuple[set[Fact], set[Fact], Values]:
        """(added, deleted, numeric values) at the start (all effects if instantaneous)."""
        return _phase_effects(self._lifted.phases[0], self._binding, facts)

    def end_effects(self, facts: Facts) -> tuple[set[Fact], set[Fact], Values]:
        """(added, deleted, numeric values) at the end of a durative action, applied in
        ``facts`` (the state when it ends); nothing for an instantaneous one."""
        if len(self._lifted.phases) < 2:
            return set(), set(), {}
        return _phase_effects(self._lifted.phases[1], self._binding, facts)

    def all_effects(self, facts: Facts) -> tuple[set[Fact], set[Fact], Values]:
        """(added, deleted, values) of the whole action (start then end) in ``facts``."""
        adds, dels, values = self.start_effects(facts)
        if len(self._lifted.phases) < 2:
            return adds, dels, values
        middle = _after(facts, adds, dels, values)
        end_adds, end_dels, end_values = self.end_effects(middle)
        return (adds - end_dels) | end_adds, dels | end_dels, {**values, **end_values}

    def effects(self, facts: Facts) -> tuple[set[Fact], set[Fact]]:
        """(added, deleted) facts when applied in ``facts`` (conditions read ``facts``)."""
        adds, dels, _ = self.all_effects(facts)
        return adds, dels

    def apply(self, facts: Facts) -> frozenset[Fact]:
        """The state after this action (PDDL semantics: deletes first, then adds)."""
        adds, dels, values = self.all_effects(facts)
        return _after(facts, adds, dels, values)

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


def _timed_conditions(action: Any) -> tuple[list[Any], list[Any], list[Any]]:
    """A durative action's conditions: (at start, over all, at end)."""
    at_start: list[Any] = []
    over_all: list[Any] = []
    at_end: list[Any] = []
    for interval, conditions in action.conditions.items():
        lower, upper = interval.lower, interval.upper
        if lower.is_from_start() and upper.is_from_start() and lower.delay == upper.delay == 0:
            at_start.extend(conditions)
        elif lower.is_from_end() and upper.is_from_end():
            at_end.extend(conditions)
        else:
            over_all.extend(conditions)
    return at_start, over_all, at_end


def _timed_effects(action: Any) -> tuple[list[Any], list[Any]]:
    """A durative action's effects: (at start, at end)."""
    start: list[Any] = []
    end: list[Any] = []
    for timing, effects in action.effects.items():
        (end if timing.is_from_end() else start).extend(effects)
    return start, end


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
        durative = hasattr(action, "duration")
        if durative:
            at_start, over_all, at_end = _timed_conditions(action)
            start_effects, end_effects = _timed_effects(action)
        else:
            at_start, over_all, at_end = list(action.preconditions), [], []
            start_effects, end_effects = list(action.effects), []
        parts, strips = self._parts(at_start)
        phases = [self._phase(name, start_effects)]
        if durative:
            phases.append(self._phase(name, end_effects))
        lifted = _LiftedAction(
            name=name,
            parameters=tuple(p.name for p in action.parameters),
            precondition_parts=parts,
            effects=tuple(e for phase in phases for e in phase.effects),
            strips_preconditions=strips,
            phases=tuple(phases),
            invariant_parts=self._parts(over_all)[0],
            end_parts=self._parts(at_end)[0],
            durative=durative,
        )
        self._lifted[name] = lifted
        return lifted

    def _parts(
        self, conditions: Iterable[Any]
    ) -> tuple[Parts, tuple[Callable[[Binding], Fact], ...] | None]:
        """Conjuncts as (text, condition), and their atoms if all are positive atoms
        (a STRIPS precondition; None otherwise)."""
        c = self._compiler
        parts: list[tuple[Callable[[Binding], str], Condition]] = []
        atoms: list[Callable[[Binding], Fact]] | None = []
        for pre in conditions:
            for conjunct in pre.args if pre.is_and() else [pre]:
                parts.append((c.render(conjunct), c.condition(conjunct)))
                if atoms is not None:
                    if conjunct.is_fluent_exp() and conjunct.type.is_bool_type():
                        atoms.append(c.atom(conjunct))
                    else:
                        atoms = None
        return tuple(parts), None if atoms is None else tuple(atoms)

    def _phase(self, name: str, effects: Iterable[Any]) -> _Phase:
        c = self._compiler
        booleans: list[_Effect] = []
        numbers: list[_NumericEffect] = []
        for effect in effects:
            condition = c.condition(effect.condition) if effect.is_conditional() else None
            forall = tuple((v.name, c.objects(v.type)) for v in effect.forall)
            if not effect.fluent.type.is_bool_type():
                if effect.fluent.fluent().name.lower() == COST_FLUENT:
                    continue
                kind = (
                    "increase"
                    if effect.is_increase()
                    else "decrease"
                    if effect.is_decrease()
                    else "assign"
                )
                numbers.append(
                    _NumericEffect(
                        c.atom(effect.fluent), kind, c.number(effect.value), condition, forall
                    )
                )
                continue
            value = effect.value
            if not value.is_bool_constant():
                raise UnsupportedFeatureError(
                    f"action {name}: effect {effect} assigns a computed value",
                    feature="non-constant boolean effects",
                )
            booleans.append(
                _Effect(
                    c.atom(effect.fluent),
                    bool(value.bool_constant_value()),
                    effect.fluent.fluent().name.lower(),
                    condition,
                    forall,
                )
            )
        return _Phase(tuple(booleans), tuple(numbers))

    def initial_values(self) -> dict[Fact, float]:
        """The numeric atoms' values in the task's initial state (``total-cost`` aside)."""
        values: dict[Fact, float] = {}
        for fluent_exp, value in self.task.problem.explicit_initial_values.items():
            if fluent_exp.type.is_bool_type() or fluent_exp.fluent().name == COST_FLUENT:
                continue
            if value.is_int_constant() or value.is_real_constant():
                values[self._compiler.atom(fluent_exp)({})] = float(value.constant_value())
        return values

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
        elif ground.step.start != step.start or ground.step.duration != step.duration:
            # The same action planned at other times (steps compare without their
            # times): this step's times, not those of the plan that grounded it first.
            return GroundAction(step, ground._lifted, ground._binding)
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
        if any(step.start is not None for step in steps):
            return self._check_timed(steps, facts)
        state = _SimState(facts)  # one copy, updated in place: plans can be long, states big
        state.values = dict(values_of(facts))
        for index, step in enumerate(steps):
            ground = self.ground(step)
            if not ground.applicable(state):
                unmet = tuple(ground.unmet_preconditions(state))
                return PlanCheck(False, FactSnapshot(state, state.values), index, unmet)
            if ground.durative and ground._lifted.end_parts:
                # Sequentially, the end follows the start at once: the at-end
                # conditions must hold in the state the start effects make.
                middle = ground._started(state)
                unmet = tuple(f"at end: {c}" for c in ground.unmet_at_end(middle))
                if unmet:
                    return PlanCheck(False, FactSnapshot(state, state.values), index, unmet)
            adds, dels, values = ground.all_effects(state)
            state -= dels
            state |= adds
            state.values.update(values)
        reached = self.goal_holds(state)
        return PlanCheck(reached, FactSnapshot(state, state.values), None, (), reached)

    def _check_timed(self, steps: Sequence[PlanStep], facts: Facts) -> PlanCheck:
        """Simulate a temporal plan on its timeline: start and end points in time order
        (an end before a start at the same instant); at each point its conditions are
        checked and its effects applied, and after every point the over-all
        conditions of the actions then running."""
        points = []
        for index, step in enumerate(steps):
            start = step.start or 0.0
            points.append((round(start, 6), 1, index, "start"))
            if self.ground(step).durative:
                points.append((round(start + (step.duration or 0.0), 6), 0, index, "end"))
        points.sort()
        ends = {index: at for at, kind, index, _ in points if kind == 0}
        state: Facts = FactSnapshot(facts, values_of(facts))
        running: set[int] = set()
        for position, (now, _, index, point) in enumerate(points):
            ground = self.ground(steps[index])
            if point == "start":
                unmet = tuple(
                    text(ground._binding)
                    for text, cond in ground._lifted.precondition_parts
                    if not cond(ground._binding, state)
                )
                effects = ground.start_effects(state)
                running.add(index)
            else:
                unmet = tuple(f"at end: {c}" for c in ground.unmet_at_end(state))
                effects = ground.end_effects(state)
                running.discard(index)
            if unmet:
                return PlanCheck(False, FactSnapshot(state, values_of(state)), index, unmet)
            state = _after(state, *effects)
            if position + 1 < len(points) and points[position + 1][0] == now:
                continue  # the invariants hold between instants: finish this one first
            for other in sorted(running):
                if ends.get(other, now) <= now:
                    continue
                broken = self.ground(steps[other]).unmet_invariant(state)
                if broken:
                    unmet = tuple(f"over all: {c}" for c in broken)
                    return PlanCheck(False, FactSnapshot(state, values_of(state)), other, unmet)
        reached = self.goal_holds(state)
        return PlanCheck(reached, FactSnapshot(state, values_of(state)), None, (), reached)

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
            if (
                pre is None
                or ground.durative
                or any(e.condition is not None or e.forall for e in ground._lifted.effects)
            ):
                return None
            adds = {e.atom(ground._binding) for e in ground._lifted.effects if e.add}
            needed = (needed - adds) | set(pre)
        return frozenset(needed)
