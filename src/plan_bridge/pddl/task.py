"""Loading PDDL into a :class:`PlanningTask` and explaining why it failed.

A :class:`PlanningTask` wraps a unified-planning ``Problem`` (parsed from PDDL or
built in code) together with plain-Python views of it -- action signatures,
predicates, objects, initial facts, goal atoms -- so that the rest of plan_bridge
(skills, belief state, executive) never has to touch UP expression trees.

Ground facts are tuples of lower-case names, ``("at", "robot", "kitchen")``; the
string form ``"(at robot kitchen)"`` is accepted wherever a fact is expected.
PDDL is case-insensitive and UP lower-cases everything it reads, so names are
compared in lower case.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

from plan_bridge.errors import FactError
from plan_bridge.pddl.front_end import FrontEnd, analyse, parse_with_up
from plan_bridge.pddl.restate import replace_init
from plan_bridge.pddl.source import (
    DEFAULT_MAX_BYTES,
    DEFAULT_MAX_DEPTH,
    ProblemText,
    SourceText,
    check_source,
    decode_source,
    read_source,
)
from plan_bridge.pddl.spec import ProblemSpec
from plan_bridge.pddl.up_runtime import ensure_unified_planning

__all__ = [
    "ActionSchema",
    "Fact",
    "FactLike",
    "Parameter",
    "PlanningTask",
    "PredicateSchema",
    "format_fact",
    "load_task",
    "load_task_from_text",
    "parse_fact",
    "task_from_problem",
    "task_from_spec",
]


class Primer(Protocol):
    """Something that starts parsing a problem's text elsewhere while we parse it
    here (:meth:`plan_bridge.planning.worker.WorkerPool.prime`)."""

    def prime(self, base: ProblemText) -> None: ...

    def warm_up(self, count: int = 1) -> None: ...


Fact = tuple[str, ...]
"""A ground atom: predicate name followed by object names, all lower case."""

FactLike = str | Sequence[str]
"""A :data:`Fact` or its PDDL text form ``"(at robot kitchen)"``."""

_FACT_TEXT = re.compile(r"^\s*\(\s*([^()\s]+(?:\s+[^()\s]+)*)\s*\)\s*$")


def parse_fact(fact: FactLike) -> Fact:
    """Normalise ``"(at r k)"``, ``["at", "r", "k"]`` or ``("at", "r", "k")`` to a Fact."""
    if isinstance(fact, str):
        match = _FACT_TEXT.match(fact)
        if match is None:
            raise FactError(f"not a ground atom: {fact!r}; expected e.g. '(at robot kitchen)'")
        return tuple(match.group(1).lower().split())
    parts = tuple(str(part).lower() for part in fact)
    if not parts or any(not part or part.isspace() for part in parts):
        raise FactError(f"not a ground atom: {fact!r}; expected e.g. ('at', 'robot', 'kitchen')")
    return parts


def format_fact(fact: Sequence[str]) -> str:
    """``("at", "r", "k")`` -> ``"(at r k)"``."""
    return "(" + " ".join(fact) + ")"


@dataclass(frozen=True)
class Parameter:
    """A typed parameter of an action or predicate."""

    name: str
    type: str


@dataclass(frozen=True)
class _Schema:
    """A name with typed parameters."""

    name: str
    parameters: tuple[Parameter, ...]

    @property
    def arity(self) -> int:
        return len(self.parameters)


@dataclass(frozen=True)
class ActionSchema(_Schema):
    """A lifted action: its name and typed parameters."""

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.parameters)


@dataclass(frozen=True)
class PredicateSchema(_Schema):
    """A boolean fluent (PDDL predicate) and its typed parameters."""


class _StepLike(Protocol):
    @property
    def action(self) -> str: ...

    @property
    def arguments(self) -> tuple[str, ...]: ...


@dataclass(frozen=True, eq=False)
class PlanningTask:
    """A planning problem plus plain-Python views of it.

    ``problem`` is the unified-planning ``Problem``; treat it as read-only (use
    :meth:`with_initial_state` to derive a task with another initial state).
    """

    problem: Any
    domain_path: Path | None
    problem_path: Path | None
    actions: Mapping[str, ActionSchema]
    predicates: Mapping[str, PredicateSchema]
    functions: Mapping[str, PredicateSchema]
    objects: Mapping[str, str]
    """Object name -> type name."""
    initial_facts: frozenset[Fact]
    goal_facts: tuple[Fact, ...]
    """The positive ground atoms of the goal conjunction."""
    goal_is_conjunctive: bool
    """False when the goal holds more than a conjunction of positive atoms."""
    warnings: tuple[str, ...] = ()
    type_ancestors: Mapping[str, frozenset[str]] = field(default_factory=dict)
    """Type name -> the type and all its supertypes."""
    domain_text: str | None = None
    """The PDDL domain text, when the task was loaded from PDDL."""
    problem_text: str | None = None
    """The PDDL problem text (with the current initial state), when loaded from PDDL."""
    spec: ProblemSpec | None = None
    """The problem as data, when plan_bridge built it (:func:`task_from_spec`): it
    travels to the planners as such, never through a PDDL reader."""

    @property
    def pddl_problem(self) -> str | None:
        """The problem's PDDL text: the text read, or the one a spec writes."""
        if self.problem_text is not None:
            return self.problem_text
        return self.spec.pddl_text() if self.spec is not None else None

    @property
    def name(self) -> str:
        return str(self.problem.name)

    @property
    def goal(self) -> tuple[str, ...]:
        """The goal expressions as text (UP syntax)."""
        return tuple(str(goal) for goal in self.problem.goals)

    def objects_of_type(self, type_name: str) -> tuple[str, ...]:
        return tuple(
            name
            for name, kind in self.objects.items()
            if type_name in self.type_ancestors.get(kind, frozenset({kind}))
        )

    # -- facts -----------------------------------------------------------------
    def check_fact(self, fact: FactLike) -> Fact:
        """Normalise ``fact`` and check predicate, arity, objects and types.

        Raises :class:`FactError` naming what is wrong and what is allowed.
        """
        atom = parse_fact(fact)
        name, args = atom[0], atom[1:]
        schema = self.predicates.get(name)
        if schema is None:
            raise FactError(
                f"{format_fact(atom)}: unknown predicate {name!r}; "
                f"predicates: {', '.join(sorted(self.predicates)) or 'none'}"
            )
        if len(args) != schema.arity:
            signature = " ".join(f"?{p.name} - {p.type}" for p in schema.parameters)
            raise FactError(
                f"{format_fact(atom)}: {name} takes {schema.arity} argument(s), got "
                f"{len(args)}; signature: ({name} {signature})"
            )
        for arg, parameter in zip(args, schema.parameters, strict=True):
            kind = self.objects.get(arg)
            if kind is None:
                raise FactError(
                    f"{format_fact(atom)}: unknown object {arg!r}; objects: "
                    f"{', '.join(sorted(self.objects)) or 'none'}"
                )
            if parameter.type not in self.type_ancestors.get(kind, frozenset({kind})):
                raise FactError(
                    f"{format_fact(atom)}: object {arg!r} has type {kind!r}, but "
                    f"?{parameter.name} of {name} needs type {parameter.type!r}"
                )
        return atom

    def with_initial_state(self, facts: Iterable[FactLike]) -> PlanningTask:
        """A copy of this task whose initial state is exactly ``facts`` (closed world).

        Numeric fluents (e.g. action costs) keep their values. Raises
        :class:`FactError` for a fact that does not fit the task.
        """
        new_facts = frozenset(self.check_fact(fact) for fact in facts)
        ensure_unified_planning()
        problem = self.problem.clone()
        for fluent_exp, value in list(problem.explicit_initial_values.items()):
            if fluent_exp.type.is_bool_type() and value.is_true():
                problem.set_initial_value(fluent_exp, False)
        for atom in new_facts:
            fluent = problem.fluent(atom[0])
            problem.set_initial_value(fluent(*(problem.object(arg) for arg in atom[1:])), True)
        problem_text = None
        spec = None if self.spec is None else self.spec.with_state(init=new_facts)
        if self.problem_text is not None:
            # Rewriting the (:init ...) of the original text keeps every name as it
            # was; UP's PDDLWriter would take seconds on large problems.
            source = SourceText(self.problem_text, str(self.problem_path or "<problem>"), "problem")
            problem_text = replace_init(source, sorted(new_facts))
        return dataclasses.replace(
            self, problem=problem, initial_facts=new_facts, problem_text=problem_text, spec=spec
        )

    # -- plans -----------------------------------------------------------------
    def up_plan(self, steps: Iterable[_StepLike]) -> Any:
        """A unified-planning ``SequentialPlan`` for ``steps`` (e.g. for validation)."""
        ensure_unified_planning()
        from unified_planning.plans import (  # type: ignore[import-untyped]
            ActionInstance,
            SequentialPlan,
        )

        problem = self.problem
        return SequentialPlan(
            [
                ActionInstance(
                    problem.action(step.action), [problem.object(a) for a in step.arguments]
                )
                for step in steps
            ]
        )


def load_task(
    domain: str | Path,
    problem: str | Path,
    *,
    max_bytes: int = DEFAULT_MAX_BYTES,
    max_depth: int = DEFAULT_MAX_DEPTH,
    prime: Primer | None = None,
    before_parse: Callable[[], object] | None = None,
) -> PlanningTask:
    """Load a PDDL domain and problem file.

    Raises :class:`PddlError` (or its subclass :class:`UnsupportedFeatureError`)
    with file, line, column and the offending text for anything that cannot be
    loaded; never a parser traceback.

    ``prime``: a planner worker pool (e.g. ``default_pool()``) that starts parsing
    the same text in a planner process while this process parses it, so the first
    solve does not parse again (:meth:`WorkerPool.prime`). Pass it when the task
    will be planned. ``before_parse`` is called once the files passed the cheap
    checks, before unified-planning parses them (the CLI checks the planner name
    there, so an unknown planner is reported before a parse of several seconds).
    """
    domain_source = read_source(domain, "domain", max_bytes=max_bytes)
    check_source(domain_source, max_depth=max_depth)
    problem_source = read_source(problem, "problem", max_bytes=max_bytes)
    check_source(problem_source, max_depth=max_depth)
    return _parsed(domain_source, problem_source, prime, before_parse, Path(domain), Path(problem))


def load_task_from_text(
    domain_text: str,
    problem_text: str,
    *,
    domain_name: str = "<domain>",
    problem_name: str = "<problem>",
    max_depth: int = DEFAULT_MAX_DEPTH,
    prime: Primer | None = None,
    before_parse: Callable[[], object] | None = None,
) -> PlanningTask:
    """Like :func:`load_task` for PDDL held in strings (names are used in errors)."""
    domain_source = decode_source(domain_text.encode("utf-8"), domain_name, "domain")
    check_source(domain_source, max_depth=max_depth)
    problem_source = decode_source(problem_text.encode("utf-8"), problem_name, "problem")
    check_source(problem_source, max_depth=max_depth)
    return _parsed(domain_source, problem_source, prime, before_parse)


def _parsed(
    domain_source: SourceText,
    problem_source: SourceText,
    prime: Primer | None,
    before_parse: Callable[[], object] | None,
    domain_path: Path | None = None,
    problem_path: Path | None = None,
) -> PlanningTask:
    """The task of two checked sources: the front end's verdict, then unified-planning's
    parse of its rewrite."""
    front = analyse(domain_source, problem_source)
    _prime(prime, front)
    if before_parse is not None:
        before_parse()
    up_problem, notes = parse_with_up(front)
    task = task_from_problem(
        up_problem, domain_path=domain_path, problem_path=problem_path, warnings=notes
    )
    return dataclasses.replace(task, domain_text=front.domain_text, problem_text=front.problem_text)


def _prime(pool: Primer | None, front: FrontEnd) -> None:
    # The planner process parses the text UP can read (the front end's rewrite).
    if pool is not None:
        pool.prime(ProblemText.of(front.domain_text, front.problem_text))


def task_from_problem(
    problem: Any,
    *,
    domain_path: Path | None = None,
    problem_path: Path | None = None,
    warnings: Sequence[str] = (),
) -> PlanningTask:
    """Wrap a unified-planning ``Problem`` (e.g. built in code) as a task."""
    ensure_unified_planning()
    from unified_planning.model import Problem  # type: ignore[import-untyped]

    if not isinstance(problem, Problem):
        raise TypeError(f"expected a unified_planning.model.Problem, got {type(problem).__name__}")
    ancestors: dict[str, frozenset[str]] = {}
    for user_type in problem.user_types:
        chain = []
        current = user_type
        while current is not None:
            chain.append(current.name)
            current = current.father
        ancestors[user_type.name] = frozenset(chain)

    actions = {
        action.name: ActionSchema(
            action.name,
            tuple(Parameter(p.name, _type_name(p.type)) for p in action.parameters),
        )
        for action in problem.actions
    }
    predicates: dict[str, PredicateSchema] = {}
    functions: dict[str, PredicateSchema] = {}
    for fluent in problem.fluents:
        schema = PredicateSchema(
            fluent.name, tuple(Parameter(p.name, _type_name(p.type)) for p in fluent.signature)
        )
        (predicates if fluent.type.is_bool_type() else functions)[fluent.name] = schema
    objects = {obj.name: _type_name(obj.type) for obj in problem.all_objects}
    initial = frozenset(
        _fact_of(fluent_exp)
        for fluent_exp, value in problem.explicit_initial_values.items()
        if fluent_exp.type.is_bool_type() and value.is_bool_constant() and value.is_true()
    )
    goal_facts, conjunctive = _goal_atoms(problem.goals)
    return PlanningTask(
        problem=problem,
        domain_path=domain_path,
        problem_path=problem_path,
        actions=actions,
        predicates=predicates,
        functions=functions,
        objects=objects,
        initial_facts=initial,
        goal_facts=tuple(goal_facts),
        goal_is_conjunctive=conjunctive,
        warnings=tuple(warnings),
        type_ancestors=ancestors,
    )


def task_from_spec(spec: ProblemSpec, *, warnings: Sequence[str] = ()) -> PlanningTask:
    """The task of a problem built in memory (:class:`~plan_bridge.pddl.spec.ProblemSpec`):
    its unified-planning problem made with UP's API, no PDDL text read."""
    ensure_unified_planning()
    task = task_from_problem(spec.build(), warnings=warnings)
    return dataclasses.replace(task, domain_text=spec.domain, spec=spec)


def _type_name(up_type: Any) -> str:
    if up_type.is_user_type():
        return str(up_type.name)
    return str(up_type)


def _fact_of(fluent_exp: Any) -> Fact:
    return (fluent_exp.fluent().name, *(arg.object().name for arg in fluent_exp.args))


def _goal_atoms(goals: Iterable[Any]) -> tuple[list[Fact], bool]:
    atoms: list[Fact] = []
    conjunctive = True
    pending = list(goals)
    while pending:
        node = pending.pop(0)
        if node.is_and():
            pending[:0] = list(node.args)
        elif node.is_fluent_exp() and all(arg.is_object_exp() for arg in node.args):
            atoms.append(_fact_of(node))
        elif node.is_true():
            continue
        else:
            conjunctive = False
    return atoms, conjunctive
