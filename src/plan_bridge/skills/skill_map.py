"""Skill maps: a ``skills.toml`` file that binds PDDL actions to skill factories.

A domain folder's ``skills.toml`` says which actions run as the user's own skills;
every other action keeps the registry's fallback (simulated). No Python setup code
is needed::

    # skills.toml
    [move]                                    # a PDDL action of domain.pddl
    factory = "my_skills:make_move"           # "module:callable"
    arguments = ["?r", "?to"]                 # optional: what the factory gets, in order
    outcome_map = { arrived = "succeeded", blocked = "aborted" }   # optional

    pick = "my_skills:make_pick"              # short form: just the factory

    [[place]]                                 # [[action]]: several entries for one action,
    factory = "my_skills:make_place"          # at most one without a variant (the main skill)
    [[place]]
    factory = "my_skills:make_careful_place"
    variant = "careful"

Modules are looked up in the map's folder first (``my_skills`` is ``my_skills.py``
or ``my_skills/`` next to ``skills.toml``, imported as part of the domain's package,
so it can import its siblings with ``from . import helpers``), then among installed
modules. ``arguments`` lists ``?parameter`` names of the action and constants (a
string without ``?``, a number or a boolean), passed as they are.

:func:`load_skill_map` reads, checks and resolves a map (every problem reported at
once, each as ``skills.toml:LINE: ...``, as a :class:`SkillMapError`);
:meth:`SkillMap.apply` registers its entries in a
:class:`~plan_bridge.skills.registry.SkillRegistry` as the user's own skills
(``simulated=False``). :meth:`plan_bridge.missions.mission.Target.setup` applies a
domain folder's ``skills.toml`` on its own.
"""

from __future__ import annotations

import difflib
import importlib
import importlib.util
import inspect
import json
import re
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any, Protocol

from plan_bridge.errors import PlanBridgeError
from plan_bridge.skills.registry import REQUIRED_OUTCOMES, Skill, SkillFactory, SkillRegistry

if TYPE_CHECKING:
    import smach
    from plan_bridge.pddl.task import ActionSchema

__all__ = [
    "ENTRY_KEYS",
    "MAP_FILE",
    "HasActions",
    "MapProblem",
    "SelectedArguments",
    "SkillMap",
    "SkillMapEntry",
    "SkillMapError",
    "describe_factory",
    "find_skill_map",
    "load_skill_map",
    "registered_skill",
]

#: The name of a domain folder's skill map.
MAP_FILE = "skills.toml"
#: The keys an entry may have.
ENTRY_KEYS = ("factory", "arguments", "outcome_map", "variant")

Constant = str | int | float | bool
"""A constant in ``arguments``: passed to the factory as it is."""


class HasActions(Protocol):
    """What a map is checked against: the domain's actions (a
    :class:`~plan_bridge.pddl.task.PlanningTask` has them)."""

    @property
    def actions(self) -> Mapping[str, ActionSchema]: ...


# -- errors ---------------------------------------------------------------------------


@dataclass(frozen=True)
class MapProblem:
    """One problem of a skill map, at ``path:line`` (``line`` None: the whole file)."""

    path: str
    line: int | None
    message: str
    column: int | None = None

    @property
    def location(self) -> str:
        parts = [self.path]
        if self.line is not None:
            parts.append(str(self.line))
            if self.column is not None:
                parts.append(str(self.column))
        return ":".join(parts)

    def __str__(self) -> str:
        return f"{self.location}: {self.message}"


class SkillMapError(PlanBridgeError):
    """A skill map that cannot be used: every problem found, each with its ``file:line``."""

    def __init__(self, problems: Sequence[MapProblem]) -> None:
        if not problems:
            raise ValueError("a SkillMapError needs at least one problem")
        self.problems = tuple(problems)
        super().__init__(self._render())

    @property
    def path(self) -> str:
        return self.problems[0].path

    @property
    def line(self) -> int | None:
        return self.problems[0].line

    def _render(self) -> str:
        if len(self.problems) == 1:
            return str(self.problems[0])
        listed = "\n  ".join(str(problem) for problem in self.problems)
        return f"{len(self.problems)} problems in the skill map {self.path}:\n  {listed}"

    def __reduce__(self) -> tuple[object, ...]:
        return (type(self), (self.problems,))


# -- the map ----------------------------------------------------------------------------


@dataclass(frozen=True)
class _Parameter:
    index: int


@dataclass(frozen=True)
class _Constant:
    value: Constant


class SelectedArguments:
    """A factory called with some of the action's arguments, and constants
    (``arguments = ["?to", "fast"]``): ``selected("r1", "hall", "kitchen")`` calls
    ``factory("kitchen", "fast")``.

    Its signature takes the action's parameters, so :meth:`SkillRegistry.check`
    checks it like any factory; ``__qualname__`` is the factory's, for messages.
    """

    def __init__(
        self,
        factory: SkillFactory,
        picks: Sequence[_Parameter | _Constant],
        parameters: Sequence[str],
        shown: Sequence[str],
    ) -> None:
        self.factory = factory
        self.picks = tuple(picks)
        self.shown = tuple(shown)
        """The ``arguments`` as written in the map."""
        self.__signature__ = inspect.Signature(
            [
                inspect.Parameter(_identifier(name, i), inspect.Parameter.POSITIONAL_ONLY)
                for i, name in enumerate(parameters)
            ]
        )
        self.__qualname__ = _qualname(factory)
        self.__name__ = getattr(factory, "__name__", self.__qualname__)
        self.__module__ = getattr(factory, "__module__", None) or __name__
        self._arity = len(parameters)

    def __call__(self, *arguments: str) -> smach.State:
        if len(arguments) != self._arity:
            raise TypeError(
                f"{self.__qualname__}: the action has {self._arity} parameter(s), got "
                f"{len(arguments)} argument(s)"
            )
        values = [
            arguments[pick.index] if isinstance(pick, _Parameter) else pick.value
            for pick in self.picks
        ]
        return self.factory(*values)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, SelectedArguments):
            return NotImplemented
        return (self.factory, self.picks, self._arity) == (other.factory, other.picks, other._arity)

    def __hash__(self) -> int:
        return hash((self.factory, self.picks, self._arity))

    def __repr__(self) -> str:
        return f"<{self.__qualname__}({', '.join(self.shown)})>"


@dataclass(frozen=True)
class SkillMapEntry:
    """One action (or variant) of a skill map, resolved."""

    action: str
    """The action's name, as in the domain."""
    target: str
    """The factory as written: ``"module:callable"``."""
    factory: SkillFactory
    """What is registered: the factory, or a :class:`SelectedArguments` around it."""
    path: Path
    line: int | None
    arguments: tuple[Constant, ...] | None = None
    """``arguments`` as written; None: all of the action's, in PDDL order."""
    outcome_map: Mapping[str, str] = field(default_factory=dict)
    variant: str = ""

    @property
    def location(self) -> str:
        """``path/skills.toml:LINE``."""
        return f"{self.path}:{self.line}" if self.line is not None else str(self.path)

    @property
    def label(self) -> str:
        """``[action]``, or ``[action] variant "name"``, for messages."""
        return f"[{self.action}]" + (f" variant {self.variant!r}" if self.variant else "")


@dataclass(frozen=True)
class SkillMap:
    """The entries of a ``skills.toml``, checked against a domain's actions."""

    path: Path
    entries: tuple[SkillMapEntry, ...] = ()

    def entry(self, action: str, variant: str = "") -> SkillMapEntry | None:
        """The entry for ``action`` (or one of its variants), or None."""
        name = action.lower()
        for entry in self.entries:
            if entry.action.lower() == name and entry.variant == variant:
                return entry
        return None

    @property
    def actions(self) -> list[str]:
        """The actions the map gives a main skill to."""
        return sorted({entry.action for entry in self.entries if not entry.variant})

    def apply(self, registry: SkillRegistry, *, registered_by: str = "") -> SkillRegistry:
        """Register every entry in ``registry`` as the user's own skill (not simulated).

        An entry for an action (or variant) that ``registry`` already has is an error
        naming both; ``registered_by`` says who registered the other (for messages,
        e.g. "the domain's setup()"). An entry registered there by this same map (a
        domain's ``setup()`` that returns the same registry each time) is left as it
        is. Nothing is registered unless every entry fits.
        """
        problems: list[MapProblem] = []
        owner = registered_by or "the registry"
        new: list[SkillMapEntry] = []
        for entry in self.entries:
            existing = registered_skill(registry, entry.action, entry.variant)
            if existing is None:
                new.append(entry)
                continue
            if (
                existing.factory == entry.factory
                and existing.outcome_map == entry.outcome_map
                and not existing.simulated
            ):
                continue  # this map's entry, applied before
            shown = describe_factory(existing.factory)
            if entry.variant:
                what = f"a variant {entry.variant!r} of the skill for {entry.action!r} ({shown})"
            else:
                what = f"a skill for {entry.action!r} ({shown})"
            problems.append(
                MapProblem(
                    str(entry.path),
                    entry.line,
                    f"{entry.label} maps it to {entry.target}, but {owner} already registered "
                    f"{what}; an action has one skill (and one of each variant): remove the "
                    f"map entry or the other registration, or make this entry another way to "
                    f'perform the action with variant = "NAME"',
                )
            )
        if problems:
            raise SkillMapError(problems)
        for entry in new:
            registry.register(
                entry.action,
                outcome_map=dict(entry.outcome_map) or None,
                variant=entry.variant or None,
                simulated=False,
            )(entry.factory)
        return registry


def registered_skill(registry: SkillRegistry, action: str, variant: str = "") -> Skill | None:
    """The skill ``registry`` has for ``action`` (or for one of its variants), or None."""
    return registry.get_variant(action, variant) if variant else registry.get(action)


def find_skill_map(folder: str | Path) -> Path | None:
    """The folder's ``skills.toml``, if it has one."""
    path = Path(folder) / MAP_FILE
    return path if path.is_file() else None


def describe_factory(factory: object) -> str:
    """``module:qualname`` of a factory (with the selected arguments, if any)."""
    if isinstance(factory, SelectedArguments):
        return f"{describe_factory(factory.factory)}({', '.join(factory.shown)})"
    module = getattr(factory, "__module__", None)
    name = _qualname(factory)
    return f"{module}:{name}" if module else name


# -- loading ---------------------------------------------------------------------------


def load_skill_map(
    path: str | Path, task: HasActions, *, package: ModuleType | None = None
) -> SkillMap:
    """Read, check and resolve the skill map at ``path`` (a file, or a folder with a
    ``skills.toml``) against ``task``'s actions.

    Factories are imported now: modules are looked up in the map's folder first (as
    submodules of ``package``, the domain folder's package, when given; else of the
    package already loaded for that folder, or of a new empty one), then among
    installed modules. Raises :class:`SkillMapError` with every problem found.
    """
    path = Path(path)
    if path.is_dir():
        path = path / MAP_FILE
    try:
        text = path.read_bytes().decode("utf-8")
    except FileNotFoundError:
        raise SkillMapError([MapProblem(str(path), None, "no such skill map file")]) from None
    except UnicodeDecodeError as exc:
        raise SkillMapError(
            [MapProblem(str(path), None, f"not UTF-8 text ({exc.reason} at byte {exc.start})")]
        ) from None
    except OSError as exc:
        raise SkillMapError([MapProblem(str(path), None, exc.strerror or str(exc))]) from None
    return _Reader(path, text, task, package).read()


def _toml() -> Any:
    """The TOML reader: the standard library's (Python 3.11+), else tomli, else None."""
    if sys.version_info >= (3, 11):
        import tomllib

        return tomllib
    try:  # pragma: no cover - Python 3.10
        return importlib.import_module("tomli")
    except ModuleNotFoundError:  # pragma: no cover - Python 3.10
        return None


_TOML_POSITION = re.compile(r"\s*\(at line (\d+), column (\d+)\)$")
_TOML_AT_END = re.compile(r"\s*\(at end of document\)$")


class _Reader:
    def __init__(self, path: Path, text: str, task: HasActions, package: ModuleType | None) -> None:
        self.path = path
        self.text = text
        self.actions = {name.lower(): schema for name, schema in task.actions.items()}
        self.package = package
        self.problems: list[MapProblem] = []

    def problem(self, line: int | None, message: str) -> None:
        self.problems.append(MapProblem(str(self.path), line, message))

    def read(self) -> SkillMap:
        toml = _toml()
        if toml is None:  # pragma: no cover - Python 3.10
            raise SkillMapError(
                [MapProblem(str(self.path), None, "reading skill maps needs Python 3.11+ or tomli")]
            )
        try:
            data: dict[str, Any] = toml.loads(self.text)
        except toml.TOMLDecodeError as exc:
            raise SkillMapError([_syntax_problem(self.path, str(exc), self.text)]) from None
        lines = _Lines(self.text)
        entries: list[SkillMapEntry] = []
        for action, value in data.items():
            if isinstance(value, str):
                elements: list[Any] = [{"factory": value}]
            elif isinstance(value, dict):
                elements = [value]
            elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
                elements = value
            else:
                self.problem(
                    lines.entry(action),
                    f"{action} = {_shown(value)}: an entry is a table ([{action}] with "
                    f'factory = "module:callable") or the factory alone '
                    f'({action} = "module:callable")',
                )
                continue
            schema = self.actions.get(action.lower())
            if schema is None:
                self.problem(
                    lines.entry(action),
                    f"[{action}]: the domain has no action {action!r}"
                    f"{_did_you_mean(action.lower(), self.actions)}; actions: "
                    f"{', '.join(sorted(self.actions)) or 'none'}",
                )
                continue
            for index, element in enumerate(elements):
                entry = self.entry(schema, element, lines.at(action, index))
                if entry is not None:
                    entries.append(entry)
        self.duplicates(entries)
        if self.problems:
            raise SkillMapError(self.problems)
        return SkillMap(self.path, tuple(entries))

    def entry(
        self, schema: ActionSchema, element: dict[str, Any], where: _Where
    ) -> SkillMapEntry | None:
        action = schema.name
        line = where.line
        at = where.key

        before = len(self.problems)
        misspelled = set()
        for key in element:
            if key not in ENTRY_KEYS:
                misspelled.update(difflib.get_close_matches(key, ENTRY_KEYS, n=1, cutoff=0.6))
                hint = ""
                if key.lower() in self.actions:
                    hint = (
                        f'; {key!r} is an action: a short entry ({key} = "module:callable") '
                        f"belongs before the first [table], as keys after a header are that "
                        f"table's; or write [{key}] with factory = ..."
                    )
                self.problem(
                    at(key),
                    f"[{action}]: unknown key {key!r}{_did_you_mean(key, ENTRY_KEYS)}; "
                    f"allowed keys: {', '.join(ENTRY_KEYS)}{hint}",
                )
        variant = element.get("variant", "")
        if not isinstance(variant, str) or ("variant" in element and not variant.strip()):
            self.problem(
                at("variant"),
                f"[{action}]: variant must be a non-empty string naming another way to "
                f'perform the action (e.g. variant = "careful"), got {_shown(variant)}',
            )
            variant = ""
        label = f"[{action}]" + (f" variant {variant!r}" if variant else "")
        outcome_map = self.outcome_map(label, element.get("outcome_map", {}), at("outcome_map"))
        picks = self.arguments(label, schema, element.get("arguments"), at("arguments"))
        target = element.get("factory")
        factory: SkillFactory | None = None
        if target is None:
            if "factory" in misspelled:
                return None  # the misspelled key was reported
            self.problem(
                line,
                f'{label}: no factory; add factory = "module:callable" (a function or class '
                f"that takes the action's arguments and returns a smach.State)",
            )
        elif not isinstance(target, str):
            self.problem(
                at("factory"),
                f'{label}: factory must be a string "module:callable", got {_shown(target)}',
            )
        else:
            factory = self.factory(label, action, target, at("factory"))
        if factory is None or picks is None or len(self.problems) > before:
            return None
        arguments = element.get("arguments")
        count = schema.arity if arguments is None else len(picks)
        arity = _arity_problem(factory, count)
        if arity:
            selected = (
                f"the action's {count} parameter(s) "
                f"({', '.join('?' + p.lstrip('?') for p in schema.parameter_names) or 'none'})"
                if arguments is None
                else f"{count} argument(s) (arguments = {_toml_text(arguments)})"
            )
            self.problem(
                at("factory"),
                f"{label}: factory {target} cannot take {selected}: {arity}; change the "
                f"factory's parameters or choose what it gets with arguments = "
                f'["?param", ...]',
            )
            return None
        registered: SkillFactory = factory
        if arguments is not None:
            registered = SelectedArguments(
                factory, picks, schema.parameter_names, [str(a) for a in arguments]
            )
        return SkillMapEntry(
            action=action,
            target=target if isinstance(target, str) else "",
            factory=registered,
            path=self.path,
            line=line,
            arguments=None if arguments is None else tuple(arguments),
            outcome_map=outcome_map,
            variant=variant,
        )

    def outcome_map(self, label: str, value: object, line: int | None) -> dict[str, str]:
        allowed = ", ".join(REQUIRED_OUTCOMES)
        if not isinstance(value, dict):
            self.problem(
                line,
                f"{label}: outcome_map must be a table of the skill's outcomes to one of "
                f'{allowed}, e.g. outcome_map = {{ blocked = "aborted" }}; got {_shown(value)}',
            )
            return {}
        result: dict[str, str] = {}
        for source, target in value.items():
            if not isinstance(target, str) or target not in REQUIRED_OUTCOMES:
                if isinstance(target, str):
                    shown = _toml_text(target) + _did_you_mean(target, REQUIRED_OUTCOMES)
                else:
                    shown = _shown(target)
                self.problem(
                    line,
                    f"{label}: outcome_map sends {source!r} to {shown}; a "
                    f"skill's outcome can only be mapped to {allowed}",
                )
                continue
            result[source] = target
        return result

    def arguments(
        self, label: str, schema: ActionSchema, value: object, line: int | None
    ) -> list[_Parameter | _Constant] | None:
        names = [name.lstrip("?").lower() for name in schema.parameter_names]
        shown = ", ".join(f"?{name}" for name in names) or "none"
        if value is None:
            return [_Parameter(i) for i in range(len(names))]
        if not isinstance(value, list):
            self.problem(
                line,
                f"{label}: arguments must be a list of the action's parameters (?name) and "
                f'constants, e.g. arguments = ["?{names[-1] if names else "x"}"]; got '
                f"{_shown(value)}; parameters of {schema.name}: {shown}",
            )
            return None
        picks: list[_Parameter | _Constant] = []
        ok = True
        for item in value:
            if isinstance(item, str) and item.startswith("?"):
                name = item[1:].lower()
                if name in names:
                    picks.append(_Parameter(names.index(name)))
                    continue
                guess = difflib.get_close_matches(name, names, n=1, cutoff=0.6)
                self.problem(
                    line,
                    f"{label}: arguments: {item} is not a parameter of {schema.name}"
                    + (f" (did you mean ?{guess[0]}?)" if guess else "")
                    + f"; parameters: {shown}",
                )
                ok = False
            elif isinstance(item, str) and item.lower() in names:
                self.problem(
                    line,
                    f"{label}: arguments: {item!r} is written like the parameter ?{item.lower()} "
                    f"without its '?'; write \"?{item.lower()}\" for the parameter (a constant "
                    f"cannot be spelled like a parameter of the action)",
                )
                ok = False
            elif isinstance(item, str | int | float | bool):
                picks.append(_Constant(item))
            else:
                self.problem(
                    line,
                    f"{label}: arguments: {_shown(item)} is neither a parameter (?name) nor a "
                    f"constant (a string, number or boolean); parameters: {shown}",
                )
                ok = False
        return picks if ok else None

    def factory(
        self, label: str, action: str, target: str, line: int | None
    ) -> SkillFactory | None:
        module_name, colon, attribute = target.partition(":")
        module_name, attribute = module_name.strip(), attribute.strip()
        if not colon or not module_name or not attribute:
            head, dot, tail = target.rpartition(".")
            example = (
                f"{head}:{tail}"
                if dot and head and tail
                else f"my_skills:make_{_identifier(action, 0)}"
            )
            self.problem(
                line,
                f'{label}: factory "{target}" is not "module:callable"; write the module '
                f'and the name in it, e.g. factory = "{example}"',
            )
            return None
        if not all(part.isidentifier() for part in module_name.split(".")):
            self.problem(line, f"{label}: factory {target}: {module_name!r} is not a module name")
            return None
        folder = self.path.parent
        try:
            module = _import(module_name, folder, self.package)
        except _FactoryImportError as exc:
            self.problem(line, f"{label}: factory {target}: {exc}")
            return None
        value: object = module
        for part in attribute.split("."):
            if not hasattr(value, part):
                where = f"module {module_name}" if value is module else _shown(value)
                names = _callables(value)
                self.problem(
                    line,
                    f"{label}: factory {target}: {where} ({_origin(module)}) has no attribute "
                    f"{part!r}{_did_you_mean(part, names)}; callables in it: "
                    f"{', '.join(names) or 'none'}",
                )
                return None
            value = getattr(value, part)
        if not callable(value):
            self.problem(
                line,
                f"{label}: factory {target} is {_shown(value)}, which is not callable; a "
                f"factory is a function or class that takes the action's arguments and "
                f"returns a smach.State",
            )
            return None
        factory: SkillFactory = value
        return factory

    def duplicates(self, entries: list[SkillMapEntry]) -> None:
        seen: dict[tuple[str, str], SkillMapEntry] = {}
        for entry in entries:
            key = (entry.action.lower(), entry.variant)
            first = seen.setdefault(key, entry)
            if first is entry:
                continue
            what = f"variant {entry.variant!r}" if entry.variant else "main skill (no variant)"
            self.problem(
                entry.line,
                f"[{entry.action}]: a second {what} for {entry.action!r} (the first is at line "
                f"{first.line}); give each [[{entry.action}]] entry but one a different "
                f'variant = "NAME"',
            )


def _syntax_problem(path: Path, message: str, text: str) -> MapProblem:
    """tomllib's message with its position as ``path:line:column``."""
    match = _TOML_POSITION.search(message)
    explanation = _TOML_POSITION.sub("", message)
    if _TOML_AT_END.search(explanation):
        explanation = _TOML_AT_END.sub(" at the end of the file", explanation)
        return MapProblem(str(path), max(len(text.splitlines()), 1), f"invalid TOML: {explanation}")
    if "twice" in explanation or "overwrite" in explanation.lower():
        explanation += (
            "; an action has one [action] table: for another way to perform it, write "
            '[[action]] entries with variant = "NAME"'
        )
    if explanation.startswith("Invalid value"):
        explanation += ' (text needs quotes: factory = "module:callable")'
    if match is None:
        return MapProblem(str(path), None, f"invalid TOML: {explanation}")
    return MapProblem(
        str(path), int(match.group(1)), f"invalid TOML: {explanation}", int(match.group(2))
    )


# -- where things are in the file -------------------------------------------------------

_KEY_PART = r"""(?:[A-Za-z0-9_-]+|"(?:[^"\\]|\\.)*"|'[^']*')"""
_KEY = rf"{_KEY_PART}(?:\s*\.\s*{_KEY_PART})*"
_HEADER = re.compile(rf"^\s*(\[\[|\[)\s*({_KEY})\s*\]\]?\s*(?:#.*)?$")
_ASSIGNMENT = re.compile(rf"^\s*({_KEY})\s*=")


class _Lines:
    """Line numbers of the entries and keys of a TOML text (tomllib gives none).

    Knows ``[action]``, ``[[action]]``, ``[action.sub]`` headers, keys in them and
    top-level ``action = ...`` / ``action.key = ...``; skips multi-line strings."""

    def __init__(self, text: str) -> None:
        #: action -> the line of each of its entries ([[action]]: one per element).
        self.entries: dict[str, list[int]] = {}
        self.keys: dict[tuple[str, int], dict[str, int]] = {}
        table: list[str] = []
        in_string: str | None = None
        for number, raw in enumerate(text.splitlines(), start=1):
            if in_string is not None:
                if raw.count(in_string) % 2 == 1:
                    in_string = None
                continue
            header = _HEADER.match(raw)
            if header is not None:
                path = _key_path(header.group(2))
                if not path:
                    continue
                action = path[0]
                if len(path) == 1:
                    lines = self.entries.setdefault(action, [])
                    if header.group(1) == "[[" or not lines:
                        lines.append(number)
                    else:
                        lines[0] = number
                else:
                    self.entries.setdefault(action, [number])
                    self._key(action, path[1], number)
                table = path
            else:
                assignment = _ASSIGNMENT.match(raw)
                if assignment is not None:
                    path = _key_path(assignment.group(1))
                    if path and not table:
                        self.entries.setdefault(path[0], [number])
                        if len(path) > 1:
                            self._key(path[0], path[1], number)
                    elif path and len(table) == 1:
                        self._key(table[0], path[0], number)
            for quote in ('"""', "'''"):
                if raw.count(quote) % 2 == 1:
                    in_string = quote
                    break

    def _key(self, action: str, key: str, number: int) -> None:
        index = max(len(self.entries.get(action, ())) - 1, 0)
        self.keys.setdefault((action, index), {}).setdefault(key, number)

    def entry(self, action: str, index: int = 0) -> int | None:
        lines = self.entries.get(action)
        if not lines:
            return None
        return lines[min(index, len(lines) - 1)]

    def at(self, action: str, index: int) -> _Where:
        return _Where(self.entry(action, index), self.keys.get((action, index), {}))


@dataclass(frozen=True)
class _Where:
    """The lines of one entry: its header (or top-level key) and its keys."""

    line: int | None
    keys: Mapping[str, int]

    def key(self, key: str) -> int | None:
        """The line of ``key`` in the entry (the entry's line if it is not on one)."""
        return self.keys.get(key, self.line)


def _key_path(key: str) -> list[str]:
    """The parts of a TOML key (``a."b.c"`` -> ["a", "b.c"])."""
    toml = _toml()
    if toml is None:  # pragma: no cover - Python 3.10
        return []
    try:
        data: Any = toml.loads(f"{key} = 0")
    except toml.TOMLDecodeError:
        return []
    parts: list[str] = []
    while isinstance(data, dict) and len(data) == 1:
        name, data = next(iter(data.items()))
        parts.append(name)
    return parts


# -- importing factories ---------------------------------------------------------------


class _FactoryImportError(Exception):
    pass


def _import(module_name: str, folder: Path, package: ModuleType | None) -> ModuleType:
    """``module_name`` from ``folder`` (as a submodule of the folder's package) or installed."""
    local = folder.joinpath(*module_name.split("."))
    file = local.with_suffix(".py")
    if file.is_file() or (local / "__init__.py").is_file():
        parent = package if hasattr(package, "__path__") else None
        parent = parent or _folder_package(folder)
        own = getattr(parent, "__file__", None)
        if own and file.is_file() and Path(own).resolve() == file.resolve():
            return parent  # the domain's skills.py, loaded as its package
        full = f"{parent.__name__}.{module_name}"
        shown = str(file if file.is_file() else local / "__init__.py")
    else:
        full = shown = module_name
    try:
        return importlib.import_module(full)
    except ModuleNotFoundError as exc:
        if exc.name is not None and (full == exc.name or full.startswith(exc.name + ".")):
            local_names = sorted(p.stem for p in folder.glob("*.py") if p.stem not in ("__init__",))
            raise _FactoryImportError(
                f"no module {module_name!r}: neither {file} in the map's folder nor an "
                f"installed module{_did_you_mean(module_name, local_names)}; modules in "
                f"{folder}: {', '.join(local_names) or 'none'}"
            ) from None
        raise _FactoryImportError(
            f"importing {shown} failed: {type(exc).__name__}: {exc}"
        ) from None
    except Exception as exc:
        raise _FactoryImportError(
            f"importing {shown} failed: {type(exc).__name__}: {exc}"
        ) from None


def _folder_package(folder: Path) -> ModuleType:
    """The package whose submodules are the folder's modules: the domain's package if
    :func:`~plan_bridge.missions.mission.load_target` imported it, else an empty one."""
    resolved = folder.resolve()
    for module in list(sys.modules.values()):
        paths = getattr(module, "__path__", None)
        if (
            module is not None
            and module.__name__.startswith(("plan_bridge_domain_", "plan_bridge_skill_map_"))
            and paths is not None
            and [Path(p).resolve() for p in paths] == [resolved]
        ):
            return module
    name = re.sub(r"\W", "_", resolved.name)
    name = f"plan_bridge_skill_map_{name}_{abs(hash(str(resolved)))}"
    spec = importlib.util.spec_from_loader(name, loader=None, is_package=True)
    assert spec is not None
    module = importlib.util.module_from_spec(spec)
    module.__path__ = [str(folder)]
    sys.modules[name] = module
    return module


# -- helpers ---------------------------------------------------------------------------


def _arity_problem(factory: SkillFactory, count: int) -> str | None:
    try:
        signature = inspect.signature(factory)
    except (TypeError, ValueError):
        return None
    try:
        signature.bind(*(["x"] * count))
    except TypeError as exc:
        shown = signature.replace(return_annotation=inspect.Signature.empty)
        return f"{_qualname(factory)}{shown}: {exc}"
    return None


def _qualname(factory: object) -> str:
    name = getattr(factory, "__qualname__", None) or getattr(factory, "__name__", None)
    return str(name) if name else repr(factory)


def _identifier(name: str, index: int) -> str:
    text = re.sub(r"\W", "_", name.lstrip("?"))
    if not text or not text.isidentifier():
        text = f"arg{index}"
    return text


def _did_you_mean(word: str, choices: Mapping[str, object] | Sequence[str]) -> str:
    close = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.6)
    return f" (did you mean {close[0]}?)" if close else ""


def _callables(value: object) -> list[str]:
    """The public callables of ``value``; of a module, those defined in it (not imported)."""
    if not hasattr(value, "__dict__"):
        return []
    own = value.__name__ if isinstance(value, ModuleType) else None
    return sorted(
        name
        for name, member in vars(value).items()
        if not name.startswith("_")
        and callable(member)
        and (own is None or getattr(member, "__module__", own) == own)
    )


def _origin(module: ModuleType) -> str:
    return str(getattr(module, "__file__", None) or module.__name__)


def _toml_text(value: object) -> str:
    """A value written as in TOML (close enough for messages)."""
    try:
        return json.dumps(value)
    except (TypeError, ValueError):
        return str(value)


def _shown(value: object) -> str:
    """A TOML value as a user wrote it, and what it is."""
    kinds = {str: "a string", bool: "a boolean", int: "an integer", float: "a number"}
    kind = kinds.get(type(value))
    if kind is not None:
        return f"{_toml_text(value)} ({kind})"
    if isinstance(value, list):
        return f"{_toml_text(value)} (a list)"
    if isinstance(value, dict):
        return "a table"
    return f"{value} ({type(value).__name__})"
