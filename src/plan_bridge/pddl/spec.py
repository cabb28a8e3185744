"""Problems built in memory: objects, initial state and goal of a known domain.

A :class:`ProblemSpec` is what plan_bridge generates itself (the task of a map,
:mod:`plan_bridge.maps.tasks`): a domain's PDDL text with typed objects, true
initial atoms, numeric initial values and goal atoms, as plain data. It never goes
through unified-planning's PDDL reader, which is slow on large problems (pyparsing:
10 s for a 1,500-line problem):

* :meth:`ProblemSpec.build` makes the unified-planning ``Problem`` with UP's API, from
  the domain parsed once per process (:func:`domain_problem`, the domain alone is
  small);
* the planner workers get the spec as JSON and build the same problem, or hand
  Kairos the PDDL text :meth:`ProblemSpec.pddl_text` writes (Kairos parses it
  natively in well under a millisecond);
* ``plan-bridge problem`` and the journal show :meth:`ProblemSpec.pddl_text`.
"""

from __future__ import annotations

import hashlib
import json
import re
import threading
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

from plan_bridge.pddl.up_runtime import ensure_unified_planning

__all__ = [
    "ProblemSpec",
    "domain_name_of",
    "domain_problem",
    "format_number",
    "without_actions",
]

Fact = tuple[str, ...]
_DOMAIN_NAME = re.compile(r"\(\s*define\s*\(\s*domain\s+([^\s()]+)", re.IGNORECASE)


def domain_name_of(domain_text: str) -> str:
    """The name a PDDL domain text declares (``(define (domain NAME) ...``)."""
    match = _DOMAIN_NAME.search(domain_text)
    if match is None:
        raise ValueError("not a PDDL domain: no (define (domain NAME) ...)")
    return match.group(1).lower()


def without_actions(domain_text: str, names: Iterable[str]) -> str:
    """``domain_text`` with the actions ``names`` (``(:action NAME ...)`` or
    ``(:durative-action NAME ...)``) left out: a task that cannot use an action plans
    faster without it (a planner grounds every action over every object).

    Raises ``ValueError`` naming an action the domain does not have.
    """
    text = domain_text
    for name in names:
        found = re.search(
            rf"\(\s*:(?:durative-)?action\s+{re.escape(name)}(?=[\s()])", text, re.IGNORECASE
        )
        if found is None:
            raise ValueError(f"the domain has no action {name!r} to leave out")
        depth, end = 0, found.start()
        for end in range(found.start(), len(text)):
            if text[end] == "(":
                depth += 1
            elif text[end] == ")":
                depth -= 1
                if depth == 0:
                    break
        text = text[: found.start()] + text[end + 1 :]
    return text


def format_number(value: float) -> str:
    """A number as PDDL text: ``3``, ``2.5`` (three decimals at most)."""
    return f"{round(float(value), 3):g}"


@dataclass(frozen=True)
class ProblemSpec:
    """A problem of a domain, as data (see the module's doc). Names are lower case."""

    domain: str
    """The domain's PDDL text."""
    name: str
    objects: tuple[tuple[str, str], ...]
    """(name, type) of every object, in order."""
    init: tuple[Fact, ...]
    """The true boolean atoms of the initial state (closed world)."""
    values: tuple[tuple[Fact, float], ...]
    """The numeric atoms' initial values."""
    goal: tuple[Fact, ...]
    """The goal: the conjunction of these atoms."""
    comment: str = field(default="", compare=False)
    """A line for the top of :meth:`pddl_text` (where the problem comes from)."""
    search: str = ""
    """The Kairos search preset that suits problems of this kind, tried first (see
    :mod:`plan_bridge.planning.kairos_direct`); "" for Kairos' own choice."""
    makespan_metric: bool = False
    """The problem's metric: minimise the makespan (``total-time``)."""
    improve_s: float = 0.0
    """With the metric: Kairos improves its first plan until this many seconds pass
    without a better one (0: the first plan, as without a metric)."""

    @cached_property
    def key(self) -> str:
        """A hash of the whole problem: planner workers keep built problems under it."""
        digest = hashlib.sha256()
        digest.update(self.domain.encode("utf-8"))
        digest.update(b"\0")
        digest.update(json.dumps(self.to_json(), sort_keys=True).encode("utf-8"))
        return digest.hexdigest()[:32]

    @cached_property
    def domain_name(self) -> str:
        return domain_name_of(self.domain)

    def to_json(self) -> dict[str, Any]:
        """The problem as JSON data (the domain text left out)."""
        return {
            "name": self.name,
            "search": self.search,
            "makespan_metric": self.makespan_metric,
            "improve_s": self.improve_s,
            "objects": [list(pair) for pair in self.objects],
            "init": [list(atom) for atom in self.init],
            "values": [[*atom, value] for atom, value in self.values],
            "goal": [list(atom) for atom in self.goal],
        }

    @classmethod
    def from_json(cls, domain: str, data: Mapping[str, Any]) -> ProblemSpec:
        return cls(
            domain,
            str(data["name"]),
            tuple((str(a), str(b)) for a, b in data["objects"]),
            tuple(tuple(str(w) for w in atom) for atom in data["init"]),
            tuple(
                (tuple(str(w) for w in entry[:-1]), float(entry[-1])) for entry in data["values"]
            ),
            tuple(tuple(str(w) for w in atom) for atom in data["goal"]),
            search=str(data.get("search", "")),
            makespan_metric=bool(data.get("makespan_metric", False)),
            improve_s=float(data.get("improve_s", 0.0)),
        )

    def with_state(
        self,
        init: Iterable[Fact] | None = None,
        values: Mapping[Fact, float] | None = None,
        goal: Iterable[Fact] | None = None,
    ) -> ProblemSpec:
        """A copy with another initial state (``values`` update the numbers) or goal."""
        numbers = dict(self.values)
        if values:
            numbers.update(values)
        return ProblemSpec(
            self.domain,
            self.name,
            self.objects,
            self.init if init is None else tuple(sorted(set(init))),
            tuple(sorted(numbers.items())),
            self.goal if goal is None else tuple(goal),
            self.comment,
            self.search,
            self.makespan_metric,
            self.improve_s,
        )

    # -- text ----------------------------------------------------------------------
    def pddl_text(self) -> str:
        """The problem in PDDL (objects grouped by type, one atom per line)."""
        by_type: dict[str, list[str]] = {}
        for name, kind in self.objects:
            by_type.setdefault(kind, []).append(name)
        objects = "\n    ".join(f"{' '.join(names)} - {kind}" for kind, names in by_type.items())
        facts = [_atom(a) for a in self.init]
        numbers = [f"(= {_atom(a)} {format_number(v)})" for a, v in self.values]
        init = "\n    ".join([*facts, *numbers])
        goal = " ".join(_atom(a) for a in self.goal)
        head = f"; {self.comment}\n" if self.comment else ""
        metric = "\n  (:metric minimize (total-time))" if self.makespan_metric else ""
        return (
            f"{head}(define (problem {self.name})\n"
            f"  (:domain {self.domain_name})\n"
            f"  (:objects\n    {objects})\n"
            f"  (:init\n    {init})\n"
            f"  (:goal (and {goal})){metric})\n"
        )

    # -- unified-planning ------------------------------------------------------------
    def build(self) -> Any:
        """The unified-planning ``Problem`` (built with UP's API, nothing parsed but
        the domain, once per process)."""
        from fractions import Fraction

        from unified_planning.model import Object  # type: ignore[import-untyped]

        problem = domain_problem(self.domain).clone()
        problem.name = self.name
        objects = {}
        for name, kind in self.objects:
            objects[name] = Object(name, problem.user_type(kind), problem.environment)
        problem.add_objects(list(objects.values()))
        fluents: dict[str, Any] = {}

        def expression(atom: Fact) -> Any:
            fluent = fluents.get(atom[0])
            if fluent is None:
                fluent = fluents[atom[0]] = problem.fluent(atom[0])
            return fluent(*(objects[arg] for arg in atom[1:]))

        for atom in self.init:
            problem.set_initial_value(expression(atom), True)
        for atom, value in self.values:
            exp = expression(atom)
            number: int | Fraction
            if exp.type.is_int_type() or float(value).is_integer():
                number = round(value)
            else:
                number = Fraction(format_number(value))
            problem.set_initial_value(exp, number)
        for atom in self.goal:
            problem.add_goal(expression(atom))
        if self.makespan_metric:
            from unified_planning.model.metrics import MinimizeMakespan  # type: ignore[import-untyped]

            problem.add_quality_metric(MinimizeMakespan(environment=problem.environment))
        return problem


def _atom(atom: Fact) -> str:
    return "(" + " ".join(atom) + ")"


_domains: dict[str, Any] = {}
_domains_lock = threading.Lock()


def domain_problem(domain_text: str) -> Any:
    """The unified-planning problem of a domain alone (no objects), parsed once per
    process and domain text; clone it before changing it."""
    key = hashlib.sha256(domain_text.encode("utf-8")).hexdigest()
    with _domains_lock:
        cached = _domains.get(key)
        if cached is not None:
            return cached
        ensure_unified_planning()
        import warnings

        from unified_planning.io import PDDLReader  # type: ignore[import-untyped]

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            problem = PDDLReader().parse_problem_string(domain_text)
        _domains[key] = problem
        return problem
