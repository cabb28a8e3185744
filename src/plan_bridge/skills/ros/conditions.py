"""Conditions on the fields of a ROS 2 message, as a skill map writes them.

An entry's ``outcomes`` table maps an outcome to a condition on the result (an
action), the response (a service) or the message (a topic)::

    outcomes = { aborted = "success == false", blocked = "error_code == 102 or error_code == 103" }

A condition is comparisons ``FIELD OP VALUE`` joined by ``and`` and ``or`` (``and``
binds tighter; no parentheses). ``FIELD`` is a field path (``pose.position.x``,
``sequence[0]``), ``OP`` one of ``== != < <= > >=``, ``VALUE`` a number, ``true``,
``false``, a quoted string (``"{?item}"`` puts an argument of the action into it) or
a parameter of the action (``?item``). :func:`parse_condition` checks every path and
value against the message class when the map is loaded; :meth:`Condition.holds` is
evaluated on each message at run time.
"""

from __future__ import annotations

import operator
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from plan_bridge.skills.ros.types import RosTypeError, field_at

__all__ = [
    "Comparison",
    "Condition",
    "lookup",
    "parse_condition",
    "substitute",
    "template_parameters",
]

_OPERATORS: dict[str, Callable[[Any, Any], bool]] = {
    "==": operator.eq,
    "!=": operator.ne,
    "<=": operator.le,
    ">=": operator.ge,
    "<": operator.lt,
    ">": operator.gt,
}
_TOKEN = re.compile(
    r"""\s*(?:
        (?P<op>==|!=|<=|>=|<|>)
      | (?P<string>"(?:[^"\\]|\\.)*"|'[^']*')
      | (?P<number>-?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?)
      | (?P<param>\?[A-Za-z_][\w-]*)
      | (?P<word>[A-Za-z_][\w]*(?:\[\d+\])*(?:\.[A-Za-z_]\w*(?:\[\d+\])*)*)
    )""",
    re.VERBOSE,
)
_TEMPLATE = re.compile(r"\{\?([A-Za-z_][\w-]*)\}")


def substitute(text: str, arguments: dict[str, str]) -> str:
    """``text`` with each ``{?param}`` replaced by that argument."""
    return _TEMPLATE.sub(lambda m: arguments.get(m.group(1).lower(), m.group(0)), text)


def template_parameters(text: str) -> list[str]:
    """The parameters ``{?name}`` in ``text`` (lower case)."""
    return [name.lower() for name in _TEMPLATE.findall(text)]


@dataclass(frozen=True)
class Comparison:
    """``path OP value``; ``value`` is a constant, or ``("?", name)`` for a parameter."""

    path: str
    op: str
    value: Any
    parameter: str = ""
    """The action's parameter compared with (``?item``), lower case; ``""``: a constant."""

    def holds(self, message: Any, arguments: dict[str, str]) -> bool:
        try:
            found = lookup(message, self.path)
        except (AttributeError, IndexError):
            return False
        wanted = arguments.get(self.parameter, "") if self.parameter else self.value
        if isinstance(wanted, str):
            wanted = substitute(wanted, arguments)
        try:
            return bool(_OPERATORS[self.op](found, wanted))
        except TypeError:
            return False


@dataclass(frozen=True)
class Condition:
    """Comparisons: any of the groups holds when all of its comparisons hold."""

    text: str
    groups: tuple[tuple[Comparison, ...], ...]

    def holds(self, message: Any, arguments: dict[str, str]) -> bool:
        return any(all(c.holds(message, arguments) for c in group) for group in self.groups)

    @property
    def parameters(self) -> list[str]:
        names = [c.parameter for group in self.groups for c in group if c.parameter]
        for group in self.groups:
            for c in group:
                if isinstance(c.value, str):
                    names.extend(template_parameters(c.value))
        return names


def lookup(message: Any, path: str) -> Any:
    """The value at ``path`` (``a.b[0].c``) of a message; AttributeError or IndexError
    when it has none."""
    value = message
    for part in path.split("."):
        name, _, rest = part.partition("[")
        value = getattr(value, name)
        for index in re.findall(r"\[(\d+)\]", "[" + rest if rest else ""):
            value = value[int(index)]
    return value


def parse_condition(text: str, message: Any, parameters: Sequence[str]) -> Condition:
    """The condition ``text`` on fields of the message class ``message``, for an action
    with ``parameters`` (names without ``?``); :class:`RosTypeError` saying what is
    wrong (a field that does not exist, a value of another type, bad syntax)."""
    tokens = _tokens(text)
    groups: list[tuple[Comparison, ...]] = []
    group: list[Comparison] = []
    position = 0
    while True:
        if len(tokens) - position < 3:
            raise RosTypeError(
                f"condition {text!r} is incomplete; write FIELD OP VALUE (OP: == != < <= > >=), "
                f"joined by and / or"
            )
        group.append(_comparison(text, tokens[position : position + 3], message, parameters))
        position += 3
        if position == len(tokens):
            groups.append(tuple(group))
            return Condition(text, tuple(groups))
        kind, word = tokens[position]
        if kind != "word" or word not in ("and", "or"):
            raise RosTypeError(
                f"condition {text!r}: expected and / or after a comparison, got {word!r}"
            )
        if word == "or":
            groups.append(tuple(group))
            group = []
        position += 1


def _tokens(text: str) -> list[tuple[str, str]]:
    tokens: list[tuple[str, str]] = []
    position = 0
    stripped = text.rstrip()
    while position < len(stripped):
        match = _TOKEN.match(stripped, position)
        if match is None or match.end() == position:
            raise RosTypeError(
                f"condition {text!r}: cannot read {stripped[position:].strip()[:20]!r}; write "
                f'FIELD OP VALUE, VALUE a number, true, false, a "quoted string" or ?param'
            )
        kind = match.lastgroup or ""
        tokens.append((kind, match.group(kind)))
        position = match.end()
    return tokens


def _comparison(
    text: str, tokens: list[tuple[str, str]], message: Any, parameters: Sequence[str]
) -> Comparison:
    (path_kind, path), (op_kind, op), (value_kind, raw) = tokens
    if path_kind != "word" or path in ("and", "or", "true", "false"):
        raise RosTypeError(f"condition {text!r}: {path!r} is not a field path")
    if op_kind != "op":
        raise RosTypeError(f"condition {text!r}: expected == != < <= > >= after {path}, got {op!r}")
    try:
        field = field_at(message, path, indexes=True)
    except RosTypeError as exc:
        raise RosTypeError(f"condition {text!r}: {exc}") from None
    names = [p.lower() for p in parameters]
    parameter = ""
    value: Any
    if value_kind == "param":
        parameter = raw[1:].lower()
        if parameter not in names:
            raise RosTypeError(
                f"condition {text!r}: {raw} is not a parameter of the action; parameters: "
                f"{', '.join('?' + n for n in names) or 'none'}"
            )
        value, wanted = "", "string"
    elif value_kind == "string":
        value, wanted = _unquote(raw), "string"
        for name in template_parameters(value):
            if name not in names:
                raise RosTypeError(
                    f"condition {text!r}: {{?{name}}} is not a parameter of the action"
                )
    elif value_kind == "number":
        value = float(raw) if any(c in raw for c in ".eE") else int(raw)
        wanted = "number"
    elif value_kind == "word" and raw in ("true", "false"):
        value, wanted = raw == "true", "bool"
    else:
        raise RosTypeError(
            f"condition {text!r}: {raw!r} is not a value; write a number, true, false, a "
            f'"quoted string" or ?param'
        )
    _check_types(text, path, field.kind, field.text, op, wanted)
    return Comparison(path, op, value, parameter)


def _check_types(text: str, path: str, kind: str, shown: str, op: str, wanted: str) -> None:
    fits = {
        "string": ("string",),
        "number": ("int", "float"),
        "bool": ("bool",),
    }[wanted]
    if kind not in fits:
        raise RosTypeError(
            f"condition {text!r}: {path} is a {shown} field, compared with a {wanted}"
        )
    if kind == "bool" and op not in ("==", "!="):
        raise RosTypeError(f"condition {text!r}: {path} is a boolean: compare it with == or !=")


def _unquote(raw: str) -> str:
    if raw.startswith('"'):
        return re.sub(r"\\(.)", r"\1", raw[1:-1])
    return raw[1:-1]
