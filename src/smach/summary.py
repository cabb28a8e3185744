"""Bounded, JSON-safe summaries of values, for journals, viewers and event captures.

A core module (the event captures of :mod:`smach.events` hold summaries);
:mod:`smach.introspection.summary` re-exports it.

A summary is never a pickle: numbers, ``None`` and short strings as they are,
``repr`` cut to :data:`MAX_REPR` characters, containers cut to :data:`MAX_ITEMS`
items and :data:`MAX_DEPTH` levels.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

__all__ = ["MAX_DEPTH", "MAX_ITEMS", "MAX_REPR", "PLAIN", "Summary", "frozen", "summarise"]

MAX_REPR = 200
MAX_ITEMS = 20
MAX_DEPTH = 3

PLAIN = (str, int, float, bool, type(None))
"""The types whose values cannot change (a capture keeps them as they are)."""


def summarise(value: Any, depth: int = 0) -> Any:
    """A JSON-safe, size-bounded picture of ``value`` (never its pickle)."""
    if value is None or isinstance(value, bool | int | float):
        if isinstance(value, float) and not math.isfinite(value):  # JSON has no NaN/inf
            return repr(value)
        return value
    if isinstance(value, str):
        return value if len(value) <= MAX_REPR else value[:MAX_REPR] + "…"
    if depth >= MAX_DEPTH:
        return short_repr(value)
    if isinstance(value, Mapping):
        items = list(value.items())
        out = {str(k): summarise(v, depth + 1) for k, v in items[:MAX_ITEMS]}
        if len(items) > MAX_ITEMS:
            out["…"] = f"{len(items) - MAX_ITEMS} more"
        return out
    if isinstance(value, list | tuple | set | frozenset):
        seq = list(value)
        out_list = [summarise(v, depth + 1) for v in seq[:MAX_ITEMS]]
        if len(seq) > MAX_ITEMS:
            out_list.append(f"… {len(seq) - MAX_ITEMS} more")
        return out_list
    return short_repr(value)


def short_repr(value: Any) -> str:
    """``repr(value)`` cut to :data:`MAX_REPR` characters; never raises."""
    try:
        text = repr(value)
    except Exception as exc:  # a broken __repr__ must not break the journal
        text = f"<{type(value).__name__}: repr failed: {type(exc).__name__}>"
    return text if len(text) <= MAX_REPR else text[:MAX_REPR] + "…"


class Summary:
    """The summary of a value that could still change, made when an event happened.

    Event captures hold these instead of mutable values (a list written to the
    userdata and appended to later stays recorded as it was written).
    """

    __slots__ = ("value",)

    def __init__(self, value: Any) -> None:
        self.value = value

    def __repr__(self) -> str:
        return f"Summary({self.value!r})"

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Summary) and other.value == self.value

    __hash__ = None  # type: ignore[assignment]


def frozen(value: Any) -> Any:
    """``value`` if it cannot change (a plain value or a tuple of them), else its Summary."""
    kind = type(value)
    if kind in PLAIN or kind is Summary:
        return value
    if kind is tuple and all(type(v) in PLAIN for v in value):
        return value
    return Summary(summarise(value))
