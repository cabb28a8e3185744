"""The formula walk: conditions, effects, durations and numeric expressions.

Every atom in a precondition, effect, condition, duration, init, goal or metric is
checked against the declarations collected by :mod:`~plan_bridge.pddl.model`:
predicate or function declared, arity, variables in scope, objects and constants
declared, argument types. Each construct met is classified
(:mod:`~plan_bridge.pddl.features`): unsupported ones are errors naming the feature;
features used are noted in :class:`Usage` (with the place of first use) for
:func:`~plan_bridge.pddl.checks.check_requirements`. Durations below zero are
errors (zero is a warning). The walk records where numeric fluents are read
(:class:`Read`) for :mod:`~plan_bridge.pddl.initial_values`. Split from
:mod:`~plan_bridge.pddl.checks`, which runs it over a domain and a problem.
"""

from __future__ import annotations

import difflib
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field

from plan_bridge.pddl.diagnostics import Diagnostics
from plan_bridge.pddl.features import classify
from plan_bridge.pddl.model import DomainModel, Entry, Signature, typed_list
from plan_bridge.pddl.sexpr import Atom, Form, Node
from plan_bridge.pddl.source import SourceText

__all__ = [
    "CONTINGENT",
    "FormulaContext",
    "Read",
    "Usage",
    "check_atom",
    "check_duration",
    "check_formula",
    "check_numeric",
    "check_types",
    "suggest",
    "unsupported",
]

_COMPARISONS = frozenset(["<", ">", "<=", ">="])
_NUMERIC_EFFECTS = frozenset(["increase", "decrease", "assign", "scale-up", "scale-down"])
_ARITHMETIC = frozenset(["+", "-", "*", "/"])
#: Heads of contingent and PDDL3 constructs: unsupported wherever they appear.
CONTINGENT = frozenset(["oneof", "unknown", "probabilistic", "preference"])


@dataclass(frozen=True)
class Read:
    """A numeric fluent read by a condition, effect, duration or goal."""

    args: tuple[Node, ...]
    scope: Mapping[str, str]
    source: SourceText
    offset: int
    reader: str
    guards: tuple[Form, ...] = ()
    """The reading action's static preconditions and inequalities: the instances
    they rule out are never read (a distance between places no road joins)."""


@dataclass
class Usage:
    """Requirement flag -> (source, offset) of its first use; numeric fluents read."""

    first: dict[str, tuple[SourceText, int]] = field(default_factory=dict)
    reads: dict[str, list[Read]] = field(default_factory=dict)
    """Function name -> where conditions, effects, durations and the goal read it."""

    def note(self, flag: str, source: SourceText, offset: int) -> None:
        self.first.setdefault(flag, (source, offset))


@dataclass
class FormulaContext:
    domain: DomainModel
    source: SourceText
    diags: Diagnostics
    usage: Usage
    names: Mapping[str, Entry]
    """Objects and constants that may appear as arguments."""
    durative: bool = False
    where: str = ""
    reader: str = ""
    """What reads numeric fluents here, for messages: ``the precondition of move``."""
    guards: tuple[Form, ...] = ()
    in_forall_effect: bool = False


def suggest(word: str, choices: Iterable[str]) -> str:
    options = sorted(choices)
    # difflib is quadratic-ish per candidate: on huge problems compare with the
    # names that share the first letter only.
    pool = options if len(options) <= 2000 else [o for o in options if o[:1] == word[:1]][:2000]
    close = difflib.get_close_matches(word, pool, n=1, cutoff=0.6)
    shown = ", ".join(options[:30]) + (" ..." if len(options) > 30 else "")
    guess = f"did you mean {close[0]}? " if close else ""
    return f"{guess}declared: {shown or 'none'}"


def unsupported(ctx: FormulaContext, name: str, offset: int) -> None:
    support = classify(name)
    text = support.describe() if support else f"{name} is not supported"
    ctx.diags.error(ctx.source, offset, f"unsupported PDDL construct: {text}", feature=name)


def check_formula(ctx: FormulaContext, node: Node, scope: Mapping[str, str], mode: str) -> None:
    """``mode``: ``pre`` (condition, goal), ``eff`` (effect)."""
    if isinstance(node, Atom):
        ctx.diags.error(
            ctx.source, node.offset, f"expected a formula (...) in {ctx.where}, found {node.text!r}"
        )
        return
    if node.is_empty:
        return
    head = node.head
    if not head:
        ctx.diags.error(
            ctx.source,
            node.offset,
            f"a formula in {ctx.where} must start with a name or a connective, found '('",
        )
        return
    if head in CONTINGENT or (head == "or" and mode == "eff"):
        unsupported(ctx, head if head != "or" else "oneof", node.offset)
        return
    timing = _timing(node)
    if timing is not None:
        _timed(ctx, node, timing, scope, mode)
        return
    handlers = _CONDITIONS if mode == "pre" else _EFFECTS
    handlers.get(head, _atom_formula)(ctx, node, scope, mode)


def _timing(node: Form) -> tuple[Atom, Form] | None:
    """``start`` and ``F`` of ``(at start F)``; also ``(at end F)``, ``(over all F)``."""
    args = node.items[1:]
    if node.head not in ("at", "over") or len(args) != 2:
        return None
    when, inner = args
    if isinstance(when, Atom) and when.text in ("start", "end", "all") and isinstance(inner, Form):
        return when, inner
    return None


def _timed(
    ctx: FormulaContext,
    node: Form,
    timing: tuple[Atom, Form],
    scope: Mapping[str, str],
    mode: str,
) -> None:
    when, inner = timing
    if not ctx.durative:
        ctx.diags.error(
            ctx.source,
            node.offset,
            f"({node.head} {when.text} ...) is a timed {'effect' if mode == 'eff' else 'condition'}"
            f", but {ctx.where} is not a :durative-action",
            "write the formula without it in an :action, or make the action a "
            "(:durative-action NAME :parameters (...) :duration (= ?duration N) "
            ":condition ... :effect ...)",
        )
        return
    check_formula(ctx, inner, scope, mode)


def _conjunction(ctx: FormulaContext, node: Form, scope: Mapping[str, str], mode: str) -> None:
    for arg in node.items[1:]:
        check_formula(ctx, arg, scope, mode)


def _disjunction(ctx: FormulaContext, node: Form, scope: Mapping[str, str], mode: str) -> None:
    """``or`` and ``imply`` (in a condition: an ``or`` effect is unsupported before)."""
    if mode == "pre":
        ctx.usage.note(":disjunctive-preconditions", ctx.source, node.offset)
    _conjunction(ctx, node, scope, mode)


def _negation(ctx: FormulaContext, node: Form, scope: Mapping[str, str], mode: str) -> None:
    args = node.items[1:]
    if len(args) != 1:
        ctx.diags.error(ctx.source, node.offset, f"(not ...) takes one formula, found {len(args)}")
        return
    inner = args[0]
    if mode == "pre" and not (isinstance(inner, Form) and inner.head == "="):
        ctx.usage.note(":negative-preconditions", ctx.source, node.offset)
    check_formula(ctx, inner, scope, mode)


def _quantifier(ctx: FormulaContext, node: Form, scope: Mapping[str, str], mode: str) -> None:
    """``exists`` and ``forall``, in a condition or an effect."""
    head, args = node.head, node.items[1:]
    if len(args) != 2 or not isinstance(args[0], Form):
        ctx.diags.error(ctx.source, node.offset, f"({head} (?x - type ...) FORMULA) expected")
        return
    if mode == "eff":
        if head == "forall" and ctx.in_forall_effect:
            unsupported(ctx, "nested-forall-effect", node.offset)
            return
        ctx.usage.note(":conditional-effects", ctx.source, node.offset)
    else:
        ctx.usage.note(
            ":existential-preconditions" if head == "exists" else ":universal-preconditions",
            ctx.source,
            node.offset,
        )
    variables, _ = typed_list(
        args[0].items, ctx.source, ctx.diags, f"variables of ({head} ...)", variables=True
    )
    check_types(ctx, variables)
    outer = ctx.in_forall_effect
    ctx.in_forall_effect = outer or (mode == "eff" and head == "forall")
    check_formula(ctx, args[1], {**scope, **{v.name: v.type for v in variables}}, mode)
    ctx.in_forall_effect = outer


def _conditional(ctx: FormulaContext, node: Form, scope: Mapping[str, str], mode: str) -> None:
    """``(when CONDITION EFFECT)``."""
    ctx.usage.note(":conditional-effects", ctx.source, node.offset)
    args = node.items[1:]
    if len(args) != 2:
        ctx.diags.error(ctx.source, node.offset, "(when CONDITION EFFECT) expected")
        return
    check_formula(ctx, args[0], scope, "pre")
    check_formula(ctx, args[1], scope, "eff")


def _equality(ctx: FormulaContext, node: Form, scope: Mapping[str, str], mode: str) -> None:
    """``(= A B)`` of two names or variables, else a numeric comparison."""
    args = node.items[1:]
    if all(isinstance(a, Atom) for a in args) and len(args) == 2:
        ctx.usage.note(":equality", ctx.source, node.offset)
        for arg in args:
            _term(ctx, arg, scope)  # type: ignore[arg-type]
    else:
        _comparison(ctx, node, scope)


def _compare(ctx: FormulaContext, node: Form, scope: Mapping[str, str], mode: str) -> None:
    _comparison(ctx, node, scope)


def _numeric_effect(ctx: FormulaContext, node: Form, scope: Mapping[str, str], mode: str) -> None:
    """``(increase (FUNCTION ...) EXPRESSION)`` and the other numeric effects."""
    head, args = node.head, node.items[1:]
    if len(args) != 2:
        ctx.diags.error(ctx.source, node.offset, f"({head} (FUNCTION ...) EXPRESSION) expected")
        return
    target = args[0]
    cost = isinstance(target, Form) and target.head == "total-cost"
    ctx.usage.note(":action-costs" if cost else ":numeric-fluents", ctx.source, node.offset)
    reader = ctx.reader
    if head == "assign":
        ctx.reader = ""  # the target is written, not read
    check_numeric(ctx, target, scope, note=not cost)
    ctx.reader = reader
    check_numeric(ctx, args[1], scope, note=not cost)


def _atom_formula(ctx: FormulaContext, node: Form, scope: Mapping[str, str], mode: str) -> None:
    check_atom(ctx, node, scope)


_Handler = Callable[[FormulaContext, Form, Mapping[str, str], str], None]
_CONNECTIVES: dict[str, _Handler] = {
    "and": _conjunction,
    "or": _disjunction,
    "imply": _disjunction,
    "not": _negation,
    "exists": _quantifier,
    "forall": _quantifier,
}
#: The handler of each head in a condition or goal; an atom for any other head.
_CONDITIONS: dict[str, _Handler] = {
    **_CONNECTIVES,
    "=": _equality,
    **dict.fromkeys(_COMPARISONS, _compare),
}
#: The handler of each head in an effect; an atom for any other head.
_EFFECTS: dict[str, _Handler] = {
    **_CONNECTIVES,
    "when": _conditional,
    **dict.fromkeys(_NUMERIC_EFFECTS, _numeric_effect),
}


def _comparison(ctx: FormulaContext, node: Form, scope: Mapping[str, str]) -> None:
    ctx.usage.note(":numeric-fluents", ctx.source, node.offset)
    if len(node.items) != 3:
        ctx.diags.error(
            ctx.source, node.offset, f"({node.head} A B) compares two numeric expressions"
        )
        return
    for arg in node.items[1:]:
        check_numeric(ctx, arg, scope)


def check_numeric(
    ctx: FormulaContext, node: Node, scope: Mapping[str, str], *, note: bool = True
) -> None:
    """A numeric expression; ``note``: whether it needs :numeric-fluents (the cost
    expression of an action-costs increase, init values and the metric do not)."""
    if isinstance(node, Atom):
        if node.text.startswith("?"):
            if node.text == "?duration" and ctx.durative:
                return
            if node.text in scope:
                ctx.diags.error(
                    ctx.source,
                    node.offset,
                    f"{node.text} is an object (type {scope[node.text]!r}), but a number is "
                    f"expected here in {ctx.where}",
                    "use a function of it, e.g. (distance ?from ?to), or a number",
                )
            else:
                ctx.diags.error(
                    ctx.source,
                    node.offset,
                    f"undeclared variable {node.text} in {ctx.where}",
                    suggest(node.text, scope),
                )
            return
        try:
            float(node.text)
        except ValueError:
            ctx.diags.error(
                ctx.source,
                node.offset,
                f"expected a number or a numeric expression in {ctx.where}, found {node.text!r}",
            )
        return
    head = node.head
    if head in _ARITHMETIC:
        if len(node.items) < 2:
            ctx.diags.error(ctx.source, node.offset, f"({head} ...) needs arguments")
        for arg in node.items[1:]:
            check_numeric(ctx, arg, scope, note=note)
        return
    if head in ctx.domain.functions or head == "total-cost":
        if head != "total-cost" and note:
            ctx.usage.note(":numeric-fluents", ctx.source, node.offset)
        if ctx.reader and head in ctx.domain.functions:
            ctx.usage.reads.setdefault(head, []).append(
                Read(tuple(node.items[1:]), scope, ctx.source, node.offset, ctx.reader, ctx.guards)
            )
        check_atom(ctx, node, scope, numeric=True)
        return
    if head in ctx.domain.predicates:
        ctx.diags.error(
            ctx.source,
            node.offset,
            f"{head} is a predicate, but a numeric expression is expected here in {ctx.where}",
            "functions: " + (", ".join(sorted(ctx.domain.functions)) or "none"),
        )
        return
    ctx.diags.error(
        ctx.source,
        node.offset,
        f"undeclared function {head!r} in {ctx.where}"
        if head
        else f"expected a numeric expression in {ctx.where}",
        suggest(head, ctx.domain.functions),
    )


def check_duration(ctx: FormulaContext, node: Node, scope: Mapping[str, str]) -> None:
    if isinstance(node, Form) and node.head == "and":
        for arg in node.items[1:]:
            check_duration(ctx, arg, scope)
        return
    if (
        not isinstance(node, Form)
        or node.head not in ("=", "<=", ">=", "<", ">")
        or len(node.items) != 3
    ):
        ctx.diags.error(
            ctx.source,
            node.offset,
            f"expected a duration constraint such as (= ?duration 5) in {ctx.where}",
        )
        return
    if node.head != "=":
        ctx.usage.note(":duration-inequalities", ctx.source, node.offset)
    for arg in node.items[1:]:
        check_numeric(ctx, arg, scope)
    bound, value = node.items[1], _constant(node.items[2])
    if not (isinstance(bound, Atom) and bound.text == "?duration") or value is None:
        return
    shown = f"{value:g}"
    impossible = value < 0 if node.head in ("=", "<=") else node.head == "<" and value <= 0
    if impossible:
        ctx.diags.error(
            ctx.source,
            node.items[2].offset,
            f"a duration of {shown} in {ctx.where}: a durative action cannot take negative time"
            if node.head == "="
            else f"no duration satisfies ({node.head} ?duration {shown}) in {ctx.where}: "
            "a durative action cannot take negative time",
            "give a positive duration, e.g. (= ?duration 2)",
        )
    elif node.head == "=" and value == 0:
        ctx.diags.warning(
            ctx.source,
            node.items[2].offset,
            f"a duration of 0 in {ctx.where}: its start and end effects happen at the same instant",
            "accepted: PDDL 2.1 allows it (IPC 2004's UMTS domain has such actions) and "
            "TAMER and Kairos plan it; if the action takes no time, an (:action ...) says "
            "so plainly, and if it does, give its duration",
        )


def _constant(node: Node) -> float | None:
    """The value of a numeric expression made of numbers only (``-2``, ``(- 2)``)."""
    if isinstance(node, Atom):
        try:
            return float(node.text)
        except ValueError:
            return None
    values = [_constant(arg) for arg in node.items[1:]]
    numbers = [v for v in values if v is not None]
    if node.head not in _ARITHMETIC or not numbers or len(numbers) != len(values):
        return None
    first, rest = numbers[0], numbers[1:]
    if node.head == "-":
        return first - sum(rest) if rest else -first
    if node.head == "+":
        return sum(numbers)
    if node.head == "*":
        product = 1.0
        for number in numbers:
            product *= number
        return product
    if len(rest) != 1 or rest[0] == 0:
        return None
    return first / rest[0]


def check_atom(
    ctx: FormulaContext, node: Form, scope: Mapping[str, str], *, numeric: bool = False
) -> None:
    head = node.head
    signature: Signature | None = (
        ctx.domain.functions.get(head) if numeric else ctx.domain.predicates.get(head)
    )
    if signature is None:
        if head == "total-cost":
            ctx.diags.error(
                ctx.source,
                node.offset + 1,
                f"undeclared function 'total-cost' in {ctx.where}",
                "declare it in the domain: (:functions (total-cost) - number), with "
                ":action-costs in (:requirements ...)",
            )
            return
        if not numeric and head in ctx.domain.functions:
            ctx.diags.error(
                ctx.source,
                node.offset,
                f"{head} is a function, but a condition or fact is expected here in {ctx.where}",
                "compare it, e.g. (>= (" + head + " ...) 0)",
            )
            return
        ctx.diags.error(
            ctx.source,
            node.offset + 1,
            f"undeclared predicate {head!r} in {ctx.where}",
            suggest(head, ctx.domain.predicates),
        )
        return
    args = node.items[1:]
    if len(args) != len(signature.params):
        line, column = ctx.domain.source.line_col(signature.offset)
        shown = " ".join(f"{p.name} - {p.type}" for p in signature.params)
        ctx.diags.error(
            ctx.source,
            node.offset,
            f"{head} takes {len(signature.params)} argument(s), {len(args)} given in {ctx.where}",
            f"declared as ({head} {shown}) at {ctx.domain.source.path}:{line}:{column}",
        )
        return
    for arg, param in zip(args, signature.params, strict=True):
        if isinstance(arg, Form):
            ctx.diags.error(
                ctx.source,
                arg.offset,
                f"argument of {head} must be a name or ?variable, found '(' in {ctx.where}",
            )
            continue
        kind = _term(ctx, arg, scope)
        if kind == "object" and arg.text.startswith("?") and param.type in ctx.domain.types:
            ctx.diags.error(
                ctx.source,
                arg.offset,
                f"{arg.text} is untyped (type 'object'), but {param.name} of {head} needs "
                f"type {param.type!r} in {ctx.where}",
                f"declare it as {arg.text} - {param.type} (an untyped variable is an object)",
            )
        elif (
            kind is not None
            and kind in ctx.domain.types
            and not ctx.domain.is_subtype(kind, param.type)
            and not ctx.domain.is_subtype(param.type, kind)
        ):
            ctx.diags.error(
                ctx.source,
                arg.offset,
                f"{arg.text} has type {kind!r}, but {param.name} of {head} needs type {param.type!r} in {ctx.where}",
            )


def _term(ctx: FormulaContext, arg: Atom, scope: Mapping[str, str]) -> str | None:
    """The type of a ``?variable`` or object/constant name, after checking it is declared."""
    if arg.text.startswith("?"):
        if arg.text in scope:
            return scope[arg.text]
        if ctx.where == "(:init ...)":
            ctx.diags.error(
                ctx.source,
                arg.offset,
                f"variable {arg.text} in (:init ...): initial facts are ground",
                "name an object instead",
            )
            return None
        ctx.diags.error(
            ctx.source,
            arg.offset,
            f"undeclared variable {arg.text} in {ctx.where}",
            "in scope: " + (" ".join(scope) or "no variables"),
        )
        return None
    entry = ctx.names.get(arg.text)
    if entry is None:
        what = "object or constant" if ctx.source.kind == "problem" else "constant"
        ctx.diags.error(
            ctx.source,
            arg.offset,
            f"undeclared {what} {arg.text!r} in {ctx.where}",
            suggest(arg.text, ctx.names),
        )
        return None
    return entry.type


def check_types(ctx: FormulaContext, entries: Iterable[Entry]) -> None:
    declared = set(ctx.domain.types) | {"object"}
    for entry in entries:
        if entry.type not in declared and entry.type_offset is not None:
            ctx.diags.error(
                ctx.source,
                entry.type_offset,
                f"undeclared type {entry.type!r}",
                suggest(entry.type, declared),
            )
