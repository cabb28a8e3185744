"""Where a skill map's pieces come from: the lines of its TOML text, and the modules
its factories are imported from.

:mod:`plan_bridge.skills.skill_map` checks a ``skills.toml`` entry by entry; this
module gives it what it checks against:

* :func:`read_toml` parses the text (tomllib, or tomli on Python 3.10), a syntax
  error becoming a :class:`TomlError` at ``line:column``; :class:`TomlLines` finds
  the line of every entry and key (tomllib gives none), so that each problem can be
  reported at its ``skills.toml:LINE``;
* :func:`import_factory` resolves ``"module:callable"``: the module from the map's
  folder (as a submodule of the domain folder's package) or among installed modules,
  then the callable in it, a failure becoming a :class:`FactoryImportError` that
  names what is there instead.

Split from :mod:`~plan_bridge.skills.skill_map` to keep modules short.
"""

from __future__ import annotations

import importlib
import importlib.util
import json
import re
import sys
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

from plan_bridge.pddl.constructs import did_you_mean

if TYPE_CHECKING:
    from plan_bridge.skills.registry import SkillFactory

__all__ = [
    "EntryLines",
    "FactoryImportError",
    "TomlError",
    "TomlLines",
    "factory_name",
    "import_factory",
    "parameter_identifier",
    "read_toml",
    "shown_value",
    "toml_text",
]


# -- reading the TOML text ----------------------------------------------------------------


class TomlError(Exception):
    """A text that cannot be read as TOML, at ``line`` and ``column`` when known."""

    def __init__(self, line: int | None, message: str, column: int | None = None) -> None:
        super().__init__(message)
        self.line = line
        self.message = message
        self.column = column


def read_toml(text: str) -> dict[str, Any]:
    """The TOML document ``text``; raises :class:`TomlError`."""
    toml = _toml()
    if toml is None:  # pragma: no cover - Python 3.10
        raise TomlError(None, "reading skill maps needs Python 3.11+ or tomli")
    try:
        data: dict[str, Any] = toml.loads(text)
    except toml.TOMLDecodeError as exc:
        raise _syntax_problem(str(exc), text) from None
    return data


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


def _syntax_problem(message: str, text: str) -> TomlError:
    """tomllib's message with its position as ``line:column``."""
    match = _TOML_POSITION.search(message)
    explanation = _TOML_POSITION.sub("", message)
    if _TOML_AT_END.search(explanation):
        explanation = _TOML_AT_END.sub(" at the end of the file", explanation)
        return TomlError(max(len(text.splitlines()), 1), f"invalid TOML: {explanation}")
    if "twice" in explanation or "overwrite" in explanation.lower():
        explanation += (
            "; an action has one [action] table: for another way to perform it, write "
            '[[action]] entries with variant = "NAME"'
        )
    if explanation.startswith("Invalid value"):
        explanation += ' (text needs quotes: factory = "module:callable")'
    if match is None:
        return TomlError(None, f"invalid TOML: {explanation}")
    return TomlError(int(match.group(1)), f"invalid TOML: {explanation}", int(match.group(2)))


def toml_text(value: object) -> str:
    """A value written as in TOML (close enough for messages)."""
    try:
        return json.dumps(value)
    except (TypeError, ValueError):
        return str(value)


def shown_value(value: object) -> str:
    """A TOML value as a user wrote it, and what it is."""
    kinds = {str: "a string", bool: "a boolean", int: "an integer", float: "a number"}
    kind = kinds.get(type(value))
    if kind is not None:
        return f"{toml_text(value)} ({kind})"
    if isinstance(value, list):
        return f"{toml_text(value)} (a list)"
    if isinstance(value, dict):
        return "a table"
    return f"{value} ({type(value).__name__})"


# -- where things are in the file -------------------------------------------------------

_KEY_PART = r"""(?:[A-Za-z0-9_-]+|"(?:[^"\\]|\\.)*"|'[^']*')"""
_KEY = rf"{_KEY_PART}(?:\s*\.\s*{_KEY_PART})*"
_HEADER = re.compile(rf"^\s*(\[\[|\[)\s*({_KEY})\s*\]\]?\s*(?:#.*)?$")
_ASSIGNMENT = re.compile(rf"^\s*({_KEY})\s*=")


class TomlLines:
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
                    elif path and len(table) == 2:  # [action.goal]: "goal.FIELD"
                        self._key(table[0], f"{table[1]}.{'.'.join(path)}", number)
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

    def at(self, action: str, index: int) -> EntryLines:
        return EntryLines(self.entry(action, index), self.keys.get((action, index), {}))


@dataclass(frozen=True)
class EntryLines:
    """The lines of one entry: its header (or top-level key) and its keys."""

    line: int | None
    keys: Mapping[str, int]

    def key(self, key: str) -> int | None:
        """The line of ``key`` in the entry (the entry's line if it is not on one); a
        key of a sub-table (``goal.pose``) falls back to the sub-table's line."""
        if key in self.keys:
            return self.keys[key]
        head = key.split(".", 1)[0]
        return self.keys.get(head, self.line)


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


class FactoryImportError(Exception):
    """A ``"module:callable"`` that names no callable; the message says what is there."""


def import_factory(
    target: str, module_name: str, attribute: str, folder: Path, package: ModuleType | None
) -> SkillFactory:
    """The callable ``attribute`` (dotted) of ``module_name``, looked up in ``folder``
    first (as a submodule of ``package``, else of the folder's package), then among
    installed modules. Raises :class:`FactoryImportError` naming ``target``."""
    try:
        module = _import(module_name, folder, package)
    except FactoryImportError as exc:
        raise FactoryImportError(f"factory {target}: {exc}") from None
    value: object = module
    for part in attribute.split("."):
        if not hasattr(value, part):
            where = f"module {module_name}" if value is module else shown_value(value)
            names = _callables(value)
            raise FactoryImportError(
                f"factory {target}: {where} ({_origin(module)}) has no attribute "
                f"{part!r}{did_you_mean(part, names)}; callables in it: "
                f"{', '.join(names) or 'none'}"
            )
        value = getattr(value, part)
    if not callable(value):
        raise FactoryImportError(
            f"factory {target} is {shown_value(value)}, which is not callable; a "
            f"factory is a function or class that takes the action's arguments and "
            f"returns a smach.State"
        )
    factory: SkillFactory = value
    return factory


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
            raise FactoryImportError(
                f"no module {module_name!r}: neither {file} in the map's folder nor an "
                f"installed module{did_you_mean(module_name, local_names)}; modules in "
                f"{folder}: {', '.join(local_names) or 'none'}"
            ) from None
        raise FactoryImportError(f"importing {shown} failed: {type(exc).__name__}: {exc}") from None
    except Exception as exc:
        raise FactoryImportError(f"importing {shown} failed: {type(exc).__name__}: {exc}") from None


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


def factory_name(factory: object) -> str:
    """A factory's qualified name (its repr if it has none), for messages."""
    name = getattr(factory, "__qualname__", None) or getattr(factory, "__name__", None)
    return str(name) if name else repr(factory)


def parameter_identifier(name: str, index: int) -> str:
    """A Python identifier for the action's parameter ``name`` (``?to`` -> ``to``), or
    ``arg{index}``."""
    text = re.sub(r"\W", "_", name.lstrip("?"))
    if not text or not text.isidentifier():
        text = f"arg{index}"
    return text
