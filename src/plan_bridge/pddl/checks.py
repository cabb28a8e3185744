"""Checks of formulas and of the problem against its domain, with positions.

Every atom in a precondition, effect, condition, duration, init, goal or metric is
checked against the declarations collected by :mod:`~plan_bridge.pddl.model`:
predicate or function declared, arity, variables in scope, objects and constants
declared, argument types. Each construct met is classified
(:mod:`~plan_bridge.pddl.features`): unsupported ones are errors naming the feature;
features used without their ``:requirements`` flag are warnings naming the flag and
the line of first use. Durations below zero are errors (zero is a warning);
``total-time`` is the makespan in ``(:metric minimize (total-time))`` and unsupported
elsewhere. The walk records where numeric fluents are read
(:class:`Read`) for :mod:`~plan_bridge.pddl.initial_values`.

(Over 600 lines: the domain's and the problem's checks share the formula walk and
its private context; split, they would have to export both.)
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field

from plan_bridge.pddl.diagnostics import Diagnostics
from plan_bridge.pddl.features import IMPLIED, classify
from plan_bridge.pddl.model import DomainModel, Entry, ProblemModel, Signature, typed_list
from plan_bridge.pddl.sexpr import Atom, Form, Node, walk
from plan_bridge.pddl.source import SourceText

__all__ = ["Read", "Usage", "check_domain", "check_problem", "check_requirements"]

_COMPARISONS = frozenset(["<", ">", "<=", ">="])
_NUMERIC_EFFECTS = frozenset(["increase", "decrease", "assign", "scale-up", "scale-down"])
_ARITHMETIC = frozenset(["+", "-", "*", "/"])
_CONTINGENT = frozenset(["oneof", "unknown", "probabilistic", "preference"])


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
class _Context:
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


_PART_NAMES = {":precondition": "precondition", ":condition": "condition", ":effect": "effect"}


def _suggest(word: str, choices: Iterable[str]) -> str:
    options = sorted(choices)
    # difflib is quadratic-ish per candidate: on huge problems compare with the
    # names that share the first letter only.
    pool = options if len(options) <= 2000 else [o for o in options if o[:1] == word[:1]][:2000]
    close = difflib.get_close_matches(word, pool, n=1, cutoff=0.6)
    shown = ", ".join(options[:30]) + (" ..." if len(options) > 30 else "")
    guess = f"did you mean {close[0]}? " if close else ""
    return f"{guess}declared: {shown or 'none'}"


def check_domain(domain: DomainModel, diags: Diagnostics, usage: Usage) -> None:
    source = domain.source
    if domain.typing_at is not None:
        usage.note(":typing", source, domain.typing_at)
    declared_types = set(domain.types) | {"object"}
    for entry in _typed_entries(domain):
        if entry.type not in declared_types and entry.type_offset is not None:
            what = (
                "(:types ...) declares none"
                if not domain.explicit_types
                else _suggest(entry.type, declared_types)
            )
            diags.error(source, entry.type_offset, f"undeclared type {entry.type!r}", what)
    for name, entry in domain.constants.items():
        for kind, table in (("predicate", domain.predicates), ("function", domain.functions)):
            if name in table:
                _clash(source, diags, "constant", entry.offset, kind, table[name].offset, name)
    offsets = (
        ("predicate", {n: e.offset for n, e in domain.predicates.items()}),
        ("function", {n: e.offset for n, e in domain.functions.items()}),
        ("constant", {n: e.offset for n, e in domain.constants.items()}),
    )
    for action in domain.actions:  # UP 1.3: one namespace for actions and the others
        for kind, declared in offsets:
            if action.name in declared:
                _clash(
                    source, diags, "action", action.offset, kind, declared[action.name], action.name
                )
    static = _static_predicates(domain)
    for action in domain.actions:
        ctx = _Context(
            domain,
            source,
            diags,
            usage,
            domain.constants,
            durative=action.kind == ":durative-action",
            where=f"({action.kind} {action.name} ...)",
            guards=_guards(action.parts, static),
        )
        if ctx.durative:
            usage.note(":durative-actions", source, action.offset)
        scope = {p.name: p.type for p in action.params}
        free = action.parts.get(":vars")
        if free is not None and isinstance(free[1], Form):
            # PDDL 1.2's free variables: named unsupported, and in scope (so their
            # uses are not reported as undeclared too).
            _unsupported(ctx, ":vars", free[0].offset)
            variables, _ = typed_list(
                free[1].items, source, diags, f":vars of {action.name}", variables=True
            )
            scope.update({v.name: v.type for v in variables})
        for keyword, (word, value) in action.parts.items():
            if value is None or keyword in (":parameters", ":vars"):
                continue
            ctx.reader = f"the {_PART_NAMES.get(keyword, keyword[1:])} of {action.name}"
            if keyword == ":observe":
                _unsupported(ctx, ":observe", word.offset)
            elif keyword == ":precondition":
                _formula(ctx, value, scope, "pre")
            elif keyword == ":effect":
                _formula(ctx, value, scope, "eff")
            elif keyword == ":condition":
                _formula(ctx, value, scope, "pre")
            elif keyword == ":duration":
                _duration(ctx, value, scope)
    for head, form in domain.sections:
        if head in (":derived", ":process", ":event", ":task", ":method", ":constraints"):
            _unsupported_section(source, diags, head, form)


def _static_predicates(domain: DomainModel) -> frozenset[str]:
    """Predicates no action's effect changes."""
    changed: set[str] = set()
    for action in domain.actions:
        effect = action.parts.get(":effect")
        if effect is not None and effect[1] is not None:
            changed.update(node.head for node in walk(effect[1]) if isinstance(node, Form))
    return frozenset(domain.predicates) - changed


def _is_equality(node: Node | None) -> bool:
    return isinstance(node, Form) and node.head == "=" and len(node.items) == 3


def _guards(
    parts: Mapping[str, tuple[Atom, Node | None]], static: frozenset[str]
) -> tuple[Form, ...]:
    """The static atoms and ``(not (= A B))`` of a precondition's conjunction."""
    found: list[Form] = []
    pending = [parts[key][1] for key in (":precondition", ":condition") if key in parts]
    while pending:
        node = pending.pop()
        if not isinstance(node, Form) or not node.items:
            continue
        items = node.items
        if node.head == "and":
            pending.extend(items[1:])
        elif node.head in ("at", "over") and len(items) == 3 and isinstance(items[1], Atom):
            pending.append(items[2])
        elif node.head in static or (node.head == "not" and _is_equality(items[-1])):
            found.append(node)
    return tuple(found)


def _typed_entries(domain: DomainModel) -> Iterable[Entry]:
    yield from domain.types.values()
    yield from domain.constants.values()
    for table in (domain.predicates, domain.functions):
        for signature in table.values():
            yield from signature.params
    for action in domain.actions:
        yield from action.params


def _clash(
    source: SourceText,
    diags: Diagnostics,
    kind: str,
    offset: int,
    other: str,
    other_offset: int,
    name: str,
    other_source: SourceText | None = None,
) -> None:
    where = other_source or source
    line, column = where.line_col(other_offset)
    diags.error(
        source,
        offset,
        f"{kind} {name!r} has the name of {'an' if other[0] in 'aeiou' else 'a'} {other} (declared at {where.path}:{line}:{column}); "
        "PDDL allows it, but the unified-planning 1.3 reader needs distinct names",
        f"rename the {kind} or the {other}",
        feature="shared-names",
    )


def _unsupported(ctx: _Context, name: str, offset: int) -> None:
    support = classify(name)
    text = support.describe() if support else f"{name} is not supported"
    ctx.diags.error(ctx.source, offset, f"unsupported PDDL construct: {text}", feature=name)


def _unsupported_section(source: SourceText, diags: Diagnostics, head: str, form: Form) -> None:
    support = classify(head) or classify(":constraints" if head == ":constraints" else head)
    if head == ":derived":
        return  # reported by check_source, before any of this runs
    text = support.describe() if support else f"({head} ...) is not supported"
    diags.error(source, form.offset, f"unsupported PDDL section: {text}", feature=head)


def _formula(ctx: _Context, node: Node, scope: Mapping[str, str], mode: str) -> None:
    """``mode``: ``pre`` (condition, goal), ``eff`` (effect)."""
    if isinstance(node, Atom):
        ctx.diags.error(
            ctx.source, node.offset, f"expected a formula (...) in {ctx.where}, found {node.text!r}"
        )
        return
    if node.is_empty:
        return
    head = node.head
    args = node.items[1:]
    if not head:
        ctx.diags.error(
            ctx.source,
            node.offset,
            f"a formula in {ctx.where} must start with a name or a connective, found '('",
        )
        return
    if head in _CONTINGENT or (head == "or" and mode == "eff"):
        _unsupported(ctx, head if head != "or" else "oneof", node.offset)
        return
    if (
        head in ("at", "over")
        and len(args) == 2
        and isinstance(args[0], Atom)
        and args[0].text in ("start", "end", "all")
        and isinstance(args[1], Form)
    ):
        if not ctx.durative:
            ctx.diags.error(
                ctx.source,
                node.offset,
                f"({head} {args[0].text} ...) is a timed {'effect' if mode == 'eff' else 'condition'}"
                f", but {ctx.where} is not a :durative-action",
                "write the formula without it in an :action, or make the action a "
                "(:durative-action NAME :parameters (...) :duration (= ?duration N) "
                ":condition ... :effect ...)",
            )
            return
        _formula(ctx, args[1], scope, mode)
        return
    if head == "and":
        for arg in args:
            _formula(ctx, arg, scope, mode)
    elif head in ("or", "imply"):
        if mode == "pre":
            ctx.usage.note(":disjunctive-preconditions", ctx.source, node.offset)
        for arg in args:
            _formula(ctx, arg, scope, mode)
    elif head == "not":
        if len(args) != 1:
            ctx.diags.error(
                ctx.source, node.offset, f"(not ...) takes one formula, found {len(args)}"
            )
            return
        inner = args[0]
        if mode == "pre" and not (isinstance(inner, Form) and inner.head == "="):
            ctx.usage.note(":negative-preconditions", ctx.source, node.offset)
        _formula(ctx, inner, scope, mode)
    elif head in ("exists", "forall"):
        if len(args) != 2 or not isinstance(args[0], Form):
            ctx.diags.error(ctx.source, node.offset, f"({head} (?x - type ...) FORMULA) expected")
            return
        if mode == "eff":
            if head == "forall" and ctx.in_forall_effect:
                _unsupported(ctx, "nested-forall-effect", node.offset)
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
        _check_types(ctx, variables)
        outer = ctx.in_forall_effect
        ctx.in_forall_effect = outer or (mode == "eff" and head == "forall")
        _formula(ctx, args[1], {**scope, **{v.name: v.type for v in variables}}, mode)
        ctx.in_forall_effect = outer
    elif head == "when" and mode == "eff":
        ctx.usage.note(":conditional-effects", ctx.source, node.offset)
        if len(args) != 2:
            ctx.diags.error(ctx.source, node.offset, "(when CONDITION EFFECT) expected")
            return
        _formula(ctx, args[0], scope, "pre")
        _formula(ctx, args[1], scope, "eff")
    elif head == "=" and mode == "pre":
        if all(isinstance(a, Atom) for a in args) and len(args) == 2:
            ctx.usage.note(":equality", ctx.source, node.offset)
            for arg in args:
                _term(ctx, arg, scope)  # type: ignore[arg-type]
        else:
            _comparison(ctx, node, scope)
    elif head in _COMPARISONS and mode == "pre":
        _comparison(ctx, node, scope)
    elif head in _NUMERIC_EFFECTS and mode == "eff":
        if len(args) != 2:
            ctx.diags.error(ctx.source, node.offset, f"({head} (FUNCTION ...) EXPRESSION) expected")
            return
        target = args[0]
        cost = isinstance(target, Form) and target.head == "total-cost"
        ctx.usage.note(":action-costs" if cost else ":numeric-fluents", ctx.source, node.offset)
        reader = ctx.reader
        if head == "assign":
            ctx.reader = ""  # the target is written, not read
        _numeric(ctx, target, scope, note=not cost)
        ctx.reader = reader
        _numeric(ctx, args[1], scope, note=not cost)
    else:
        _atom(ctx, node, scope)


def _comparison(ctx: _Context, node: Form, scope: Mapping[str, str]) -> None:
    ctx.usage.note(":numeric-fluents", ctx.source, node.offset)
    if len(node.items) != 3:
        ctx.diags.error(
            ctx.source, node.offset, f"({node.head} A B) compares two numeric expressions"
        )
        return
    for arg in node.items[1:]:
        _numeric(ctx, arg, scope)


def _numeric(ctx: _Context, node: Node, scope: Mapping[str, str], *, note: bool = True) -> None:
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
                    _suggest(node.text, scope),
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
            _numeric(ctx, arg, scope, note=note)
        return
    if head in ctx.domain.functions or head == "total-cost":
        if head != "total-cost" and note:
            ctx.usage.note(":numeric-fluents", ctx.source, node.offset)
        if ctx.reader and head in ctx.domain.functions:
            ctx.usage.reads.setdefault(head, []).append(
                Read(tuple(node.items[1:]), scope, ctx.source, node.offset, ctx.reader, ctx.guards)
            )
        _atom(ctx, node, scope, numeric=True)
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
        _suggest(head, ctx.domain.functions),
    )


def _duration(ctx: _Context, node: Node, scope: Mapping[str, str]) -> None:
    if isinstance(node, Form) and node.head == "and":
        for arg in node.items[1:]:
            _duration(ctx, arg, scope)
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
        _numeric(ctx, arg, scope)
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


def _atom(ctx: _Context, node: Form, scope: Mapping[str, str], *, numeric: bool = False) -> None:
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
            _suggest(head, ctx.domain.predicates),
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


def _term(ctx: _Context, arg: Atom, scope: Mapping[str, str]) -> str | None:
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
            _suggest(arg.text, ctx.names),
        )
        return None
    return entry.type


def _check_types(ctx: _Context, entries: Iterable[Entry]) -> None:
    declared = set(ctx.domain.types) | {"object"}
    for entry in entries:
        if entry.type not in declared and entry.type_offset is not None:
            ctx.diags.error(
                ctx.source,
                entry.type_offset,
                f"undeclared type {entry.type!r}",
                _suggest(entry.type, declared),
            )


def check_problem(
    domain: DomainModel, problem: ProblemModel, diags: Diagnostics, usage: Usage
) -> None:
    source = problem.source
    ref = problem.domain_ref
    if ref is None:
        diags.error(
            source,
            problem.tree.offset,
            "the problem has no (:domain NAME) section",
            f"add (:domain {domain.name})",
        )
    elif domain.name and ref.text != domain.name:
        # A warning: knowledge bases (ROSPlan's) write problems with a placeholder name,
        # and unified-planning reads them; the front end passes the domain's name on.
        line, column = domain.source.line_col(domain.name_offset or 0)
        diags.warning(
            source,
            ref.offset,
            f"this problem is for domain {ref.text!r}, but the domain file defines {domain.name!r} "
            f"(at {domain.source.path}:{line}:{column}); planning it with {domain.name!r} - "
            "check that this is the domain file the problem was written for",
        )
    _check_types(_Context(domain, source, diags, usage, {}), problem.objects.values())
    names: dict[str, Entry] = dict(domain.constants)
    for name, entry in problem.objects.items():
        if name in domain.constants:
            # Other planners take it (one object); UP 1.3 refuses a name declared
            # twice, so the front end leaves this declaration out of what UP reads.
            constant = domain.constants[name]
            line = domain.source.line_col(constant.offset)[0]
            types = (
                f" (typed {entry.type!r} here, {constant.type!r} in the domain: the "
                "domain's type counts)"
                if entry.type != constant.type
                else ""
            )
            diags.warning(
                source,
                entry.offset,
                f"object {name!r} (line {source.line_col(entry.offset)[0]}) is already a "
                f"constant of the domain ({domain.source.path}:{line}){types}; it is the "
                "same object, declared twice",
                "unified-planning 1.3 refuses a name declared twice, so plan_bridge leaves "
                "this declaration out of what it reads; remove it from (:objects ...) to "
                "silence this warning",
            )
            continue
        for kind, table in (("predicate", domain.predicates), ("function", domain.functions)):
            if name in table:
                _clash(
                    source,
                    diags,
                    "object",
                    entry.offset,
                    kind,
                    table[name].offset,
                    name,
                    domain.source,
                )
        for action in domain.actions:
            if action.name == name:
                _clash(
                    source,
                    diags,
                    "object",
                    entry.offset,
                    "action",
                    action.offset,
                    name,
                    domain.source,
                )
        names[name] = entry
    ctx = _Context(domain, source, diags, usage, names, where="(:init ...)")
    if problem.init is not None:
        for fact in problem.init.items[1:]:
            _init_fact(ctx, fact)
    if problem.goal is not None and len(problem.goal.items) == 2:
        ctx.where = "(:goal ...)"
        ctx.reader = "the goal"
        _formula(ctx, problem.goal.items[1], {}, "pre")
        ctx.reader = ""
        if _empty_conjunction(problem.goal.items[1]):
            diags.warning(
                source,
                problem.goal.offset,
                "the goal is empty: it holds in every state, so the plan is empty and "
                "`run` ends at once (the goal already holds)",
                "ROSPlan-style problems leave (:goal (and)) to be filled at run time; "
                "write the goal atoms here to plan for them",
            )
    if problem.metric is not None:
        ctx.where = "(:metric ...)"
        items = problem.metric.items[1:]
        if (
            len(items) != 2
            or not isinstance(items[0], Atom)
            or items[0].text not in ("minimize", "maximize")
        ):
            diags.error(
                source,
                problem.metric.offset,
                "expected (:metric minimize EXPRESSION) or (:metric maximize EXPRESSION)",
            )
        else:
            _metric(ctx, items[0].text, items[1])
    for head, form in problem.sections:
        if head in (":htn", ":constraints"):
            _unsupported_section(source, diags, head, form)


def _metric(ctx: _Context, direction: str, expression: Node) -> None:
    """PDDL 2.1 defines ``total-time`` (the makespan) for every metric; unified-planning
    1.3 reads it as ``(:metric minimize (total-time))`` only, so it is unsupported
    elsewhere in a metric (a domain's own function ``total-time`` is a function)."""
    if "total-time" in ctx.domain.functions:
        _numeric(ctx, expression, {}, note=False)
        return
    makespan = (  # `total-time` alone is read as `(total-time)` (front_end rewrites it)
        isinstance(expression, Form)
        and expression.head == "total-time"
        and len(expression.items) == 1
    ) or (isinstance(expression, Atom) and expression.text == "total-time")
    if makespan and direction == "minimize":
        return
    uses = [
        node
        for node in walk(expression)
        if (isinstance(node, Form) and node.head == "total-time")
        or (isinstance(node, Atom) and node.text == "total-time")
    ]
    if uses:
        _unsupported(ctx, "total-time", uses[0].offset)
        return
    _numeric(ctx, expression, {}, note=False)


def _empty_conjunction(node: Node) -> bool:
    """``(and)``, or conjunctions of nothing but ``(and)``: a goal that always holds."""
    return (
        isinstance(node, Form)
        and node.head.lower() == "and"
        and all(_empty_conjunction(item) for item in node.items[1:])
    )


def _init_fact(ctx: _Context, fact: Node) -> None:
    if isinstance(fact, Atom) or fact.is_empty:
        ctx.diags.error(
            ctx.source,
            fact.offset,
            "expected a ground fact such as (at robot kitchen) in (:init ...)",
        )
        return
    head = fact.head
    args = fact.items[1:]
    if head in _CONTINGENT or head == "or":
        _unsupported(ctx, head if head != "or" else "or-init", fact.offset)
    elif head == "=":
        if len(args) != 2 or not isinstance(args[0], Form):
            ctx.diags.error(
                ctx.source, fact.offset, "expected (= (FUNCTION ...) NUMBER) in (:init ...)"
            )
            return
        _numeric(ctx, args[0], {}, note=False)
        _numeric(ctx, args[1], {}, note=False)
    elif (
        head == "at"
        and len(args) == 2
        and isinstance(args[0], Atom)
        and isinstance(args[1], Form)
        and _is_number(args[0].text)
    ):
        ctx.usage.note(":timed-initial-literals", ctx.source, fact.offset)
        _init_fact(ctx, args[1])
    elif head == "not":
        if len(args) == 1:
            _init_fact(ctx, args[0])
    else:
        _atom(ctx, fact, {})


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def check_requirements(
    domain: DomainModel, problem: ProblemModel | None, diags: Diagnostics, usage: Usage
) -> list[str]:
    """Warn for features used without their flag; classify every declared flag.

    Returns the flags whose engines are not installed (the caller decides whether
    that is an error)."""
    declared: dict[str, tuple[SourceText, int]] = {
        f: (domain.source, o) for f, o in domain.requirements.items()
    }
    if problem is not None:
        for flag, offset in problem.requirements.items():
            declared.setdefault(flag, (problem.source, offset))
    closure = set(declared) | {":strips"}
    for flag in list(closure):
        closure |= IMPLIED.get(flag, frozenset())
    for flag, (source, offset) in declared.items():
        support = classify(flag)
        if support is not None and support.status == "unsupported":
            diags.error(
                source, offset, f"unsupported PDDL requirement: {support.describe()}", feature=flag
            )
    for flag, (source, offset) in sorted(
        usage.first.items(), key=lambda kv: (kv[1][0].kind, kv[1][1])
    ):
        if flag in closure:
            continue
        support = classify(flag)
        what = f" ({support.what})" if support else ""
        line = source.line_col(offset)[0]
        where = (
            domain.requirements
            and f"add it to (:requirements ...) at line {domain.source.line_col(min(domain.requirements.values()))[0]}"
        )
        diags.warning(
            source,
            offset,
            f"uses {flag}{what} here (line {line}), but the domain's :requirements does not declare {flag}",
            where or f"add (:requirements {flag}) to the domain",
        )
    missing: list[str] = []
    for flag in sorted(set(usage.first) | set(declared)):
        support = classify(flag)
        if support is not None and support.status == "engine" and not support.installed_engines:
            missing.append(flag)
    return missing
