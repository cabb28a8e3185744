"""The declarations of a PDDL domain and problem, each with its position.

:func:`read_domain` and :func:`read_problem` walk the positioned tree of
:mod:`~plan_bridge.pddl.sexpr` and collect what is declared -- requirements, types,
constants, predicates, functions, actions, objects, init, goal -- in any section
order and with empty sections allowed. Structural mistakes (a duplicate name, a
dangling ``-``, a parameter without ``?``, a cyclic type hierarchy) go to the
:class:`~plan_bridge.pddl.diagnostics.Diagnostics` with the position of the offending
word (and of the earlier declaration where two are involved). Formulas are checked
later, by :mod:`~plan_bridge.pddl.checks`, against these declarations.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from plan_bridge.pddl.diagnostics import Diagnostics
from plan_bridge.pddl.sexpr import Atom, Form, Node, read_tree
from plan_bridge.pddl.source import SourceText

__all__ = [
    "ActionDef",
    "DomainModel",
    "Entry",
    "ProblemModel",
    "Signature",
    "read_domain",
    "read_problem",
]


@dataclass(frozen=True)
class Entry:
    """A declared name with its type (``object`` when untyped)."""

    name: str
    offset: int
    type: str = "object"
    type_offset: int | None = None


@dataclass
class Signature:
    """A predicate or function: name and typed ``?parameters``."""

    name: str
    offset: int
    params: list[Entry]


@dataclass
class ActionDef:
    """An ``:action`` or ``:durative-action`` with its parts by keyword."""

    kind: str
    name: str
    offset: int
    params: list[Entry]
    parts: dict[str, tuple[Atom, Node | None]]


@dataclass
class _Common:
    source: SourceText
    tree: Form
    name: str = ""
    name_offset: int | None = None
    sections: list[tuple[str, Form]] = field(default_factory=list)
    requirements: dict[str, int] = field(default_factory=dict)


@dataclass
class DomainModel(_Common):
    types: dict[str, Entry] = field(default_factory=dict)
    """Type name -> its parent; implicitly declared parents are included."""
    explicit_types: bool = False
    constants: dict[str, Entry] = field(default_factory=dict)
    predicates: dict[str, Signature] = field(default_factory=dict)
    functions: dict[str, Signature] = field(default_factory=dict)
    actions: list[ActionDef] = field(default_factory=list)
    typing_at: int | None = None
    """Offset of the first ``- type``, to warn when ``:typing`` is missing."""

    def is_subtype(self, child: str, parent: str) -> bool:
        seen: set[str] = set()
        current = child
        while current not in seen:
            if parent in (current, "object"):
                return True
            seen.add(current)
            entry = self.types.get(current)
            if entry is None:
                return False
            current = entry.type
        return False


@dataclass
class ProblemModel(_Common):
    domain_ref: Atom | None = None
    objects: dict[str, Entry] = field(default_factory=dict)
    init: Form | None = None
    goal: Form | None = None
    metric: Form | None = None


_PARTS = {
    ":action": (":parameters", ":precondition", ":effect", ":observe"),
    ":durative-action": (":parameters", ":duration", ":condition", ":effect"),
}


def _header(model: _Common, diags: Diagnostics) -> list[Form]:
    tree, source = model.tree, model.source
    items = tree.items
    if len(items) < 2 or not isinstance(items[1], Form) or items[1].head != source.kind:
        diags.error(source, tree.offset, f"expected (define ({source.kind} NAME) ...)")
        return []
    header = items[1]
    if len(header.items) != 2 or not isinstance(header.items[1], Atom):
        diags.error(
            source,
            header.offset,
            f"({source.kind} ...) must hold exactly one name",
            f"write ({source.kind} NAME)",
        )
    else:
        model.name = header.items[1].text
        model.name_offset = header.items[1].offset
    body: list[Form] = []
    seen: dict[str, int] = {}
    for item in items[2:]:
        if not isinstance(item, Form) or not item.head.startswith(":"):
            diags.error(
                source,
                item.offset,
                "expected a section such as (:predicates ...) here",
                f"everything inside (define ...) after ({source.kind} NAME) is a (:keyword ...) section",
            )
            continue
        head = item.head
        if head not in _PARTS and head not in (
            ":derived",
            ":process",
            ":event",
            ":task",
            ":method",
        ):
            if head in seen:
                line, column = source.line_col(seen[head])
                diags.error(
                    source,
                    item.offset,
                    f"duplicate section ({head} ...); the first one is at {source.path}:{line}:{column}",
                    "merge the two sections into one",
                )
            seen.setdefault(head, item.offset)
        model.sections.append((head, item))
        body.append(item)
        if head == ":requirements":
            for flag in item.items[1:]:
                if isinstance(flag, Atom):
                    model.requirements.setdefault(flag.text, flag.offset)
                else:
                    diags.error(source, flag.offset, "expected a requirement flag such as :strips")
    return body


#: A name (or ``?variable``) unified-planning 1.3 can read.
_NAME = re.compile(r"\??[A-Za-z][A-Za-z0-9_-]*")


def typed_list(
    items: list[Node], source: SourceText, diags: Diagnostics, what: str, *, variables: bool = False
) -> tuple[list[Entry], int | None]:
    """``a b - t c`` -> entries (a t) (b t) (c object); also the offset of the first ``-``."""
    entries: list[Entry] = []
    pending: list[Atom] = []
    dash_at: int | None = None
    index = 0
    while index < len(items):
        item = items[index]
        if isinstance(item, Atom) and item.text == "-":
            dash_at = item.offset if dash_at is None else dash_at
            kind = items[index + 1] if index + 1 < len(items) else None
            if not isinstance(kind, Atom) or kind.text == "-":
                diags.error(
                    source,
                    item.offset,
                    f"'-' in the {what} must be followed by a type name",
                    "write NAME ... - TYPE",
                )
                index += 1
                continue
            if not pending:
                diags.error(
                    source, item.offset, f"'- {kind.text}' in the {what} types no name before it"
                )
            entries.extend(Entry(a.text, a.offset, kind.text, kind.offset) for a in pending)
            pending = []
            index += 2
            continue
        if isinstance(item, Form):
            diags.error(source, item.offset, f"expected a name in the {what}, found '('")
        elif variables and not item.text.startswith("?"):
            diags.error(
                source,
                item.offset,
                f"parameter {item.text!r} in the {what} must start with '?'",
                f"write ?{item.text}",
            )
        elif not variables and item.text.startswith("?"):
            diags.error(
                source,
                item.offset,
                f"{item.text!r} in the {what}: names of the {what} do not start with '?'",
            )
        elif not _NAME.fullmatch(item.text):
            diags.error(
                source,
                item.offset,
                f"{item.text!r} in the {what}: a PDDL name starts with a letter and has "
                "only ASCII letters, digits, '-' and '_'",
                "rename it (unified-planning 1.3 reads no other names)",
            )
        else:
            pending.append(item)
        index += 1
    entries.extend(Entry(a.text, a.offset) for a in pending)
    seen: dict[str, Entry] = {}
    for entry in entries:
        if entry.name in seen:
            line, column = source.line_col(seen[entry.name].offset)
            diags.error(
                source,
                entry.offset,
                f"{entry.name!r} appears twice in the {what}; the first is at {source.path}:{line}:{column}",
            )
        else:
            seen[entry.name] = entry
    return entries, dash_at


def _declare(
    table: dict[str, Entry] | dict[str, Signature],
    name: str,
    offset: int,
    value: Entry | Signature,
    what: str,
    source: SourceText,
    diags: Diagnostics,
) -> None:
    if name in table:
        line, column = source.line_col(table[name].offset)
        diags.error(
            source,
            offset,
            f"{what} {name!r} is declared twice; the first declaration is at {source.path}:{line}:{column}",
            "remove or rename one of them",
        )
        return
    table[name] = value  # type: ignore[assignment]


def read_domain(source: SourceText, diags: Diagnostics) -> DomainModel:
    model = DomainModel(source, read_tree(source))
    for item in _header(model, diags):
        head = item.head
        if head == ":types":
            model.explicit_types = True
            entries, dash = typed_list(item.items[1:], source, diags, "types")
            model.typing_at = (
                model.typing_at if model.typing_at is not None else (dash or item.offset)
            )
            for entry in entries:
                if entry.name == "object":
                    continue
                model.types[entry.name] = entry
        elif head == ":constants":
            entries, dash = typed_list(item.items[1:], source, diags, "constants")
            model.typing_at = model.typing_at if model.typing_at is not None else dash
            for entry in entries:
                model.constants.setdefault(entry.name, entry)
        elif head in (":predicates", ":functions"):
            table = model.predicates if head == ":predicates" else model.functions
            what = "predicate" if head == ":predicates" else "function"
            _read_signatures(model, item, table, what, diags)
        elif head in _PARTS:
            _read_action(model, item, diags)
    for entry in list(model.types.values()):
        if entry.type != "object" and entry.type not in model.types:
            # A parent used but not listed itself is an implicitly declared type.
            model.types[entry.type] = Entry(entry.type, entry.type_offset or entry.offset)
    _check_type_cycles(model, diags)
    return model


def _read_signatures(
    model: DomainModel, section: Form, table: dict[str, Signature], what: str, diags: Diagnostics
) -> None:
    source = model.source
    items = section.items[1:]
    index = 0
    while index < len(items):
        item = items[index]
        if isinstance(item, Atom):
            if item.text == "-" and what == "function" and index + 1 < len(items):
                index += 2  # `- number`: the type of the functions before it
                continue
            diags.error(
                source,
                item.offset,
                f"expected a {what} declaration such as (name ?x - type) here, found {item.text!r}",
            )
            index += 1
            continue
        if not item.items or not isinstance(item.items[0], Atom):
            diags.error(source, item.offset, f"a {what} declaration needs a name: (name ?x - type)")
            index += 1
            continue
        name = item.items[0]
        params, dash = typed_list(
            item.items[1:], source, diags, f"parameters of {what} {name.text}", variables=True
        )
        model.typing_at = model.typing_at if model.typing_at is not None else dash
        other = model.functions if what == "predicate" else model.predicates
        if name.text in other:
            line, column = source.line_col(other[name.text].offset)
            diags.error(
                source,
                name.offset,
                f"{name.text!r} is declared both as a predicate and as a function; the other "
                f"declaration is at {source.path}:{line}:{column}",
            )
        else:
            _declare(
                table,
                name.text,
                name.offset,
                Signature(name.text, name.offset, params),
                what,
                source,
                diags,
            )
        index += 1


def _read_action(model: DomainModel, item: Form, diags: Diagnostics) -> None:
    source = model.source
    kind = item.head
    if (
        len(item.items) < 2
        or not isinstance(item.items[1], Atom)
        or item.items[1].text.startswith(":")
    ):
        diags.error(
            source, item.offset, f"({kind} ...) needs a name: ({kind} NAME :parameters (...) ...)"
        )
        return
    name = item.items[1]
    parts: dict[str, tuple[Atom, Node | None]] = {}
    rest = item.items[2:]
    index = 0
    while index < len(rest):
        word = rest[index]
        if not isinstance(word, Atom) or not word.text.startswith(":"):
            diags.error(
                source,
                word.offset,
                f"expected a keyword ({', '.join(_PARTS[kind])}) in ({kind} {name.text} ...)",
            )
            index += 1
            continue
        value = rest[index + 1] if index + 1 < len(rest) else None
        if isinstance(value, Atom) and value.text.startswith(":"):
            value = None
        if value is None:
            diags.error(
                source, word.offset, f"{word.text} in ({kind} {name.text} ...) has no value"
            )
            index += 1
        else:
            index += 2
        if word.text in parts:
            line, column = source.line_col(parts[word.text][0].offset)
            diags.error(
                source,
                word.offset,
                f"{word.text} appears twice in ({kind} {name.text} ...); the first is at {source.path}:{line}:{column}",
            )
            continue
        parts[word.text] = (word, value)
    params: list[Entry] = []
    declared = parts.get(":parameters")
    if declared is not None and declared[1] is not None:
        if isinstance(declared[1], Form):
            params, dash = typed_list(
                declared[1].items, source, diags, f"parameters of {name.text}", variables=True
            )
            model.typing_at = model.typing_at if model.typing_at is not None else dash
        else:
            diags.error(
                source,
                declared[1].offset,
                f":parameters of {name.text} must be a list: (?x - type ...)",
            )
    for other in model.actions:
        if other.name == name.text:
            line, column = source.line_col(other.offset)
            diags.error(
                source,
                name.offset,
                f"action {name.text!r} is defined twice; the first definition is at {source.path}:{line}:{column}",
            )
            return
    model.actions.append(ActionDef(kind, name.text, name.offset, params, parts))


def _check_type_cycles(model: DomainModel, diags: Diagnostics) -> None:
    source = model.source
    reported: set[str] = set()
    for start in model.types:
        chain = [start]
        while True:
            parent = model.types[chain[-1]].type if chain[-1] in model.types else "object"
            if parent == "object" or parent in reported:
                break
            if parent in chain:
                cycle = [*chain[chain.index(parent) :], parent]
                if not reported.intersection(cycle):
                    where = ", ".join(
                        f"{name} - {model.types[name].type} at "
                        + ":".join(map(str, source.line_col(model.types[name].offset)))
                        for name in cycle[:-1]
                    )
                    diags.error(
                        source,
                        model.types[cycle[0]].offset,
                        "cyclic type hierarchy: " + " is a subtype of ".join(cycle),
                        f"declared as: {where}; every type must end in object",
                    )
                reported.update(cycle)
                break
            chain.append(parent)


def read_problem(source: SourceText, diags: Diagnostics) -> ProblemModel:
    model = ProblemModel(source, read_tree(source))
    for item in _header(model, diags):
        head = item.head
        if head == ":domain":
            if len(item.items) == 2 and isinstance(item.items[1], Atom):
                model.domain_ref = item.items[1]
            else:
                diags.error(
                    source, item.offset, "(:domain ...) must hold exactly one name: (:domain NAME)"
                )
        elif head == ":objects":
            entries, _ = typed_list(item.items[1:], source, diags, "objects")
            for entry in entries:
                model.objects.setdefault(entry.name, entry)
        elif head == ":init":
            model.init = item
        elif head == ":goal":
            if len(item.items) != 2:
                diags.error(
                    source,
                    item.offset,
                    f"(:goal ...) must hold exactly one formula, found {len(item.items) - 1}",
                    "join several goals with (and ...)",
                )
            model.goal = item
        elif head == ":metric":
            model.metric = item
    if model.goal is None:
        diags.error(source, model.tree.offset, "the problem has no (:goal ...) section")
    return model
