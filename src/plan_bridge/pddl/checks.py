"""Checks of the domain and the problem against their declarations, with positions.

:func:`check_domain` checks the declarations (types declared, names distinct for
the unified-planning 1.3 reader) and walks every action's precondition, condition,
effect and duration with the formula walk of :mod:`~plan_bridge.pddl.formula_checks`;
:func:`check_problem` does the same for the problem's objects, init, goal and metric.
Features used without their ``:requirements`` flag are warnings naming the flag and
the line of first use (:func:`check_requirements`). ``total-time`` is the makespan in
``(:metric minimize (total-time))`` and unsupported elsewhere. :class:`Read` and
:class:`Usage` are defined in :mod:`~plan_bridge.pddl.formula_checks` and importable
from here.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from plan_bridge.pddl.diagnostics import Diagnostics
from plan_bridge.pddl.features import IMPLIED, classify
from plan_bridge.pddl.formula_checks import (
    CONTINGENT,
    FormulaContext,
    Read,
    Usage,
    check_atom,
    check_duration,
    check_formula,
    check_numeric,
    check_types,
    suggest,
    unsupported,
)
from plan_bridge.pddl.model import (
    ActionDef,
    DomainModel,
    Entry,
    ProblemModel,
    Signature,
    typed_list,
)
from plan_bridge.pddl.sexpr import Atom, Form, Node, walk
from plan_bridge.pddl.source import SourceText, is_number

__all__ = ["Read", "Usage", "check_domain", "check_problem", "check_requirements"]


_PART_NAMES = {":precondition": "precondition", ":condition": "condition", ":effect": "effect"}
_FORMULA_MODES = {":precondition": "pre", ":condition": "pre", ":effect": "eff"}


def check_domain(domain: DomainModel, diags: Diagnostics, usage: Usage) -> None:
    source = domain.source
    if domain.typing_at is not None:
        usage.note(":typing", source, domain.typing_at)
    _check_declared_types(domain, diags)
    _check_shared_names(domain, diags)
    static = _static_predicates(domain)
    for action in domain.actions:
        _check_action(domain, action, diags, usage, static)
    for head, form in domain.sections:
        if head in (":derived", ":process", ":event", ":task", ":method", ":constraints"):
            _unsupported_section(source, diags, head, form)


def _check_declared_types(domain: DomainModel, diags: Diagnostics) -> None:
    declared_types = set(domain.types) | {"object"}
    for entry in _typed_entries(domain):
        if entry.type not in declared_types and entry.type_offset is not None:
            what = (
                "(:types ...) declares none"
                if not domain.explicit_types
                else suggest(entry.type, declared_types)
            )
            diags.error(domain.source, entry.type_offset, f"undeclared type {entry.type!r}", what)


def _check_shared_names(domain: DomainModel, diags: Diagnostics) -> None:
    """A constant or an action named like a predicate or function (or an action like
    a constant): PDDL allows it, the unified-planning 1.3 reader does not."""
    source = domain.source
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


def _check_action(
    domain: DomainModel,
    action: ActionDef,
    diags: Diagnostics,
    usage: Usage,
    static: frozenset[str],
) -> None:
    source = domain.source
    ctx = FormulaContext(
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
        unsupported(ctx, ":vars", free[0].offset)
        variables, _ = typed_list(
            free[1].items, source, diags, f":vars of {action.name}", variables=True
        )
        scope.update({v.name: v.type for v in variables})
    for keyword, (word, value) in action.parts.items():
        if value is None or keyword in (":parameters", ":vars"):
            continue
        ctx.reader = f"the {_PART_NAMES.get(keyword, keyword[1:])} of {action.name}"
        if keyword == ":observe":
            unsupported(ctx, ":observe", word.offset)
        elif keyword in _FORMULA_MODES:
            check_formula(ctx, value, scope, _FORMULA_MODES[keyword])
        elif keyword == ":duration":
            check_duration(ctx, value, scope)


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


def _unsupported_section(source: SourceText, diags: Diagnostics, head: str, form: Form) -> None:
    if head == ":derived":
        return  # reported by check_source, before any of this runs
    support = classify(head)
    text = support.describe() if support else f"({head} ...) is not supported"
    diags.error(source, form.offset, f"unsupported PDDL section: {text}", feature=head)


def check_problem(
    domain: DomainModel, problem: ProblemModel, diags: Diagnostics, usage: Usage
) -> None:
    source = problem.source
    _check_domain_ref(domain, problem, diags)
    check_types(FormulaContext(domain, source, diags, usage, {}), problem.objects.values())
    names = _problem_names(domain, problem, diags)
    ctx = FormulaContext(domain, source, diags, usage, names, where="(:init ...)")
    if problem.init is not None:
        for fact in problem.init.items[1:]:
            _init_fact(ctx, fact)
    if problem.goal is not None and len(problem.goal.items) == 2:
        _check_goal(ctx, problem.goal)
    if problem.metric is not None:
        _check_metric_section(ctx, problem.metric)
    for head, form in problem.sections:
        if head in (":htn", ":constraints"):
            _unsupported_section(source, diags, head, form)


def _check_domain_ref(domain: DomainModel, problem: ProblemModel, diags: Diagnostics) -> None:
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


def _problem_names(
    domain: DomainModel, problem: ProblemModel, diags: Diagnostics
) -> dict[str, Entry]:
    """The domain's constants and the problem's objects, which arguments may name."""
    names: dict[str, Entry] = dict(domain.constants)
    for name, entry in problem.objects.items():
        if name in domain.constants:
            _object_is_constant(domain, problem, name, entry, diags)
            continue
        clashes = [
            (kind, table[name].offset) for kind, table in _signatures(domain) if name in table
        ]
        clashes += [("action", action.offset) for action in domain.actions if action.name == name]
        for kind, offset in clashes:
            _clash(problem.source, diags, "object", entry.offset, kind, offset, name, domain.source)
        names[name] = entry
    return names


def _signatures(domain: DomainModel) -> tuple[tuple[str, Mapping[str, Signature]], ...]:
    return (("predicate", domain.predicates), ("function", domain.functions))


def _object_is_constant(
    domain: DomainModel, problem: ProblemModel, name: str, entry: Entry, diags: Diagnostics
) -> None:
    # Other planners take it (one object); UP 1.3 refuses a name declared
    # twice, so the front end leaves this declaration out of what UP reads.
    source = problem.source
    constant = domain.constants[name]
    line = domain.source.line_col(constant.offset)[0]
    types = (
        f" (typed {entry.type!r} here, {constant.type!r} in the domain: the domain's type counts)"
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


def _check_goal(ctx: FormulaContext, goal: Form) -> None:
    ctx.where = "(:goal ...)"
    ctx.reader = "the goal"
    check_formula(ctx, goal.items[1], {}, "pre")
    ctx.reader = ""
    if _empty_conjunction(goal.items[1]):
        ctx.diags.warning(
            ctx.source,
            goal.offset,
            "the goal is empty: it holds in every state, so the plan is empty and "
            "`run` ends at once (the goal already holds)",
            "ROSPlan-style problems leave (:goal (and)) to be filled at run time; "
            "write the goal atoms here to plan for them",
        )


def _check_metric_section(ctx: FormulaContext, metric: Form) -> None:
    ctx.where = "(:metric ...)"
    items = metric.items[1:]
    if (
        len(items) != 2
        or not isinstance(items[0], Atom)
        or items[0].text not in ("minimize", "maximize")
    ):
        ctx.diags.error(
            ctx.source,
            metric.offset,
            "expected (:metric minimize EXPRESSION) or (:metric maximize EXPRESSION)",
        )
    else:
        _metric(ctx, items[0].text, items[1])


def _metric(ctx: FormulaContext, direction: str, expression: Node) -> None:
    """PDDL 2.1 defines ``total-time`` (the makespan) for every metric; unified-planning
    1.3 reads it as ``(:metric minimize (total-time))`` only, so it is unsupported
    elsewhere in a metric (a domain's own function ``total-time`` is a function)."""
    if "total-time" in ctx.domain.functions:
        check_numeric(ctx, expression, {}, note=False)
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
        unsupported(ctx, "total-time", uses[0].offset)
        return
    check_numeric(ctx, expression, {}, note=False)


def _empty_conjunction(node: Node) -> bool:
    """``(and)``, or conjunctions of nothing but ``(and)``: a goal that always holds."""
    return (
        isinstance(node, Form)
        and node.head.lower() == "and"
        and all(_empty_conjunction(item) for item in node.items[1:])
    )


def _init_fact(ctx: FormulaContext, fact: Node) -> None:
    if isinstance(fact, Atom) or fact.is_empty:
        ctx.diags.error(
            ctx.source,
            fact.offset,
            "expected a ground fact such as (at robot kitchen) in (:init ...)",
        )
        return
    head = fact.head
    args = fact.items[1:]
    if head in CONTINGENT or head == "or":
        unsupported(ctx, head if head != "or" else "or-init", fact.offset)
    elif head == "=":
        if len(args) != 2 or not isinstance(args[0], Form):
            ctx.diags.error(
                ctx.source, fact.offset, "expected (= (FUNCTION ...) NUMBER) in (:init ...)"
            )
            return
        check_numeric(ctx, args[0], {}, note=False)
        check_numeric(ctx, args[1], {}, note=False)
    elif (
        head == "at"
        and len(args) == 2
        and isinstance(args[0], Atom)
        and isinstance(args[1], Form)
        and is_number(args[0].text)
    ):
        ctx.usage.note(":timed-initial-literals", ctx.source, fact.offset)
        _init_fact(ctx, args[1])
    elif head == "not":
        if len(args) == 1:
            _init_fact(ctx, args[0])
    else:
        check_atom(ctx, fact, {})


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
