"""Skill-map entries that bind a PDDL action to a ROS 2 action, service or topic.

::

    [drive]
    ros_action = "/courier/drive"                  # or ros_service = ..., ros_topic = ...
    type = "test_msgs/action/Fibonacci"            # resolved when the map is loaded
    goal = { order = "waypoints.yaml:?to" }        # field path -> value ("request" for a service)
    outcomes = { blocked = "sequence[0] == -1" }   # conditions on the result, in order
    outcome_map = { blocked = "aborted" }
    status = { canceled = "aborted" }              # the action's terminal status -> outcome
    timeout = 30.0                                 # seconds (action: exec timeout; service:
    server_wait = 10.0                             #   call timeout; topic: the wait)
    feedback = "last"                              # "last", "none" or a list of field paths

:func:`check_ros_entry` reads one such entry (called by the skill map's checks for an
entry with ``ros_action``, ``ros_service`` or ``ros_topic``): the type is imported,
every field path and condition is checked against the message definition, every
table lookup against the table's file and the problem's objects, every outcome
against ``outcome_map``; problems go to the map's list, each at its line. The
result is a :class:`RosEntry`, and the skill factory registered for it is a
:class:`~plan_bridge.skills.ros.skill_states.RosSkill`. docs/plan-bridge.md ("Skill
maps") describes the entries.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from plan_bridge.pddl.constructs import did_you_mean
from plan_bridge.skills.registry import REQUIRED_OUTCOMES
from plan_bridge.skills.ros.conditions import (
    Condition,
    parse_condition,
    substitute,
    template_parameters,
)
from plan_bridge.skills.ros.types import RosTypeError, field_at, resolve_interface, value_problem
from plan_bridge.skills.skill_map_source import shown_value, toml_text

if TYPE_CHECKING:
    from plan_bridge.pddl.task import ActionSchema
    from plan_bridge.skills.skill_map_source import EntryLines

__all__ = ["ROS_KEYS", "Fill", "RosEntry", "check_ros_entry", "is_ros_entry", "runs_on_ros"]

#: The keys that make an entry a ROS one, and the interface kind each needs.
ROS_KEYS = {"ros_action": "action", "ros_service": "srv", "ros_topic": "msg"}
_COMMON = ("type", "outcomes", "outcome_map", "timeout", "variant")
#: The keys each kind of entry may have.
KEYS = {
    "ros_action": ("ros_action", *_COMMON, "goal", "status", "server_wait", "feedback"),
    "ros_service": ("ros_service", *_COMMON, "request", "server_wait"),
    "ros_topic": ("ros_topic", *_COMMON),
}
#: An action's terminal statuses, as ``status`` names them.
STATUSES = ("succeeded", "aborted", "canceled")
DEFAULT_STATUS = {"succeeded": "succeeded", "aborted": "aborted", "canceled": "aborted"}
#: Seconds to wait for a server that is not up, unless ``server_wait`` says otherwise.
SERVER_WAIT = 10.0
#: Seconds a topic entry waits for its message, unless ``timeout`` says otherwise.
TOPIC_TIMEOUT = 10.0
FEEDBACK_MODES = ("last", "none")
_TABLE = re.compile(r"^(?P<file>[\w./-]+\.(?:ya?ml|json)):(?P<key>.+)$")
_NAME = re.compile(r"^/?(?:[A-Za-z_~{][\w{}?~-]*)(?:/[A-Za-z_{][\w{}?-]*)*$")


def runs_on_ros(folder: str | Path) -> bool:
    """Whether the skill map of the domain ``folder`` binds an action to ROS 2 (so a
    mission of it needs the robot's servers running: it is not a simulated mission)."""
    from plan_bridge.skills.skill_map_source import TomlError, read_toml

    path = Path(folder) / "skills.toml"
    try:
        data = read_toml(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, TomlError):
        return False
    entries = [
        v for value in data.values() for v in (value if isinstance(value, list) else [value])
    ]
    return any(isinstance(entry, dict) and is_ros_entry(entry) for entry in entries)


def is_ros_entry(element: Mapping[str, Any]) -> bool:
    """Whether a map entry binds its action to ROS 2 (has a ``ros_*`` key)."""
    return any(key in element for key in ROS_KEYS)


@dataclass(frozen=True)
class Fill:
    """One field of the goal or request and where its value comes from."""

    path: str
    shown: str
    """The value as written in the map."""
    constant: Any = None
    parameter: int | None = None
    """The action's argument at this index (``"?to"``), or the table key it picks."""
    template: str | None = None
    """A string with ``{?param}`` parts."""
    table: Mapping[str, Any] | None = None
    """A lookup: the table (keys lower case) and ``key`` or ``parameter``."""
    key: str = ""

    def value(self, arguments: Sequence[str], names: Mapping[str, str]) -> Any:
        """The value for a step with ``arguments`` (``names``: parameter -> argument)."""
        if self.table is not None:
            key = arguments[self.parameter] if self.parameter is not None else self.key
            return self.table[key.lower()]
        if self.parameter is not None:
            return arguments[self.parameter]
        if self.template is not None:
            return substitute(self.template, dict(names))
        return self.constant


@dataclass(frozen=True)
class RosEntry:
    """A checked ROS entry: what to call, with what, and how the answer maps to outcomes."""

    key: str
    """``ros_action``, ``ros_service`` or ``ros_topic``."""
    name: str
    """The action, service or topic name; ``{?param}`` parts are filled per step."""
    type_name: str
    interface: Any
    parameters: tuple[str, ...]
    """The PDDL action's parameter names, lower case, without ``?``."""
    fills: tuple[Fill, ...] = ()
    conditions: tuple[tuple[str, Condition], ...] = ()
    status: Mapping[str, str] = field(default_factory=lambda: dict(DEFAULT_STATUS))
    timeout: float | None = None
    server_wait: float = SERVER_WAIT
    feedback: str | tuple[str, ...] = "last"
    outcomes: tuple[str, ...] = REQUIRED_OUTCOMES
    """Every outcome the skill can return (the three, and those ``outcome_map`` maps)."""

    @property
    def kind(self) -> str:
        """``action``, ``service`` or ``topic``."""
        return self.key.removeprefix("ros_")

    def describe(self) -> str:
        """``ROS action /courier/drive (test_msgs/action/Fibonacci)``."""
        return f"ROS {self.kind} {self.name} ({self.type_name})"

    def ground_name(self, arguments: Sequence[str]) -> str:
        return substitute(self.name, self.names(arguments))

    def names(self, arguments: Sequence[str]) -> dict[str, str]:
        return dict(zip(self.parameters, arguments, strict=False))

    @property
    def sent_type(self) -> Any:
        """The class of what is sent (a goal, a request), None for a topic."""
        if self.key == "ros_action":
            return self.interface.Goal
        return self.interface.Request if self.key == "ros_service" else None

    @property
    def answer_type(self) -> Any:
        """The class conditions look at: the result, the response, the message."""
        if self.key == "ros_action":
            return self.interface.Result
        return self.interface.Response if self.key == "ros_service" else self.interface


Report = Callable[[int | None, str], None]


def check_ros_entry(
    schema: ActionSchema,
    element: Mapping[str, Any],
    where: EntryLines,
    label: str,
    *,
    folder: Path,
    objects_of_type: Callable[[str], Sequence[str]] | None,
    report: Report,
) -> RosEntry | None:
    """The entry ``element`` for ``schema``, checked (problems go to ``report(line,
    message)``); None when it has any."""
    return _EntryReader(schema, element, where, label, folder, objects_of_type, report).read()


class _EntryReader:
    def __init__(
        self,
        schema: ActionSchema,
        element: Mapping[str, Any],
        where: EntryLines,
        label: str,
        folder: Path,
        objects_of_type: Callable[[str], Sequence[str]] | None,
        report: Report,
    ) -> None:
        self.schema = schema
        self.element = element
        self.where = where
        self.label = label
        self.folder = folder
        self.objects_of_type = objects_of_type
        self._report = report
        self.failed = False
        self.parameters = tuple(name.lstrip("?").lower() for name in schema.parameter_names)
        self.types = {
            name.lstrip("?").lower(): p.type
            for name, p in zip(schema.parameter_names, schema.parameters, strict=False)
        }
        self.tables: dict[Path, Mapping[str, Any] | None] = {}

    def problem(self, key: str, message: str) -> None:
        self.failed = True
        self._report(self.where.key(key), f"{self.label}: {message}")

    # -- the entry ------------------------------------------------------------------------
    def read(self) -> RosEntry | None:
        kinds = [key for key in ROS_KEYS if key in self.element]
        if len(kinds) > 1 or "factory" in self.element:
            both = [*kinds, *(["factory"] if "factory" in self.element else [])]
            self.problem(
                both[1],
                f"{' and '.join(both)} in one entry; an entry runs one thing: a factory, a "
                f"ros_action, a ros_service or a ros_topic",
            )
            return None
        key = kinds[0]
        self.unknown_keys(key)
        name = self.interface_name(key)
        interface = self.interface(key)
        # The keys that need no type are checked whatever the type: every mistake at once.
        timeout = self.seconds("timeout", TOPIC_TIMEOUT if key == "ros_topic" else None)
        server_wait = self.seconds("server_wait", SERVER_WAIT)
        status = self.status(key)
        if interface is None or name is None:
            return None
        entry = RosEntry(key, name, str(self.element["type"]), interface, self.parameters)
        fills = self.fills(entry)
        conditions = self.conditions(entry)
        feedback = self.feedback(entry)
        named = [name for name, _ in conditions] + list(status.values())
        outcomes = self.outcomes(named, self.element.get("outcome_map", {}))
        if self.failed:
            return None
        return RosEntry(
            key,
            name,
            entry.type_name,
            interface,
            self.parameters,
            fills,
            conditions,
            status,
            timeout,
            server_wait if server_wait is not None else SERVER_WAIT,
            feedback,
            outcomes,
        )

    def unknown_keys(self, kind: str) -> None:
        allowed = KEYS[kind]
        for key in self.element:
            if key in allowed or key in ("factory", *ROS_KEYS):
                continue
            hint = ""
            if key in ("goal", "request"):
                right = (
                    "goal" if kind == "ros_action" else "request" if kind == "ros_service" else ""
                )
                hint = (
                    f" (a {kind.removeprefix('ros_')}'s message is {right!r})"
                    if right
                    else (" (a topic is only listened to: nothing is sent)")
                )
            elif key == "arguments":
                hint = (
                    ' (a ROS entry picks the action\'s arguments itself: write "?param" '
                    "in goal, request or outcomes)"
                )
            self.problem(
                key,
                f"unknown key {key!r} for a {kind} entry{did_you_mean(key, allowed)}{hint}; "
                f"allowed keys: {', '.join(allowed)}",
            )

    def interface_name(self, key: str) -> str | None:
        name = self.element[key]
        if not isinstance(name, str) or not _NAME.match(name.strip()):
            self.problem(
                key,
                f'{key} must be a ROS name such as "/courier/drive" ("{{?r}}" puts an '
                f"argument in it), got {shown_value(name)}",
            )
            return None
        for parameter in template_parameters(name):
            if parameter not in self.parameters:
                self.problem(
                    key, f"{key}: {{?{parameter}}} is not a parameter{self.shown_parameters()}"
                )
        return name.strip()

    def shown_parameters(self) -> str:
        return f" of {self.schema.name}; parameters: {', '.join('?' + p for p in self.parameters) or 'none'}"

    def interface(self, key: str) -> Any:
        type_name = self.element.get("type")
        kind = ROS_KEYS[key]
        if type_name is None:
            example = {
                "action": "nav2_msgs/action/NavigateToPose",
                "srv": "std_srvs/srv/SetBool",
                "msg": "std_msgs/msg/String",
            }[kind]
            self.problem(key, f'no type; add type = "{example}" (the {kind} type the server uses)')
            return None
        if not isinstance(type_name, str):
            self.problem(
                "type", f"type must be a string PACKAGE/{kind}/NAME, got {shown_value(type_name)}"
            )
            return None
        try:
            return resolve_interface(type_name, kind)
        except RosTypeError as exc:
            self.problem("type", str(exc))
            return None

    # -- the goal or request ------------------------------------------------------------------
    def fills(self, entry: RosEntry) -> tuple[Fill, ...]:
        key = {"ros_action": "goal", "ros_service": "request"}.get(entry.key)
        if key is None or key not in self.element:
            return ()
        table = self.element[key]
        if not isinstance(table, dict):
            self.problem(
                key,
                f'{key} must be a table of field paths to values, e.g. {key} = {{ "pose.header.frame_id" '
                f'= "map" }}, got {shown_value(table)}',
            )
            return ()
        fills = []
        for path, value in table.items():
            fill = self.fill(key, entry.sent_type, path, value)
            if fill is not None:
                fills.append(fill)
        return tuple(fills)

    def fill(self, key: str, message: Any, path: str, value: Any) -> Fill | None:
        where = f"{key}.{path}"
        try:
            target = field_at(message, path)
        except RosTypeError as exc:
            self.problem(where, f"{key} {toml_text(path)}: {exc}")
            return None
        shown = toml_text(value)
        if isinstance(value, str):
            lookup = _TABLE.match(value)
            if lookup is not None:
                return self.lookup(
                    where, key, path, target, value, lookup.group("file"), lookup.group("key")
                )
            if re.fullmatch(r"\?[\w-]+", value):
                index = self.parameter(where, f"{key} {toml_text(path)}", value)
                if index is None:
                    return None
                if target.kind != "string":
                    self.problem(
                        where,
                        f"{key} {toml_text(path)}: {value} is an object name (text), but the "
                        f"field is a {target.text}; look its value up in a table of the folder "
                        f'instead: "TABLE.yaml:{value}"',
                    )
                    return None
                return Fill(path, shown, parameter=index)
            if template_parameters(value):
                for name in template_parameters(value):
                    if name not in self.parameters:
                        self.problem(
                            where,
                            f"{key} {toml_text(path)}: {{?{name}}} is not a parameter{self.shown_parameters()}",
                        )
                        return None
                if target.kind != "string":
                    self.problem(
                        where,
                        f"{key} {toml_text(path)}: a text with {{?param}} fills a string field, not a {target.text}",
                    )
                    return None
                return Fill(path, shown, template=value)
        problem = value_problem(target, value)
        if problem is not None:
            self.problem(where, f"{key} {toml_text(path)}: {problem}")
            return None
        return Fill(path, shown, constant=value)

    def parameter(self, where: str, what: str, text: str) -> int | None:
        name = text[1:].lower()
        if name in self.parameters:
            return self.parameters.index(name)
        self.problem(
            where,
            f"{what}: {text} is not a parameter{did_you_mean(name, self.parameters)}{self.shown_parameters()}",
        )
        return None

    def lookup(
        self, where: str, key: str, path: str, target: Any, shown: str, file: str, picked: str
    ) -> Fill | None:
        what = f"{key} {toml_text(path)}"
        table = self.table(where, what, file)
        if table is None:
            return None
        index = None
        if picked.startswith("?"):
            index = self.parameter(where, what, picked)
            if index is None:
                return None
            wanted = self.objects(index)
            source = f"the objects of type {self.types[self.parameters[index]]} ({picked})"
        else:
            wanted, source = [picked], "the key"
        missing = [name for name in wanted if name.lower() not in table]
        if missing:
            keys = ", ".join(sorted(table)) or "none"
            self.problem(
                where,
                f"{what}: {file} has no entry for {', '.join(missing)} ({source}); its keys: {keys}",
            )
            return None
        for name in wanted:
            problem = value_problem(target, table[name.lower()])
            if problem is not None:
                self.problem(where, f"{what}: {file}: {name}: {problem}")
                return None
        if index is not None:
            return Fill(path, toml_text(shown), parameter=index, table=table)
        return Fill(path, toml_text(shown), table=table, key=picked)

    def objects(self, index: int) -> list[str]:
        """The problem's objects that can be the argument at ``index`` (none known: [])."""
        if self.objects_of_type is None:
            return []
        return list(self.objects_of_type(self.types[self.parameters[index]]))

    def table(self, where: str, what: str, file: str) -> Mapping[str, Any] | None:
        path = (self.folder / file).resolve()
        if path in self.tables:
            return self.tables[path]
        loaded = _load_table(path)
        if isinstance(loaded, str):
            self.problem(where, f"{what}: {loaded}")
            self.tables[path] = None
            return None
        self.tables[path] = loaded
        return loaded

    # -- outcomes -----------------------------------------------------------------------------
    def conditions(self, entry: RosEntry) -> tuple[tuple[str, Condition], ...]:
        value = self.element.get("outcomes", {})
        if not isinstance(value, dict):
            self.problem(
                "outcomes",
                f'outcomes must be a table of outcome = "condition", e.g. outcomes = {{ aborted = '
                f'"success == false" }}, got {shown_value(value)}',
            )
            return ()
        found = []
        for outcome, text in value.items():
            where = f"outcomes.{outcome}"
            if not isinstance(text, str):
                self.problem(
                    where,
                    f'outcomes: {outcome} = {shown_value(text)}: a condition is text, e.g. "success == false"',
                )
                continue
            try:
                found.append((outcome, parse_condition(text, entry.answer_type, self.parameters)))
            except RosTypeError as exc:
                self.problem(where, f"outcomes: {outcome}: {exc}")
        return tuple(found)

    def status(self, key: str) -> dict[str, str]:
        value = self.element.get("status", {})
        status = dict(DEFAULT_STATUS)
        if key != "ros_action":
            return status
        if not isinstance(value, dict):
            self.problem(
                "status",
                f'status must be a table, e.g. status = {{ canceled = "aborted" }}, got {shown_value(value)}',
            )
            return status
        for name, outcome in value.items():
            if name not in STATUSES:
                self.problem(
                    "status",
                    f"status: {name!r} is not a terminal status{did_you_mean(name, STATUSES)}; statuses: {', '.join(STATUSES)}",
                )
            elif not isinstance(outcome, str):
                self.problem(
                    "status", f"status: {name} = {shown_value(outcome)}: an outcome is text"
                )
            else:
                status[name] = outcome
        return status

    def outcomes(self, named: Sequence[str], outcome_map: object) -> tuple[str, ...]:
        mapped = outcome_map if isinstance(outcome_map, dict) else {}
        own: list[str] = list(REQUIRED_OUTCOMES)
        for outcome in named:
            if outcome in own:
                continue
            if outcome not in mapped:
                self.problem(
                    "outcomes" if "outcomes" in self.element else "status",
                    f"outcome {outcome!r} is not one of {', '.join(REQUIRED_OUTCOMES)}"
                    f"{did_you_mean(outcome, REQUIRED_OUTCOMES)}; map it with outcome_map = "
                    f'{{ {outcome} = "aborted" }} (or to another of them)',
                )
                continue
            own.append(outcome)
        for source in mapped:
            if source not in own:
                self.problem(
                    "outcome_map",
                    f"outcome_map names {source!r}, which no condition (outcomes) or status gives; "
                    f"outcomes of this entry: {', '.join(own)}",
                )
        return tuple(own)

    # -- the rest -------------------------------------------------------------------------------
    def seconds(self, key: str, default: float | None) -> float | None:
        value = self.element.get(key, default)
        if value is None:
            return None
        if isinstance(value, bool) or not isinstance(value, int | float) or value <= 0:
            self.problem(key, f"{key} must be a number of seconds > 0, got {shown_value(value)}")
            return default
        return float(value)

    def feedback(self, entry: RosEntry) -> str | tuple[str, ...]:
        value = self.element.get("feedback", "last")
        if isinstance(value, str) and value in FEEDBACK_MODES:
            return value
        if isinstance(value, list) and value and all(isinstance(v, str) for v in value):
            for path in value:
                try:
                    field_at(entry.interface.Feedback, path, indexes=True)
                except RosTypeError as exc:
                    self.problem("feedback", f"feedback {toml_text(path)}: {exc}")
            return tuple(value)
        self.problem(
            "feedback",
            f'feedback must be "last" (the latest message), "none", or a list of the '
            f"feedback's field paths to record, got {shown_value(value)}",
        )
        return "last"


def _load_table(path: Path) -> Mapping[str, Any] | str:
    """The table (a mapping, keys lower case) in ``path``, or why it cannot be read."""
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        return f"no table file {path} (a YAML or JSON file of names to values, next to skills.toml)"
    except (OSError, UnicodeDecodeError) as exc:
        return f"cannot read {path}: {exc}"
    try:
        if path.suffix == ".json":
            data = json.loads(text)
        else:
            import yaml

            data = yaml.safe_load(text)
    except ImportError:
        return f"reading {path.name} needs PyYAML (it comes with the ros extra)"
    except Exception as exc:
        return f"{path.name} is not valid {'JSON' if path.suffix == '.json' else 'YAML'}: {exc}"
    if not isinstance(data, dict):
        return f"{path.name} must hold a table of names to values at its top, not {type(data).__name__}"
    return {str(key).lower(): value for key, value in data.items()}
