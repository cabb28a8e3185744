"""ROS 2 interface types for skill-map entries: resolving ``pkg/kind/Name`` and
checking field paths and values against a message definition.

A ``skills.toml`` entry names its interface by the name ROS 2 tools use
(``type = "nav2_msgs/action/NavigateToPose"``). :func:`resolve_interface` imports it
when the map is loaded (the start of a mission, ``plan-bridge check``); a package
that is not installed is a :class:`RosTypeError` that names it and the command that
installs it. :func:`field_at` follows a field path (``pose.header.frame_id``,
``sequence[0]``) through the generated classes' ``get_fields_and_field_types()``,
and :func:`value_problem` says why a TOML or YAML value cannot fill a field. Nothing
here needs a running ROS graph: the generated Python classes describe themselves.

:func:`assign` and :func:`message_data` are what a running skill uses: filling a
goal or request from plain data, and turning a message into bounded plain data for
the journal and the viewer.
"""

from __future__ import annotations

import importlib
import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from importlib import metadata
from typing import Any

from plan_bridge.pddl.constructs import did_you_mean

__all__ = [
    "FieldType",
    "RosTypeError",
    "assign",
    "field_at",
    "install_hint",
    "message_data",
    "resolve_interface",
    "value_problem",
]

#: The interface kinds and the entry key that uses each.
KINDS = ("msg", "srv", "action")
_NAME = re.compile(r"^([A-Za-z][A-Za-z0-9_]*)/(msg|srv|action)/([A-Za-z][A-Za-z0-9_]*)$")
_INTS = frozenset(
    [
        "int8",
        "uint8",
        "int16",
        "uint16",
        "int32",
        "uint32",
        "int64",
        "uint64",
        "char",
        "short",
        "long",
        "byte",
    ]
)
_FLOATS = frozenset(("float", "double", "float32", "float64", "long double"))
_STRINGS = frozenset(("string", "wstring"))
#: Longest list and deepest nesting :func:`message_data` writes out.
DATA_ITEMS, DATA_DEPTH = 32, 8


class RosTypeError(Exception):
    """An interface name that does not resolve, or a field path or value that does not
    fit the message; the message says what is wrong and what is allowed."""


@dataclass(frozen=True)
class FieldType:
    """What a message field holds: ``bool``, ``int``, ``float``, ``string``,
    ``message`` (``message`` is its class), ``list`` (of ``element``) or ``other``."""

    kind: str
    text: str
    message: Any = None
    element: FieldType | None = None
    size: int | None = None
    """A fixed-size array's length (``double[36]``)."""

    def describe(self) -> str:
        return self.text


# -- resolving names -------------------------------------------------------------------


def install_hint(package: str) -> str:
    """How to install the ROS 2 message package ``package`` here."""
    dashed = package.replace("_", "-")
    for distribution, wheel in (
        ("ros-jazzy-rclpy", f"ros-jazzy-{dashed}"),
        ("ros-rclpy", f"ros-{dashed}"),
    ):
        try:
            metadata.version(distribution)
        except metadata.PackageNotFoundError:
            continue
        distro = "jazzy" if "jazzy" in distribution else "kilted"
        return (
            f"pip install {wheel} (where it is published on PyPI), or install "
            f"ros-{distro}-{dashed} with your ROS 2 distribution and source its setup.bash "
            f"before running"
        )
    sourced = os.environ.get("ROS_DISTRO")
    if sourced:
        return f"apt install ros-{sourced}-{dashed}, then source /opt/ros/{sourced}/setup.bash"
    return f'pip install "smach-planner[ros]" (rclpy), then pip install ros-jazzy-{dashed}'


def _ros_loaded() -> str | None:
    """None once rclpy is importable (loaded through smach.ros, which silences its
    generator's one known DeprecationWarning); else why not."""
    try:
        importlib.import_module("smach.ros.rclpy_api")
    except ImportError as exc:
        return str(exc)
    return None


def resolve_interface(name: str, kind: str) -> Any:
    """The generated class of the interface ``name`` (``pkg/kind/Name``), which must be of
    ``kind`` (``msg``, ``srv`` or ``action``); :class:`RosTypeError` otherwise."""
    match = _NAME.match(name.strip())
    if match is None:
        raise RosTypeError(
            f"type {name!r} is not a ROS 2 interface name; write PACKAGE/{kind}/NAME, e.g. "
            f"{_EXAMPLES[kind]!r}"
        )
    package, found_kind, type_name = match.groups()
    if found_kind != kind:
        raise RosTypeError(
            f"type {name} is {_ARTICLE[found_kind]}, but this entry needs {_ARTICLE[kind]} "
            f"(PACKAGE/{kind}/NAME)"
        )
    why = _ros_loaded()
    if why is not None:
        raise RosTypeError(f"type {name} cannot be resolved without rclpy: {why}")
    try:
        module = importlib.import_module(f"{package}.{kind}")
    except ModuleNotFoundError as exc:
        if exc.name in (package, f"{package}.{kind}"):
            missing = (
                f"the message package {package} is not installed"
                if exc.name == package
                else f"the package {package} has no {kind} interfaces"
            )
            raise RosTypeError(
                f"type {name}: {missing}; install it: {install_hint(package)}"
            ) from None
        raise RosTypeError(f"type {name}: importing {package}.{kind} failed: {exc}") from None
    except Exception as exc:
        raise RosTypeError(
            f"type {name}: importing {package}.{kind} failed: {type(exc).__name__}: {exc}"
        ) from None
    interface = getattr(module, type_name, None)
    if interface is None:
        names = sorted(n for n in dir(module) if n[:1].isupper() and "_" not in n)
        raise RosTypeError(
            f"type {name}: {package}/{kind} has no {type_name!r}"
            f"{did_you_mean(type_name, names)}; its {kind} types: {', '.join(names) or 'none'}"
        )
    return interface


_EXAMPLES = {
    "msg": "std_msgs/msg/String",
    "srv": "std_srvs/srv/SetBool",
    "action": "nav2_msgs/action/NavigateToPose",
}
_ARTICLE = {"msg": "a message", "srv": "a service", "action": "an action"}


# -- field paths -------------------------------------------------------------------------

_STEP = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)")


def _field_type(text: str) -> FieldType:
    """The :class:`FieldType` of a rosidl type string (``sequence<int32>``, ``double[36]``,
    ``geometry_msgs/Pose``, ``string<=10``)."""
    sequence = re.fullmatch(r"sequence<(.+?)(?:,\s*\d+)?>", text)
    if sequence is not None:
        return FieldType("list", text, element=_field_type(sequence.group(1)))
    array = re.fullmatch(r"(.+)\[(\d+)\]", text)
    if array is not None:
        return FieldType(
            "list", text, element=_field_type(array.group(1)), size=int(array.group(2))
        )
    base = text.split("<=", 1)[0]
    if base in ("boolean", "bool"):
        return FieldType("bool", text)
    if base in _INTS:
        return FieldType("int", text)
    if base in _FLOATS:
        return FieldType("float", text)
    if base in _STRINGS:
        return FieldType("string", text)
    if "/" in base:
        package, _, name = base.partition("/")
        module = importlib.import_module(f"{package}.msg")
        return FieldType("message", text, message=getattr(module, name.split("/")[-1]))
    return FieldType("other", text)


def fields_of(message: Any) -> dict[str, str]:
    """Field name -> rosidl type string of a generated message class."""
    fields: dict[str, str] = message.get_fields_and_field_types()
    return fields


def type_label(message: Any) -> str:
    """``pkg/msg/Name`` of a generated message class (its Python module says which);
    the parts of a service or action as ``std_srvs/srv/SetBool request``."""
    module = getattr(message, "__module__", "")
    package = module.split(".", 1)[0]
    kind = module.split(".")[1] if module.count(".") >= 1 else "msg"
    name = str(message.__name__)
    for part in ("Request", "Response", "Goal", "Result", "Feedback"):
        if kind != "msg" and name.endswith(f"_{part}"):
            return f"{package}/{kind}/{name.removesuffix('_' + part)} {part.lower()}"
    return f"{package}/{kind}/{name}"


def field_at(message: Any, path: str, *, indexes: bool = False) -> FieldType:
    """The type of the field at ``path`` (``pose.header.frame_id``; with ``indexes``,
    list items too: ``sequence[0]``) of the message class ``message``;
    :class:`RosTypeError` naming the first step that is not a field."""
    if not path or path.strip() != path:
        raise RosTypeError(f"{path!r} is not a field path; write field names joined by '.'")
    current = FieldType("message", type_label(message), message=message)
    for part in path.split("."):
        step = _STEP.fullmatch(part)
        if step is None or (step.group(2) and not indexes):
            allowed = "field names joined by '.'" + (" and [N] list items" if indexes else "")
            raise RosTypeError(f"{path!r} is not a field path: {part!r}; write {allowed}")
        if current.kind != "message":
            raise RosTypeError(
                f"{path!r}: {part!r} is below a field of type {current.text}, which has no fields"
            )
        fields = fields_of(current.message)
        name = step.group(1)
        if name not in fields:
            raise RosTypeError(
                f"{type_label(current.message)} has no field {name!r}"
                f"{did_you_mean(name, list(fields))}; its fields: {', '.join(fields) or 'none'}"
            )
        try:
            current = _field_type(fields[name])
        except ImportError as exc:
            raise RosTypeError(f"{path!r}: the type of {name} cannot be imported: {exc}") from None
        for _ in re.findall(r"\[\d+\]", step.group(2)):
            if current.kind != "list" or current.element is None:
                raise RosTypeError(f"{path!r}: {name} is a {current.text}, not a list")
            current = current.element
    return current


def value_problem(field: FieldType, value: object) -> str | None:
    """Why ``value`` (TOML or YAML data) cannot fill a field of type ``field``, or None."""
    kind = field.kind
    if kind == "bool":
        return None if isinstance(value, bool) else _wrong(field, value, "true or false")
    if kind == "int":
        ok = isinstance(value, int) and not isinstance(value, bool)
        return None if ok else _wrong(field, value, "an integer")
    if kind == "float":
        ok = isinstance(value, int | float) and not isinstance(value, bool)
        return None if ok else _wrong(field, value, "a number")
    if kind == "string":
        return None if isinstance(value, str) else _wrong(field, value, "a string")
    if kind == "list":
        if not isinstance(value, list):
            return _wrong(field, value, "a list")
        if field.size is not None and len(value) != field.size:
            return f"{field.text} needs exactly {field.size} items, got {len(value)}"
        assert field.element is not None
        for index, item in enumerate(value):
            problem = value_problem(field.element, item)
            if problem is not None:
                return f"item {index}: {problem}"
        return None
    if kind == "message":
        return _message_problem(field, value)
    return f"fields of type {field.text} cannot be set from a skill map"


def _message_problem(field: FieldType, value: object) -> str | None:
    if not isinstance(value, Mapping):
        return _wrong(
            field, value, f"a table of its fields ({', '.join(fields_of(field.message))})"
        )
    fields = fields_of(field.message)
    for key, item in value.items():
        if key not in fields:
            return (
                f"{type_label(field.message)} has no field {key!r}{did_you_mean(str(key), list(fields))}; "
                f"its fields: {', '.join(fields)}"
            )
        problem = value_problem(_field_type(fields[key]), item)
        if problem is not None:
            return f"{key}: {problem}"
    return None


def _wrong(field: FieldType, value: object, wanted: str) -> str:
    shown = repr(value) if not isinstance(value, Mapping) else "a table"
    return f"a {field.text} field needs {wanted}, got {shown}"


# -- at run time ------------------------------------------------------------------------------


def assign(message: Any, path: str, value: object) -> None:
    """Set the field at ``path`` of ``message`` (an instance) to ``value``: plain data,
    tables becoming the nested messages they describe."""
    *parents, last = path.split(".")
    target = message
    for name in parents:
        target = getattr(target, name)
    setattr(target, last, _converted(getattr(target, last), value, _slot_type(target, last)))


def _slot_type(message: Any, name: str) -> FieldType:
    return _field_type(fields_of(type(message))[name])


def _converted(current: Any, value: object, field: FieldType) -> Any:
    if field.kind == "message" and isinstance(value, Mapping):
        built = field.message()
        for key, item in value.items():
            setattr(built, key, _converted(getattr(built, key), item, _slot_type(built, key)))
        return built
    if field.kind == "float" and isinstance(value, int):
        return float(value)
    if field.kind == "list" and isinstance(value, list) and field.element is not None:
        element = field.element
        if element.kind == "message":
            return [_converted(None, item, element) for item in value]
        if element.kind == "float":
            return [float(item) for item in value]
    return value


def message_data(value: Any, depth: int = 0) -> Any:
    """A message as plain data (dicts, lists, numbers, text), lists cut at
    :data:`DATA_ITEMS` items and nesting at :data:`DATA_DEPTH`: what the journal keeps."""
    if depth > DATA_DEPTH:
        return "..."
    if hasattr(value, "get_fields_and_field_types"):
        return {
            name: message_data(getattr(value, name), depth + 1) for name in fields_of(type(value))
        }
    if hasattr(value, "tolist"):  # numpy arrays (fixed-size numeric fields)
        value = value.tolist()
    if isinstance(value, bytes | bytearray):
        return list(value[:DATA_ITEMS])
    if isinstance(value, Sequence) and not isinstance(value, str):
        items = [message_data(item, depth + 1) for item in list(value)[:DATA_ITEMS]]
        if len(value) > DATA_ITEMS:
            items.append(f"... {len(value) - DATA_ITEMS} more")
        return items
    return value
