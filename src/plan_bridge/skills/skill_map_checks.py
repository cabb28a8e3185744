"""Checking a skill map: each entry of a ``skills.toml`` against the domain's actions.

:func:`check_skill_map` is what :func:`~plan_bridge.skills.skill_map.load_skill_map`
runs on the text it read: every action named is one of the domain's, every key is
one an entry may have, ``arguments`` name the action's parameters, ``outcome_map``
maps to the required outcomes, each factory imports and takes the arguments it is
given, and each action has one main skill and one of each variant. Every problem
found is collected, at its ``skills.toml:LINE``, into one
:class:`~plan_bridge.skills.skill_map.SkillMapError`.

Split from :mod:`~plan_bridge.skills.skill_map` to keep modules short; where things
are in the file and how factories are imported is
:mod:`~plan_bridge.skills.skill_map_source`.
"""

from __future__ import annotations

import difflib
import inspect
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

from plan_bridge.pddl.constructs import did_you_mean
from plan_bridge.skills.registry import REQUIRED_OUTCOMES, SkillFactory
from plan_bridge.skills.ros.entries import ROS_KEYS, check_ros_entry, is_ros_entry
from plan_bridge.skills.ros.skill_states import RosSkill
from plan_bridge.skills.skill_map_model import (
    ENTRY_KEYS,
    ConstantPick,
    MapProblem,
    ParameterPick,
    SelectedArguments,
    SkillMap,
    SkillMapEntry,
    SkillMapError,
)
from plan_bridge.skills.skill_map_source import (
    EntryLines,
    FactoryImportError,
    TomlError,
    TomlLines,
    factory_name,
    import_factory,
    parameter_identifier,
    read_toml,
    shown_value,
    toml_text,
)

if TYPE_CHECKING:
    from plan_bridge.pddl.task import ActionSchema
    from plan_bridge.skills.skill_map_model import HasActions

__all__ = ["check_skill_map"]


def check_skill_map(
    path: Path, text: str, task: HasActions, package: ModuleType | None
) -> SkillMap:
    """The skill map ``text`` (read from ``path``), checked against ``task``'s actions
    and resolved (factories imported); raises :class:`SkillMapError` with every
    problem found."""
    return _Reader(path, text, task, package).read()


class _Reader:
    def __init__(self, path: Path, text: str, task: HasActions, package: ModuleType | None) -> None:
        self.path = path
        self.text = text
        self.actions = {name.lower(): schema for name, schema in task.actions.items()}
        self.package = package
        self.problems: list[MapProblem] = []
        #: The problem's objects of a type (None: not known, e.g. `skills` on the front end).
        self.objects_of_type = getattr(task, "objects_of_type", None)

    def problem(self, line: int | None, message: str) -> None:
        self.problems.append(MapProblem(str(self.path), line, message))

    def read(self) -> SkillMap:
        try:
            data = read_toml(self.text)
        except TomlError as exc:
            raise SkillMapError(
                [MapProblem(str(self.path), exc.line, exc.message, exc.column)]
            ) from None
        lines = TomlLines(self.text)
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
                    f"{action} = {shown_value(value)}: an entry is a table ([{action}] with "
                    f'factory = "module:callable") or the factory alone '
                    f'({action} = "module:callable")',
                )
                continue
            schema = self.actions.get(action.lower())
            if schema is None:
                self.problem(
                    lines.entry(action),
                    f"[{action}]: the domain has no action {action!r}"
                    f"{did_you_mean(action.lower(), self.actions)}; actions: "
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
        self, schema: ActionSchema, element: dict[str, Any], where: EntryLines
    ) -> SkillMapEntry | None:
        if is_ros_entry(element):
            return self.ros_entry(schema, element, where)
        action = schema.name
        line = where.line
        at = where.key

        before = len(self.problems)
        misspelled = set()
        for key in element:
            if key not in ENTRY_KEYS:
                misspelled.update(difflib.get_close_matches(key, ENTRY_KEYS, n=1, cutoff=0.6))
                if difflib.get_close_matches(key, ROS_KEYS, n=1, cutoff=0.6):
                    misspelled.add("factory")  # a misspelled ros_* key: no factory expected
                hint = ""
                if key.lower() in self.actions:
                    hint = (
                        f'; {key!r} is an action: a short entry ({key} = "module:callable") '
                        f"belongs before the first [table], as keys after a header are that "
                        f"table's; or write [{key}] with factory = ..."
                    )
                self.problem(
                    at(key),
                    f"[{action}]: unknown key {key!r}{did_you_mean(key, (*ENTRY_KEYS, *ROS_KEYS))}; "
                    f"allowed keys: {', '.join(ENTRY_KEYS)} (a ROS entry: "
                    f"{', '.join(ROS_KEYS)} with type){hint}",
                )
        variant = self.variant(action, element, at("variant"))
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
                f"that takes the action's arguments and returns a smach.State), or bind the "
                f'action to ROS 2 with ros_action, ros_service or ros_topic and type = "..."',
            )
        elif not isinstance(target, str):
            self.problem(
                at("factory"),
                f'{label}: factory must be a string "module:callable", got {shown_value(target)}',
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
                else f"{count} argument(s) (arguments = {toml_text(arguments)})"
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

    def variant(self, action: str, element: dict[str, Any], line: int | None) -> str:
        variant = element.get("variant", "")
        if not isinstance(variant, str) or ("variant" in element and not variant.strip()):
            self.problem(
                line,
                f"[{action}]: variant must be a non-empty string naming another way to "
                f'perform the action (e.g. variant = "careful"), got {shown_value(variant)}',
            )
            return ""
        return variant

    def ros_entry(
        self, schema: ActionSchema, element: dict[str, Any], where: EntryLines
    ) -> SkillMapEntry | None:
        """An entry with ros_action, ros_service or ros_topic (see
        :mod:`~plan_bridge.skills.ros.entries`)."""
        before = len(self.problems)
        variant = self.variant(schema.name, element, where.key("variant"))
        label = f"[{schema.name}]" + (f" variant {variant!r}" if variant else "")
        outcome_map = self.outcome_map(
            label, element.get("outcome_map", {}), where.key("outcome_map")
        )
        entry = check_ros_entry(
            schema,
            element,
            where,
            label,
            folder=self.path.parent,
            objects_of_type=self.objects_of_type,
            report=self.problem,
        )
        if entry is None or len(self.problems) > before:
            return None
        return SkillMapEntry(
            action=schema.name,
            target=f"{entry.key} {entry.name}",
            factory=RosSkill(entry),
            path=self.path,
            line=where.line,
            outcome_map=outcome_map,
            variant=variant,
            ros=entry,
        )

    def outcome_map(self, label: str, value: object, line: int | None) -> dict[str, str]:
        allowed = ", ".join(REQUIRED_OUTCOMES)
        if not isinstance(value, dict):
            self.problem(
                line,
                f"{label}: outcome_map must be a table of the skill's outcomes to one of "
                f'{allowed}, e.g. outcome_map = {{ blocked = "aborted" }}; got {shown_value(value)}',
            )
            return {}
        result: dict[str, str] = {}
        for source, target in value.items():
            if not isinstance(target, str) or target not in REQUIRED_OUTCOMES:
                if isinstance(target, str):
                    shown = toml_text(target) + did_you_mean(target, REQUIRED_OUTCOMES)
                else:
                    shown = shown_value(target)
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
    ) -> list[ParameterPick | ConstantPick] | None:
        names = [name.lstrip("?").lower() for name in schema.parameter_names]
        shown = ", ".join(f"?{name}" for name in names) or "none"
        if value is None:
            return [ParameterPick(i) for i in range(len(names))]
        if not isinstance(value, list):
            self.problem(
                line,
                f"{label}: arguments must be a list of the action's parameters (?name) and "
                f'constants, e.g. arguments = ["?{names[-1] if names else "x"}"]; got '
                f"{shown_value(value)}; parameters of {schema.name}: {shown}",
            )
            return None
        picks: list[ParameterPick | ConstantPick] = []
        ok = True
        for item in value:
            if isinstance(item, str) and item.startswith("?"):
                name = item[1:].lower()
                if name in names:
                    picks.append(ParameterPick(names.index(name)))
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
                picks.append(ConstantPick(item))
            else:
                self.problem(
                    line,
                    f"{label}: arguments: {shown_value(item)} is neither a parameter (?name) nor a "
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
                else f"my_skills:make_{parameter_identifier(action, 0)}"
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
        try:
            return import_factory(target, module_name, attribute, self.path.parent, self.package)
        except FactoryImportError as exc:
            self.problem(line, f"{label}: {exc}")
            return None

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


def _arity_problem(factory: SkillFactory, count: int) -> str | None:
    try:
        signature = inspect.signature(factory)
    except (TypeError, ValueError):
        return None
    try:
        signature.bind(*(["x"] * count))
    except TypeError as exc:
        shown = signature.replace(return_annotation=inspect.Signature.empty)
        return f"{factory_name(factory)}{shown}: {exc}"
    return None
