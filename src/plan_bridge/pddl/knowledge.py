"""A knowledge base: the planning problem under construction, changed while the robot works.

Robotics users keep the problem in a knowledge base that perception and operators
change while the robot works (PlanSys2's problem expert, ROSPlan's knowledge base).
:class:`KnowledgeBase` holds, for one PDDL domain, the problem's instances (objects
and their types), facts (ground atoms of predicates), numeric values (ground atoms
of functions) and goal (a conjunction of ground atoms)::

    kb = KnowledgeBase("domain.pddl")
    kb.add_instance("leia", "robot")
    kb.add_instance("kitchen", "room")
    kb.add_fact("(robot_at leia kitchen)")
    kb.set_value("(battery leia)", 100)
    kb.set_goal("(and (robot_at leia bathroom))")
    text = kb.problem_pddl()      # a PDDL problem UP's reader reads
    task = kb.task()              # a PlanningTask the planners plan

Every change is checked against the domain first: an unknown predicate, function,
type or object, a wrong number of arguments or an object of the wrong type is
refused with a :class:`KnowledgeError` naming it and what is allowed (with "did you
mean" for a near miss); a refused change changes nothing. Removing an instance that
facts, values or goal atoms use is refused unless ``cascade=True``, which removes
them with it (the PlanSys2 import cascades, as PlanSys2's problem expert does).

Each change increments :attr:`KnowledgeBase.version` and is passed to the listeners
(:meth:`KnowledgeBase.add_listener`) as a :class:`KnowledgeChange`, from the changing
thread, after the change. All methods may be called from any thread (ROS callbacks).

The facts and values live in a :class:`FactStore`: its own, or the belief of the
executive that uses it (:meth:`KnowledgeBase.use_facts`): one belief, which skills'
effects and observations and the knowledge base's changes all update.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Iterable, Mapping, Sequence
from collections.abc import Set as AbstractSet
from dataclasses import dataclass
from typing import Any, Literal, Protocol

from plan_bridge.pddl.knowledge_terms import (
    COST_FLUENT,
    NAME,
    NAME_RULE,
    DomainTerms,
    KnowledgeError,
    atom_of,
    conjunction,
    finite_number,
    function_atom,
    goal_atoms,
    guess,
    initial_values,
    listing,
    number_text,
    value_assignments,
)
from plan_bridge.pddl.source import decode_source, read_source
from plan_bridge.pddl.task import (
    Fact,
    FactLike,
    PlanningTask,
    PredicateSchema,
    format_fact,
    load_task_from_text,
)

__all__ = [
    "FactStore",
    "KnowledgeBase",
    "KnowledgeChange",
    "KnowledgeError",
    "function_atom",
    "goal_atoms",
    "value_assignments",
]

ChangeKind = Literal["instance", "fact", "value", "goal", "problem"]


@dataclass(frozen=True)
class KnowledgeChange:
    """One change of a knowledge base, as its listeners receive it."""

    version: int
    """The knowledge base's version after the change."""
    kind: ChangeKind
    """``problem`` is :meth:`KnowledgeBase.clear` (everything at once)."""
    description: str
    """What changed, e.g. ``instance leia - robot added``."""
    source: str = "api"
    """Who changed it: ``api``, ``ros``, ``operator (cli)``, ``commands:12``, ..."""

    @property
    def changes_objects_or_goal(self) -> bool:
        """Whether a task built before the change is out of date (an executive replans)."""
        return self.kind in ("instance", "goal", "problem")

    def __str__(self) -> str:
        return f"{self.description} ({self.source})"


class FactStore(Protocol):
    """Where a knowledge base keeps facts and numeric values: its own store, or an
    executive's belief (:class:`~plan_bridge.belief.Belief`)."""

    @property
    def facts(self) -> AbstractSet[Fact]: ...

    @property
    def values(self) -> Mapping[Fact, float]: ...

    def observe(
        self, observations: Iterable[tuple[Fact, bool | float]]
    ) -> Sequence[tuple[Fact, bool | float]]:
        """Set facts true or false and numeric atoms to numbers; returns what changed."""
        ...

    def forget_values(self, atoms: Iterable[Fact]) -> Sequence[Fact]:
        """Drop numeric atoms' values; returns those that had one."""
        ...


class _OwnFacts:
    """A knowledge base's own facts (used under its lock only)."""

    def __init__(
        self, facts: Iterable[Fact] = (), values: Mapping[Fact, float] | None = None
    ) -> None:
        self._facts = set(facts)
        self._values = dict(values or {})
        self.version = 0

    @property
    def facts(self) -> frozenset[Fact]:
        return frozenset(self._facts)

    @property
    def values(self) -> dict[Fact, float]:
        return dict(self._values)

    def observe(
        self, observations: Iterable[tuple[Fact, bool | float]]
    ) -> list[tuple[Fact, bool | float]]:
        changed: list[tuple[Fact, bool | float]] = []
        for fact, value in observations:
            if not isinstance(value, bool):
                if self._values.get(fact) != value:
                    self._values[fact] = value
                    changed.append((fact, value))
            elif (fact in self._facts) != value:
                (self._facts.add if value else self._facts.discard)(fact)
                changed.append((fact, value))
        self.version += bool(changed)
        return changed

    def forget_values(self, atoms: Iterable[Fact]) -> list[Fact]:
        forgotten = [a for a in dict.fromkeys(atoms) if self._values.pop(a, None) is not None]
        self.version += bool(forgotten)
        return forgotten


class KnowledgeBase:
    """A PDDL problem under construction for one domain (see the module documentation).

    ``domain``: a domain file, or a :class:`PlanningTask` whose domain is used (the
    problem starts empty; :meth:`from_task` starts with the task's problem). ``name``
    is the problem's name in :meth:`problem_pddl`.
    """

    def __init__(self, domain: str | os.PathLike[str] | PlanningTask, *, name: str = "") -> None:
        if isinstance(domain, PlanningTask):
            self._init(DomainTerms.of_task(domain), name or domain.name)
        else:
            self._init(
                DomainTerms.read(read_source(os.fspath(domain), "domain")), name or "problem"
            )

    @classmethod
    def from_text(
        cls, domain_text: str, *, name: str = "problem", domain_name: str = "<domain>"
    ) -> KnowledgeBase:
        """A knowledge base for a domain given as PDDL text (``domain_name`` names it in errors)."""
        kb = cls.__new__(cls)
        source = decode_source(domain_text.encode("utf-8"), domain_name, "domain")
        kb._init(DomainTerms.read(source), name)
        return kb

    @classmethod
    def from_task(
        cls,
        task: PlanningTask,
        *,
        objects: Mapping[str, str] | None = None,
        facts: Iterable[Fact] = (),
        values: Mapping[Fact, float] | None = None,
    ) -> KnowledgeBase:
        """A knowledge base holding ``task``'s problem: its objects (constants aside),
        facts and values (or ``objects``, name -> type, with ``facts`` and ``values``: a
        task view's whole world), and its goal, a conjunction of ground atoms."""
        if not task.goal_is_conjunctive:
            raise KnowledgeError(
                f"the goal of {task.name} is not a conjunction of ground atoms "
                f"({' '.join(task.goal)}); a knowledge base holds such goals only"
            )
        kb = cls(task)
        constants = kb._domain.constants
        named = task.objects if objects is None else objects
        kb._instances = {n: t for n, t in named.items() if n not in constants}
        known = {**constants, **kb._instances}
        kb._store = (
            _OwnFacts(task.initial_facts, initial_values(task))
            if objects is None
            else _OwnFacts(
                (f for f in facts if all(a in known for a in f[1:])),
                {a: v for a, v in (values or {}).items() if all(n in known for n in a[1:])},
            )
        )
        kb._goal = dict.fromkeys(task.goal_facts)
        return kb

    def _init(self, domain: DomainTerms, name: str) -> None:
        name = name.lower()
        if not NAME.match(name):
            raise KnowledgeError(f"problem name {name!r}: {NAME_RULE}")
        self._domain = domain
        self.name = name
        self._lock = threading.RLock()
        self._instances: dict[str, str] = {}
        self._goal: dict[Fact, None] = {}
        self._store: FactStore = _OwnFacts()
        self._version = 0
        self._listeners: list[Callable[[KnowledgeChange], None]] = []
        self._task: tuple[tuple[int, int, object], PlanningTask] | None = None

    # -- what it holds -----------------------------------------------------------------
    @property
    def version(self) -> int:
        """Changes made so far (facts the executive's skills change do not count)."""
        return self._version

    @property
    def domain_name(self) -> str:
        return self._domain.name

    @property
    def domain_text(self) -> str:
        return self._domain.text

    @property
    def types(self) -> dict[str, str]:
        """Type -> parent type (``object`` is the root)."""
        return dict(self._domain.types)

    @property
    def predicates(self) -> dict[str, PredicateSchema]:
        return dict(self._domain.predicates)

    @property
    def functions(self) -> dict[str, PredicateSchema]:
        return dict(self._domain.functions)

    @property
    def constants(self) -> dict[str, str]:
        """The domain's constants: name -> type (they are objects of every problem)."""
        return dict(self._domain.constants)

    @property
    def instances(self) -> dict[str, str]:
        """The problem's objects: name -> type, in the order they were added."""
        with self._lock:
            return dict(self._instances)

    @property
    def objects(self) -> dict[str, str]:
        """Every object facts may name: the constants and the instances."""
        with self._lock:
            return {**self._domain.constants, **self._instances}

    @property
    def facts(self) -> frozenset[Fact]:
        with self._lock:
            return frozenset(self._store.facts)

    @property
    def values(self) -> dict[Fact, float]:
        with self._lock:
            return dict(self._store.values)

    @property
    def goal(self) -> tuple[Fact, ...]:
        """The goal's atoms (their conjunction is the goal; none: the empty goal)."""
        with self._lock:
            return tuple(self._goal)

    def to_json(self) -> dict[str, Any]:
        """Everything it holds, as JSON data (what the ROS ``get`` services return)."""
        with self._lock:
            return {
                "problem": self.name,
                "domain": self._domain.name,
                "version": self._version,
                "instances": dict(self._instances),
                "facts": sorted(format_fact(f) for f in self._store.facts),
                "values": sorted([format_fact(a), v] for a, v in self._store.values.items()),
                "goal": [format_fact(g) for g in self._goal],
            }

    # -- listeners and the fact store --------------------------------------------------
    def add_listener(self, listener: Callable[[KnowledgeChange], None]) -> None:
        """Call ``listener(change)`` after every change (in the changing thread)."""
        with self._lock:
            self._listeners = [*self._listeners, listener]

    def remove_listener(self, listener: Callable[[KnowledgeChange], None]) -> None:
        with self._lock:
            self._listeners = [cb for cb in self._listeners if cb != listener]

    def use_facts(self, store: FactStore | None) -> None:
        """Keep facts and values in ``store`` from now on (an executive's belief: its
        facts become the knowledge base's, the knowledge base's own are dropped);
        ``None``: in a store of its own again, starting with a copy of the current ones."""
        with self._lock:
            if store is None:
                store = _OwnFacts(self._store.facts, self._store.values)
            self._store = store
            self._task = None

    # -- checks ------------------------------------------------------------------------
    def check_fact(self, fact: FactLike) -> Fact:
        """``fact`` normalised, or :class:`KnowledgeError` if it does not fit."""
        with self._lock:
            return self._check(atom_of(fact), "predicate")

    def check_goal(self, goal: str | Iterable[FactLike]) -> list[Fact]:
        """The atoms of ``goal`` (text ``"(and (a x) (b y))"`` or facts), checked."""
        with self._lock:
            return self._check_goal(goal)

    def _check_goal(self, goal: str | Iterable[FactLike]) -> list[Fact]:
        return list(dict.fromkeys(self._check(a, "predicate") for a in goal_atoms(goal)))

    def _check(self, atom: Fact, kind: Literal["predicate", "function"]) -> Fact:
        return self._domain.check_atom(atom, kind, self._instances)

    # -- changes -----------------------------------------------------------------------
    def add_instance(self, name: str, type: str = "object", *, source: str = "api") -> bool:
        """Add the object ``name`` of ``type``; False if it is there already."""
        name, kind = name.strip().lower(), type.strip().lower()
        with self._lock:
            self._domain.check_instance(name, kind, self._instances)
            if name in self._instances:
                return False
            self._instances[name] = kind
            change = self._bump("instance", f"instance {name} - {kind} added", source)
        self._notify(change)
        return True

    def remove_instance(self, name: str, *, cascade: bool = False, source: str = "api") -> bool:
        """Remove the object ``name``. When facts, values or goal atoms name it:
        refused, or with ``cascade`` removed with it. Always True (it was there)."""
        name = name.strip().lower()
        with self._lock:
            if name in self._domain.constants:
                raise KnowledgeError(f"{name!r} is a constant of domain {self._domain.name}")
            if name not in self._instances:
                raise KnowledgeError(
                    f"no instance {name!r}{guess(name, self._instances)}; instances: "
                    f"{listing(self._instances)}"
                )
            facts = sorted(f for f in self._store.facts if name in f[1:])
            values = sorted(a for a in self._store.values if name in a[1:])
            goal = [g for g in self._goal if name in g[1:]]
            users = [
                f"{len(items)} {what} ({', '.join(format_fact(i) for i in items[:3])}"
                f"{', ...' if len(items) > 3 else ''})"
                for items, what in (
                    (facts, "fact(s)"),
                    (values, "value(s)"),
                    (goal, "goal atom(s)"),
                )
                if items
            ]
            if users and not cascade:
                raise KnowledgeError(
                    f"instance {name!r} is used by {'; '.join(users)}: remove those first, "
                    f"or remove the instance with cascade (they are removed with it)"
                )
            self._store.observe([(f, False) for f in facts])
            self._store.forget_values(values)
            for atom in goal:
                del self._goal[atom]
            del self._instances[name]
            also = f" with {'; '.join(users)}" if users else ""
            change = self._bump("instance", f"instance {name} removed{also}", source)
        self._notify(change)
        return True

    def add_facts(self, facts: Iterable[FactLike], *, source: str = "api") -> list[Fact]:
        """Make ``facts`` true (all checked first); returns those that were not."""
        return self._observe(facts, True, source)

    def add_fact(self, fact: FactLike, *, source: str = "api") -> bool:
        return bool(self._observe([fact], True, source))

    def remove_facts(self, facts: Iterable[FactLike], *, source: str = "api") -> list[Fact]:
        """Make ``facts`` false (all checked first); returns those that were true."""
        return self._observe(facts, False, source)

    def remove_fact(self, fact: FactLike, *, source: str = "api") -> bool:
        return bool(self._observe([fact], False, source))

    def set_values(
        self,
        values: Mapping[FactLike, float] | Iterable[tuple[FactLike, float]],
        *,
        source: str = "api",
    ) -> list[Fact]:
        """Set numeric atoms (``{"(battery leia)": 100}``); returns those that changed."""
        pairs = values.items() if isinstance(values, Mapping) else values
        with self._lock:
            checked = [
                (self._check(atom_of(atom), "function"), finite_number(atom, value))
                for atom, value in pairs
            ]
            changed = self._store.observe(checked)
            if not changed:
                return []
            shown = ", ".join(f"{format_fact(a)} = {number_text(float(v))}" for a, v in changed)
            change = self._bump("value", f"values set: {shown}", source)
        self._notify(change)
        return [atom for atom, _ in changed]

    def set_value(self, atom: FactLike, value: float, *, source: str = "api") -> bool:
        return bool(self.set_values([(atom, value)], source=source))

    def remove_values(self, atoms: Iterable[FactLike], *, source: str = "api") -> list[Fact]:
        """Forget numeric atoms' values; returns those that had one."""
        with self._lock:
            checked = [self._check(atom_of(a), "function") for a in atoms]
            forgotten = list(self._store.forget_values(checked))
            if not forgotten:
                return []
            shown = " ".join(format_fact(a) for a in forgotten)
            change = self._bump("value", f"values removed: {shown}", source)
        self._notify(change)
        return forgotten

    def remove_value(self, atom: FactLike, *, source: str = "api") -> bool:
        return bool(self.remove_values([atom], source=source))

    def set_goal(self, goal: str | Iterable[FactLike], *, source: str = "api") -> bool:
        """Make the goal the conjunction of ``goal``'s atoms (``"(and (a x) (b y))"``,
        ``"(a x)"`` or facts; ``"(and)"`` or none: the empty goal). False if unchanged."""
        with self._lock:
            atoms = self._check_goal(goal)
            if atoms == list(self._goal):
                return False
            self._goal = dict.fromkeys(atoms)
            change = self._bump("goal", f"goal set to {conjunction(atoms)}", source)
        self._notify(change)
        return True

    def add_goal(self, goal: str | Iterable[FactLike], *, source: str = "api") -> list[Fact]:
        """Add atoms to the goal's conjunction; returns those that were not in it."""
        with self._lock:
            added = [a for a in self._check_goal(goal) if a not in self._goal]
            if not added:
                return []
            self._goal.update(dict.fromkeys(added))
            shown = " ".join(format_fact(a) for a in added)
            change = self._bump("goal", f"goal atoms added: {shown}", source)
        self._notify(change)
        return added

    def remove_goal(self, goal: str | Iterable[FactLike], *, source: str = "api") -> list[Fact]:
        """Remove atoms from the goal; returns those that were in it."""
        with self._lock:
            removed = [a for a in self._check_goal(goal) if a in self._goal]
            if not removed:
                return []
            for atom in removed:
                del self._goal[atom]
            shown = " ".join(format_fact(a) for a in removed)
            change = self._bump("goal", f"goal atoms removed: {shown}", source)
        self._notify(change)
        return removed

    def clear_goal(self, *, source: str = "api") -> bool:
        """The empty goal; False if it was empty."""
        return self.set_goal([], source=source)

    def clear(self, *, source: str = "api") -> bool:
        """Remove every instance, fact, value and goal atom; False if there was none."""
        with self._lock:
            facts, values = self._store.facts, self._store.values
            if not (self._instances or facts or values or self._goal):
                return False
            self._store.observe([(f, False) for f in facts])
            self._store.forget_values(list(values))
            self._instances, self._goal = {}, {}
            change = self._bump("problem", "problem cleared", source)
        self._notify(change)
        return True

    def _observe(self, facts: Iterable[FactLike], truth: bool, source: str) -> list[Fact]:
        with self._lock:
            checked = [self._check(atom_of(f), "predicate") for f in facts]
            changed = [f for f, _ in self._store.observe([(f, truth) for f in checked])]
            if not changed:
                return []
            verb = "facts added" if truth else "facts removed"
            change = self._bump("fact", f"{verb}: {' '.join(map(format_fact, changed))}", source)
        self._notify(change)
        return changed

    def _bump(self, kind: ChangeKind, description: str, source: str) -> KnowledgeChange:
        self._version += 1
        self._task = None
        return KnowledgeChange(self._version, kind, description, source)

    def _notify(self, change: KnowledgeChange) -> None:
        for listener in self._listeners:  # a copy-on-write list
            listener(change)

    # -- the problem -------------------------------------------------------------------
    def problem_pddl(self, *, comment: str = "") -> str:
        """The problem as PDDL text (ends with a newline). Facts and values are sorted;
        a domain with action costs gets ``(= (total-cost) 0)`` and ``(:metric
        minimize (total-cost))``."""
        with self._lock:
            return self._problem_text(comment)

    def _problem_text(self, comment: str) -> str:
        domain = self._domain
        by_type: dict[str, list[str]] = {}
        for name, kind in self._instances.items():
            by_type.setdefault(kind, []).append(name)
        untyped = not domain.types and set(by_type) <= {"object"}
        objects = [
            " ".join(names) + ("" if untyped else f" - {kind}") for kind, names in by_type.items()
        ]
        values = dict(self._store.values)
        cost = domain.functions.get(COST_FLUENT)
        costs = cost is not None and cost.arity == 0
        if costs:
            values.setdefault((COST_FLUENT,), 0.0)
        init = [format_fact(f) for f in sorted(self._store.facts)]
        init += [f"(= {format_fact(a)} {number_text(v)})" for a, v in sorted(values.items())]
        lines = [f"; {line}" for line in comment.splitlines()]
        lines += [f"(define (problem {self.name})", f"  (:domain {domain.name})"]
        for head, items, close in (
            ("(:objects", objects, ")"),
            ("(:init", init, ")"),
            ("(:goal (and", [format_fact(g) for g in self._goal], "))"),
        ):
            lines += [f"  {head}", *(f"    {item}" for item in items), f"  {close}"]
        if costs:
            lines.append(f"  (:metric minimize ({COST_FLUENT}))")
        return "\n".join([*lines, ")"]) + "\n"

    def task(self) -> PlanningTask:
        """The problem as a :class:`PlanningTask` (parsed by unified-planning; kept
        until the knowledge base or its fact store changes)."""
        with self._lock:
            key = (self._version, id(self._store), getattr(self._store, "version", None))
            if self._task is not None and self._task[0] == key:
                return self._task[1]
            text = self._problem_text("")
        task = load_task_from_text(
            self._domain.text,
            text,
            domain_name=self._domain.path,
            problem_name=f"<knowledge base {self.name}>",
        )
        with self._lock:
            if self._version == key[0]:
                self._task = (key, task)
        return task

    def describes(self, task: PlanningTask) -> bool:
        """Whether ``task`` has this problem's objects and goal (its initial state aside)."""
        with self._lock:
            objects = {**self._domain.constants, **self._instances}
            goal = set(self._goal)
        return (
            task.goal_is_conjunctive
            and dict(task.objects) == objects
            and set(task.goal_facts) == goal
        )

    def __repr__(self) -> str:
        with self._lock:
            return (
                f"KnowledgeBase({self.name} of {self._domain.name}: {len(self._instances)} "
                f"instances, {len(self._store.facts)} facts, {len(self._goal)} goal atoms, "
                f"version {self._version})"
            )
