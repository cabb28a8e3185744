"""The terms a knowledge base speaks: its domain's declarations and the text forms of
atoms, goals and values.

:class:`DomainTerms` is what :class:`~plan_bridge.pddl.knowledge.KnowledgeBase` needs of
its PDDL domain (types, constants, predicates, functions, action names), read by the
front end without unified-planning. :func:`goal_atoms`, :func:`value_assignments` and
:func:`function_atom` read the text forms the ROS services and the PlanSys2 import
receive (``"(and (robot_at leia kitchen))"``, ``"(= (battery leia) 100)"``), bounded
in size and nesting; anything but a conjunction of ground atoms is refused with a
:class:`KnowledgeError` that says what is allowed.
"""

from __future__ import annotations

import difflib
import math
import re
import warnings
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from decimal import Decimal
from typing import Any, Literal

from plan_bridge.errors import FactError
from plan_bridge.pddl.checks import Usage, check_domain
from plan_bridge.pddl.diagnostics import Diagnostics
from plan_bridge.pddl.model import read_domain
from plan_bridge.pddl.source import SourceText, check_source, decode_source
from plan_bridge.pddl.task import (
    Fact,
    FactLike,
    Parameter,
    PlanningTask,
    PredicateSchema,
    format_fact,
    parse_fact,
)

__all__ = [
    "DomainTerms",
    "KnowledgeError",
    "function_atom",
    "goal_atoms",
    "value_assignments",
]

#: The longest text a goal, fact or value may be given as (characters), and its nesting.
MAX_TEXT = 100_000
MAX_DEPTH = 32
#: The function of action costs: a problem of a domain that declares it starts it at 0
#: and minimises it.
COST_FLUENT = "total-cost"
#: A PDDL name unified-planning reads (lower case), and the words no object may be called.
NAME = re.compile(r"[a-z][a-z0-9_-]*\Z")
RESERVED = frozenset(
    {"and", "or", "not", "imply", "exists", "forall", "when", "either", "object", "number"}
)
NAME_RULE = (
    "a PDDL name starts with a letter and has only letters, digits, '-' and '_' "
    "(and is not a keyword such as and, not, object)"
)
_NOT_ATOMS = frozenset(
    {"not", "or", "imply", "exists", "forall", "when", "=", "<", ">", "<=", ">="}
)
Sexp = str | list["Sexp"]


class KnowledgeError(FactError):
    """A change the knowledge base refuses: what is wrong and what is allowed.

    A :class:`~plan_bridge.errors.FactError` (so a ``ValueError``): the operator API
    and the ROS services answer it as a refusal.
    """


@dataclass(frozen=True)
class DomainTerms:
    """What a knowledge base needs of its domain (names in lower case)."""

    name: str
    text: str
    path: str
    types: Mapping[str, str]
    """Type -> its parent type (``object`` is the root and not listed)."""
    constants: Mapping[str, str]
    predicates: Mapping[str, PredicateSchema]
    functions: Mapping[str, PredicateSchema]
    actions: frozenset[str]

    @classmethod
    def read(cls, source: SourceText) -> DomainTerms:
        check_source(source)
        diagnostics = Diagnostics()
        model = read_domain(source, diagnostics)
        check_domain(model, diagnostics, Usage())
        diagnostics.raise_errors()

        def schemas(table: Mapping[str, Any]) -> dict[str, PredicateSchema]:
            return {
                name.lower(): PredicateSchema(
                    name.lower(),
                    tuple(Parameter(p.name.lstrip("?").lower(), p.type.lower()) for p in s.params),
                )
                for name, s in table.items()
            }

        return cls(
            name=model.name.lower(),
            text=source.text,
            path=source.path,
            types={n.lower(): e.type.lower() for n, e in model.types.items() if n != "object"},
            constants={n.lower(): e.type.lower() for n, e in model.constants.items()},
            predicates=schemas(model.predicates),
            functions=schemas(model.functions),
            actions=frozenset(a.name.lower() for a in model.actions),
        )

    @classmethod
    def of_task(cls, task: PlanningTask) -> DomainTerms:
        """The domain of ``task``: the text it was read from, or for a problem built in
        code the domain as UP's writer writes it."""
        text = task.domain_text
        if text is None:
            from unified_planning.io import PDDLWriter  # type: ignore[import-untyped]

            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                text = str(PDDLWriter(task.problem).get_domain())
        path = str(task.domain_path or "<domain>")
        return cls.read(decode_source(text.encode("utf-8"), path, "domain"))

    def is_a(self, kind: str, wanted: str) -> bool:
        """Whether type ``kind`` is ``wanted`` or one of its subtypes."""
        if wanted == "object":
            return True
        seen: set[str] = set()
        while kind not in seen:
            if kind == wanted:
                return True
            seen.add(kind)
            parent = self.types.get(kind)
            if parent is None:
                return False
            kind = parent
        return False

    def check_atom(
        self, atom: Fact, kind: Literal["predicate", "function"], instances: Mapping[str, str]
    ) -> Fact:
        """``atom`` if it fits a predicate (or function) and the objects (the constants
        and ``instances``); else :class:`KnowledgeError` naming what is wrong."""
        domain = self
        table = domain.predicates if kind == "predicate" else domain.functions
        name, args = atom[0], atom[1:]
        schema = table.get(name)
        if schema is None:
            other = domain.functions if kind == "predicate" else domain.predicates
            if name in other:
                how = (
                    f"give it a value: (= {format_fact(atom)} 10)"
                    if kind == "predicate"
                    else "add it as a fact"
                )
                other_kind = "function" if kind == "predicate" else "predicate"
                raise KnowledgeError(
                    f"{format_fact(atom)}: {name!r} is a {other_kind}, not a {kind}; {how}"
                )
            raise KnowledgeError(
                f"{format_fact(atom)}: unknown {kind} {name!r}{guess(name, table)}; "
                f"{kind}s of domain {domain.name}: {listing(table)}"
            )
        if len(args) != schema.arity:
            raise KnowledgeError(
                f"{format_fact(atom)}: {name} takes {schema.arity} argument(s), got "
                f"{len(args)}; signature: {signature(schema)}"
            )
        objects = {**domain.constants, **instances}
        for arg, parameter in zip(args, schema.parameters, strict=True):
            kind_of_arg = objects.get(arg)
            fitting = [o for o, t in objects.items() if domain.is_a(t, parameter.type)]
            if kind_of_arg is None:
                raise KnowledgeError(
                    f"{format_fact(atom)}: unknown object {arg!r}"
                    f"{guess(arg, fitting) or guess(arg, objects)}; objects of type "
                    f"{parameter.type}: {listing(fitting)} (add it first as an instance: "
                    f"{arg} - {parameter.type})"
                )
            if not domain.is_a(kind_of_arg, parameter.type):
                raise KnowledgeError(
                    f"{format_fact(atom)}: {arg!r} is {article(kind_of_arg)}, but ?{parameter.name} "
                    f"of {name} takes {article(parameter.type)}; objects of type {parameter.type}: "
                    f"{listing(fitting)}"
                )
        return atom

    def check_instance(self, name: str, kind: str, instances: Mapping[str, str]) -> None:
        """Refuse a new object ``name`` of type ``kind`` that the domain does not allow."""
        domain = self
        if not NAME.match(name) or name in RESERVED:
            raise KnowledgeError(f"instance name {name!r}: {NAME_RULE}")
        if name in domain.constants:
            raise KnowledgeError(
                f"{name!r} is a constant of domain {domain.name} (type "
                f"{domain.constants[name]}): it is an object of every problem already"
            )
        for what, names in (
            ("predicate", domain.predicates),
            ("function", domain.functions),
            ("action", domain.actions),
        ):
            if name in names:
                raise KnowledgeError(
                    f"instance name {name!r} is the name of {article(what)} of domain {domain.name}; "
                    "the unified-planning reader needs distinct names: choose another"
                )
        if kind != "object" and kind not in domain.types:
            declared = ["object", *domain.types]
            raise KnowledgeError(
                f"instance {name} - {kind}: unknown type {kind!r}{guess(kind, declared)}; "
                f"types of domain {domain.name}: {listing(declared)}"
            )
        known = instances.get(name)
        if known is not None and known != kind:
            raise KnowledgeError(
                f"instance {name!r} is {article(known)} already; remove it first to make it {article(kind)}"
            )


_TOKEN = re.compile(r"\(|\)|[^\s()]+")


def _read_forms(text: str, what: str) -> list[Sexp]:
    """The parenthesised forms of ``text`` (words lower-cased)."""
    if len(text) > MAX_TEXT:
        raise KnowledgeError(f"{what} is longer than {MAX_TEXT} characters")
    shown = text.strip() if len(text) <= 200 else text.strip()[:200] + "..."
    stack: list[list[Sexp]] = [[]]
    for token in _TOKEN.findall(text):
        if token == "(":
            if len(stack) > MAX_DEPTH:
                raise KnowledgeError(f"{what} {shown!r}: nested deeper than {MAX_DEPTH}")
            stack.append([])
        elif token == ")":
            if len(stack) == 1:
                raise KnowledgeError(f"{what} {shown!r}: unbalanced ')'")
            done = stack.pop()
            stack[-1].append(done)
        else:
            stack[-1].append(token.lower())
    if len(stack) != 1:
        raise KnowledgeError(f"{what} {shown!r}: unbalanced '(' (a ')' is missing)")
    return stack[0]


def _ground_atom(form: Sexp, what: str) -> Fact:
    if isinstance(form, str):
        raise KnowledgeError(
            f"{what}: expected an atom in parentheses like (robot_at leia kitchen), found {form!r}"
        )
    if not form:
        raise KnowledgeError(f"{what}: an empty () is not an atom")
    if isinstance(form[0], str) and form[0] in _NOT_ATOMS:
        raise KnowledgeError(
            f"{what}: ({form[0]} ...) is not supported; goals are conjunctions of ground atoms "
            f"like (and (robot_at leia kitchen) (door_open d1))"
        )
    words = [w for w in form if isinstance(w, str)]
    if len(words) != len(form):
        raise KnowledgeError(
            f"{what}: ({words[0] if words else ''} ...) holds a form; "
            f"a ground atom holds names only"
        )
    variables = [w for w in words if w.startswith("?")]
    if variables:
        raise KnowledgeError(f"{what}: {variables[0]} is a variable; atoms here are ground")
    return tuple(words)


def goal_atoms(goal: str | Iterable[FactLike]) -> list[Fact]:
    """The atoms of a goal given as ``"(and (a x) (b y))"``, ``"(a x) (b y)"`` or facts.

    Raises :class:`KnowledgeError` for anything but a conjunction of ground atoms.
    """
    if not isinstance(goal, str):
        return [atom_of(f) for f in goal]
    pending = list(_read_forms(goal, "goal"))
    atoms: list[Fact] = []
    while pending:
        form = pending.pop(0)
        if isinstance(form, list) and form and form[0] == "and":
            pending[:0] = form[1:]
        else:
            atoms.append(_ground_atom(form, f"goal {goal.strip()!r}"))
    return atoms


def value_assignments(text: str) -> list[tuple[Fact, float]]:
    """``"(= (battery leia) 100)"`` (one or more) -> ``[(("battery", "leia"), 100.0)]``."""
    found: list[tuple[Fact, float]] = []
    for form in _read_forms(text, "value"):
        if not (isinstance(form, list) and len(form) == 3 and form[0] == "="):
            raise KnowledgeError(
                f"value {text.strip()!r}: expected (= (function args...) number), "
                f"e.g. (= (battery leia) 100)"
            )
        atom = _ground_atom(form[1], f"value {text.strip()!r}")
        number = form[2]
        try:
            value = float(number) if isinstance(number, str) else math.nan
        except ValueError:
            value = math.nan
        if not math.isfinite(value):
            raise KnowledgeError(
                f"value {text.strip()!r}: {number!r} is not a number; e.g. (= (battery leia) 100)"
            )
        found.append((atom, value))
    if not found:
        raise KnowledgeError("expected (= (function args...) number), e.g. (= (battery leia) 100)")
    return found


def function_atom(text: str) -> Fact:
    """A numeric atom as ``"(battery leia)"``, ``"battery leia"`` or ``"(= (battery leia) 5)"``."""
    forms = _read_forms(text, "function")
    if forms and all(isinstance(f, str) for f in forms):
        return _ground_atom(forms, f"function {text.strip()!r}")
    if len(forms) == 1 and isinstance(forms[0], list) and forms[0][:1] == ["="]:
        return value_assignments(text)[0][0]
    if len(forms) != 1:
        raise KnowledgeError(f"function {text.strip()!r}: expected one atom like (battery leia)")
    return _ground_atom(forms[0], f"function {text.strip()!r}")


# -- helpers -------------------------------------------------------------------------


def atom_of(fact: FactLike) -> Fact:
    try:
        return parse_fact(fact)
    except FactError as exc:
        raise KnowledgeError(str(exc)) from None


def finite_number(atom: FactLike, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise KnowledgeError(f"{atom}: the value {value!r} is not a finite number")
    return float(value)


def number_text(value: float) -> str:
    if value.is_integer() and abs(value) < 1e15:
        return str(int(value))
    return format(Decimal(repr(value)), "f")


def conjunction(atoms: Sequence[Fact]) -> str:
    return "(and" + "".join(" " + format_fact(a) for a in atoms) + ")"


def signature(schema: PredicateSchema) -> str:
    return (
        "(" + " ".join([schema.name, *(f"?{p.name} - {p.type}" for p in schema.parameters)]) + ")"
    )


def article(noun: str) -> str:
    """``an item``, ``a robot``."""
    return ("an " if noun[:1] in "aeiou" else "a ") + noun


def guess(word: str, choices: Iterable[str]) -> str:
    close = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def listing(names: Iterable[str], limit: int = 20) -> str:
    items = list(names)
    if not items:
        return "none"
    more = f", ... ({len(items) - limit} more)" if len(items) > limit else ""
    return ", ".join(items[:limit]) + more


def initial_values(task: PlanningTask) -> dict[Fact, float]:
    """The numeric atoms' initial values of ``task`` (``total-cost`` aside)."""
    values: dict[Fact, float] = {}
    for fluent_exp, value in task.problem.explicit_initial_values.items():
        if fluent_exp.type.is_bool_type() or fluent_exp.fluent().name == COST_FLUENT:
            continue
        if value.is_int_constant() or value.is_real_constant():
            atom = (fluent_exp.fluent().name, *(arg.object().name for arg in fluent_exp.args))
            values[atom] = float(value.constant_value())
    return values
