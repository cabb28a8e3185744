"""The PDDL front end: a positioned pass over domain and problem before UP reads them.

:func:`analyse` reads both files into positioned declarations
(:mod:`~plan_bridge.pddl.model`), checks formulas and the problem against the
domain (:mod:`~plan_bridge.pddl.checks`), classifies every requirement and construct
(:mod:`~plan_bridge.pddl.features`) and rewrites the text where unified-planning 1.3
rejects valid PDDL (:mod:`~plan_bridge.pddl.rewrite`). Errors are raised as one
:class:`~plan_bridge.errors.PddlError` at the first one's ``file:line:column``
(the others listed); warnings are kept. :func:`parse_with_up` then hands the
rewritten text to UP's reader and translates its failures back to positions in
the user's files.
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from plan_bridge.errors import PddlError, UnsupportedFeatureError
from plan_bridge.pddl.checks import Usage, check_domain, check_problem, check_requirements
from plan_bridge.pddl.diagnostics import Diagnostic, Diagnostics
from plan_bridge.pddl.features import ENGINES, classify
from plan_bridge.pddl.initial_values import check_initial_values
from plan_bridge.pddl.model import DomainModel, ProblemModel, read_domain, read_problem
from plan_bridge.pddl.rewrite import DOMAIN_ORDER, PROBLEM_ORDER, Edit, Rewritten, rewrite
from plan_bridge.pddl.sexpr import Atom, Form, walk
from plan_bridge.pddl.source import (
    DEFAULT_MAX_BYTES,
    DEFAULT_MAX_DEPTH,
    check_source,
    read_source,
)
from plan_bridge.pddl.source_text import SourceText, paused_gc

__all__ = ["FrontEnd", "analyse", "analyse_files", "parse_with_up"]


@dataclass
class FrontEnd:
    """The result of the positioned pass over one domain and problem."""

    domain: SourceText
    problem: SourceText
    domain_model: DomainModel
    problem_model: ProblemModel
    diagnostics: Diagnostics
    needs_engine: list[tuple[str, SourceText, int]] = field(default_factory=list)
    """(feature, source, offset) of features planned only by engines not installed."""
    domain_up: Rewritten = field(default_factory=lambda: Rewritten(""))
    problem_up: Rewritten = field(default_factory=lambda: Rewritten(""))

    @property
    def domain_text(self) -> str:
        """The domain text handed to unified-planning (rewritten where needed)."""
        return self.domain_up.text

    @property
    def problem_text(self) -> str:
        return self.problem_up.text

    @property
    def warnings(self) -> list[str]:
        return [str(d) for d in self.diagnostics.warnings] + [
            str(d) for d in self._engine_diagnostics("warning")
        ]

    def _engine_diagnostics(self, severity: str) -> list[Diagnostic]:
        found = []
        for feature, source, offset in self.needs_engine:
            support = classify(feature)
            assert support is not None
            found.append(
                Diagnostic(
                    severity,
                    source,
                    offset,
                    f"{support.describe()}; none of them is installed",
                    "install one: "
                    + " or ".join(f"pip install {ENGINES[e].package}" for e in support.engines),
                    feature if severity == "error" else None,
                )
            )
        return found

    def require_engines(self) -> None:
        """Raise :class:`UnsupportedFeatureError` if a feature needs an engine that is
        not installed (the CLI's verdict; a library caller may plan with its own)."""
        found = self._engine_diagnostics("error")
        if found:
            Diagnostics(found).raise_errors()


def analyse_files(
    domain: str | Path,
    problem: str | Path,
    *,
    max_bytes: int = DEFAULT_MAX_BYTES,
    max_depth: int = DEFAULT_MAX_DEPTH,
) -> FrontEnd:
    """Read, check and analyse two PDDL files (nothing of unified-planning is imported)."""
    domain_source = read_source(domain, "domain", max_bytes=max_bytes)
    check_source(domain_source, max_depth=max_depth)
    problem_source = read_source(problem, "problem", max_bytes=max_bytes)
    check_source(problem_source, max_depth=max_depth)
    return analyse(domain_source, problem_source)


def analyse(domain: SourceText, problem: SourceText) -> FrontEnd:
    """The positioned pass over sources that passed :func:`check_source`.

    Raises :class:`PddlError` naming the first error (and listing the others)."""
    with paused_gc():
        return _analyse(domain, problem)


def _analyse(domain: SourceText, problem: SourceText) -> FrontEnd:
    diags = Diagnostics()
    usage = Usage()
    for source in (domain, problem):
        if source.preamble is not None:
            diags.warning(
                source,
                source.preamble[0],
                "(in-package ...) before (define ...): a Lisp preamble of early PDDL "
                "files, not PDDL; plan_bridge ignores it",
                "unified-planning 1.3 would refuse it: it is left out of the text it reads",
            )
    domain_model = read_domain(domain, diags)
    problem_model = read_problem(problem, diags)
    check_domain(domain_model, diags, usage)
    check_problem(domain_model, problem_model, diags, usage)
    missing = check_requirements(domain_model, problem_model, diags, usage)
    diags.raise_errors()
    check_initial_values(domain_model, problem_model, diags, usage)
    front = FrontEnd(domain, problem, domain_model, problem_model, diags)
    for flag in missing:
        where = usage.first.get(flag)
        if where is None:
            where = (domain, domain_model.requirements.get(flag, domain_model.tree.offset))
        front.needs_engine.append((flag, where[0], where[1]))
    _prepare_for_up(front)
    return front


def _prepare_for_up(front: FrontEnd) -> None:
    domain, problem = front.domain_model, front.problem_model
    domain_edits: list[Edit] = []
    problem_edits: list[Edit] = []
    for model, edits in ((domain, domain_edits), (problem, problem_edits)):
        if model.source.preamble is not None:
            edits.append(Edit(*model.source.preamble, ""))
        for head, section in model.sections:
            if len(section.items) == 1 and head not in (":init", ":action", ":durative-action"):
                edits.append(Edit(section.offset, section.end, ""))
    # An object, constant, predicate, function or action named like a type: UP 1.3
    # keeps one namespace for all of them, so the type is renamed where it is used as
    # a type (the others keep their names, since plans and skills use them).
    others: dict[str, str] = {}
    for action in domain.actions:
        others.setdefault(action.name, "an action")
    for name in domain.functions:
        others[name] = "a function"
    for name in domain.predicates:
        others[name] = "a predicate"
    for name in [*domain.constants, *problem.objects]:
        others[name] = "an object"
    taken = set(others) | set(domain.types)
    renames: dict[str, str] = {}
    for clash in sorted(set(others) & set(domain.types)):
        new = f"{clash}_type"
        while new in taken:
            new += "_"
        renames[clash] = new
        entry = domain.types[clash]
        front.diagnostics.warning(
            domain.source,
            entry.offset,
            f"type {clash!r} has the name of {others[clash]}; unified-planning 1.3 needs "
            f"distinct names, so plan_bridge reads this type as {new!r}",
        )
    if renames:
        domain_edits += _type_renames(domain.tree, renames, domain.sections)
        problem_edits += _type_renames(problem.tree, renames, problem.sections)
    for action in domain.actions:
        domain_edits += _duration_substitution(action.parts, domain.source.text)
    domain_edits += _declare_object_type(domain, problem)
    problem_edits += _drop_repeated_constants(domain, problem)
    ref = problem.domain_ref
    if ref is not None and domain.name and ref.text != domain.name:
        # Another name in (:domain ...) is a warning (checks.py); planners get the domain's.
        problem_edits.append(Edit(ref.offset, ref.offset + len(ref.text), domain.name))
    metric = problem.metric.items if problem.metric is not None else []
    if len(metric) == 3 and isinstance(metric[2], Atom) and metric[2].text == "total-time":
        # UP 1.3 reads the makespan only in parentheses (it fails on the bare word).
        problem_edits.append(Edit(metric[2].offset, metric[2].end, "(total-time)"))
    front.domain_up = _rewrite(domain, DOMAIN_ORDER, domain_edits)
    added = [] if problem.init is not None else [(":init", "(:init)")]
    front.problem_up = _rewrite(problem, PROBLEM_ORDER, problem_edits, added)


def _rewrite(
    model: DomainModel | ProblemModel,
    order: dict[str, int],
    edits: Sequence[Edit],
    added: Sequence[tuple[str, str]] = (),
) -> Rewritten:
    """:func:`~plan_bridge.pddl.rewrite.rewrite` of the file ``model`` was read from."""
    return rewrite(
        model.source.text, model.tree, [s for _, s in model.sections], order, edits, added
    )


def _declare_object_type(domain: DomainModel, problem: ProblemModel) -> list[Edit]:
    """UP 1.3 decides from the domain alone whether the type ``object`` exists: a
    problem object typed ``object`` (or untyped) in a typed domain is then a
    ``KeyError``. Declaring ``object`` in ``(:types ...)`` makes it exist."""
    types = next((form for head, form in domain.sections if head == ":types"), None)
    if types is None:
        return []
    items = types.items
    for index in range(1, len(items)):
        item, before = items[index], items[index - 1]
        after_dash = isinstance(before, Atom) and before.text == "-"
        if isinstance(item, Atom) and item.text == "object" and not after_dash:
            return []  # declared as a type name already
    entries = [*problem.objects.values(), *domain.constants.values()]
    if not any(entry.type == "object" for entry in entries) and not _untyped_quantifier(
        domain.tree
    ):
        return []
    return [Edit(types.end - 1, types.end - 1, " object")]


def _drop_repeated_constants(domain: DomainModel, problem: ProblemModel) -> list[Edit]:
    """Objects that repeat a constant of the domain (a warning of the checks): UP 1.3
    refuses a name declared twice, so they are left out of the text it reads (with
    their ``- type`` when no other object of their group is left)."""
    repeated = {e.offset for n, e in problem.objects.items() if n in domain.constants}
    if not repeated:
        return []
    edits: list[Edit] = []
    for head, section in problem.sections:
        if head != ":objects":
            continue
        items = [item for item in section.items[1:] if isinstance(item, Atom)]
        group: list[Atom] = []
        index = 0
        while index < len(items):
            item = items[index]
            if item.text == "-" and index + 1 < len(items):
                edits += _drop_from_group(group, items[index + 1].end, repeated)
                group = []
                index += 2
                continue
            group.append(item)
            index += 1
        edits += _drop_from_group(group, None, repeated)
    return edits


def _drop_from_group(names: list[Atom], type_end: int | None, repeated: set[int]) -> list[Edit]:
    """Edits dropping the repeated ones of ``names`` (typed by the ``- T`` ending at
    ``type_end``): the whole ``a b - T`` when all of them are repeated."""
    dropped = [name for name in names if name.offset in repeated]
    if type_end is not None and dropped and len(dropped) == len(names):
        return [Edit(names[0].offset, type_end, "")]
    return [Edit(name.offset, name.end, "") for name in dropped]


def _untyped_quantifier(tree: Form) -> bool:
    """Whether a ``forall``/``exists`` has an untyped variable (``(forall (?x) ...)``):
    UP 1.3 reads it as type ``object``, which must then be declared too."""
    for node in walk(tree):
        if isinstance(node, Form) and node.head in ("forall", "exists") and len(node.items) > 1:
            variables = node.items[1]
            if isinstance(variables, Form) and variables.items:
                last = variables.items[-1]
                if isinstance(last, Atom) and last.text.startswith("?"):
                    return True
    return False


def _type_renames(
    tree: Form, renames: dict[str, str], sections: list[tuple[str, Form]]
) -> list[Edit]:
    edits: list[Edit] = []
    type_sections = {id(s) for head, s in sections if head == ":types"}
    for node in walk(tree):
        if not isinstance(node, Form):
            continue
        in_types = id(node) in type_sections
        for index, item in enumerate(node.items):
            if not isinstance(item, Atom) or item.text not in renames:
                continue
            previous = node.items[index - 1] if index > 0 else None
            after_dash = index > 1 and isinstance(previous, Atom) and previous.text == "-"
            if (in_types and index > 0) or after_dash:
                edits.append(Edit(item.offset, item.end, renames[item.text]))
    return edits


def _duration_substitution(parts: dict[str, Any], text: str) -> list[Edit]:
    """``?duration`` in an effect, with ``(= ?duration EXPR)``: UP 1.3 knows no
    ``?duration`` outside the duration constraint, so EXPR is written in its place."""
    duration = parts.get(":duration")
    effect = parts.get(":effect")
    if duration is None or effect is None or effect[1] is None:
        return []
    constraint = duration[1]
    if not (
        isinstance(constraint, Form)
        and constraint.head == "="
        and len(constraint.items) == 3
        and isinstance(constraint.items[1], Atom)
        and constraint.items[1].text == "?duration"
    ):
        return []
    value = constraint.items[2]
    end = value.end
    replacement = text[value.offset : end]
    return [
        Edit(node.offset, node.end, replacement)
        for node in walk(effect[1])
        if isinstance(node, Atom) and node.text == "?duration"
    ]


# -- unified-planning's reader, its failures back at the user's positions ----------

_LOCATION_IN_MESSAGE = re.compile(r"line:? ?(\d+),? col:? ?(\d+)", re.IGNORECASE)
_PYPARSING_SUFFIX = re.compile(r"\s*\(at char \d+\),?\s*\(line:\s*\d+,\s*col:\s*\d+\)\s*$")


def parse_with_up(front: FrontEnd) -> tuple[Any, list[str]]:
    """Parse the (rewritten) text with UP's reader: the UP problem and the warnings."""
    from plan_bridge.pddl.up_runtime import ensure_unified_planning

    ensure_unified_planning()
    import pyparsing
    from unified_planning.io import PDDLReader  # type: ignore[import-untyped]

    notes = front.warnings
    reader = PDDLReader()
    try:
        # UP warns while parsing; the warnings belong to the task, not to the
        # caller's warning filters (tests run with -W error).
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            result = reader.parse_problem_string(front.domain_text, front.problem_text)
        notes.extend(str(w.message) for w in caught)
        return result, notes
    except pyparsing.ParseBaseException as exc:
        is_domain = exc.pstr == front.domain_text.replace("\t", " ").lower()
        raise _syntax_error(front, is_domain, exc) from exc
    except RecursionError as exc:
        raise PddlError(
            "expressions nested too deeply for the unified-planning PDDL reader",
            path=front.problem.path,
            hint="simplify the nesting of the formulas",
        ) from exc
    except Exception as exc:
        is_domain = _domain_fails(reader, front)
        raise _located(front, is_domain, str(exc) or type(exc).__name__, exc) from exc


def _position(front: FrontEnd, is_domain: bool, line: int, column: int) -> tuple[SourceText, int]:
    source = front.domain if is_domain else front.problem
    rewritten = front.domain_up if is_domain else front.problem_up
    view = SourceText(rewritten.text, source.path, source.kind)
    return source, rewritten.original_offset(view.offset_of(line, column))


def _syntax_error(front: FrontEnd, is_domain: bool, exc: Any) -> PddlError:
    message = _PYPARSING_SUFFIX.sub("", str(exc)).strip()
    source, offset = _position(front, is_domain, exc.lineno, exc.col)
    section = source.section_at(offset)
    where = f" in ({section} ...)" if section else ""
    return source.error(
        f"PDDL syntax error{where}: {message}",
        offset,
        hint="unified-planning 1.3 could not parse the form starting here; check it against "
        "the PDDL grammar",
    )


def _located(front: FrontEnd, is_domain: bool, message: str, exc: Exception) -> PddlError:
    first = message.strip().splitlines()[0] if message.strip() else type(exc).__name__
    match = _LOCATION_IN_MESSAGE.search(message)
    source = front.domain if is_domain else front.problem
    offset = None
    if match is not None:
        source, offset = _position(front, is_domain, int(match.group(1)), int(match.group(2)))
        first = _LOCATION_IN_MESSAGE.split(first)[0].rstrip(" .,:;-")
        first = re.sub(r"(?:from|found at|error in expression from)\s*$", "", first).rstrip(" .,:;")
    if offset is None and is_domain:
        # No position in UP's message: the action it names, if it names one.
        for action in front.domain_model.actions:
            if re.search(rf"(?<![\w-]){re.escape(action.name)}(?![\w-])", message):
                offset = action.offset
                break
    from unified_planning.exceptions import (  # type: ignore[import-untyped]
        UPUnsupportedProblemTypeError,
    )

    if isinstance(exc, UPUnsupportedProblemTypeError):
        return (
            UnsupportedFeatureError(
                f"unsupported PDDL feature: {first}",
                feature=first,
                path=source.path,
                hint="the unified-planning 1.3 PDDL reader cannot represent it",
            )
            if offset is None
            else source.error(
                f"unsupported PDDL feature: {first}",
                offset,
                "the unified-planning 1.3 PDDL reader cannot represent it",
                feature=first,
            )
        )
    return source.error(
        f"unified-planning rejected this PDDL: {first}",
        offset,
        "" if offset is not None else f"the {source.kind} file could not be read as a whole",
    )


def _domain_fails(reader: Any, front: FrontEnd) -> bool:
    """UP's semantic errors do not say which file they are about: re-read the domain
    alone; if that works, the problem is at fault."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            reader.parse_problem_string(front.domain_text, None)
    except Exception:
        return True
    return False
