"""Facts as the belief holds them: snapshots that carry numeric values, and observations.

An observation is a fact seen true or false, or a numeric atom seen with a value.
Snapshots (:class:`FactSnapshot`) are frozensets of ground facts that carry the numeric
atoms' values along, so everything that reads a state (conditions, the planner's
initial state for a replan) sees them.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

from plan_bridge.pddl.task import Fact, format_fact, parse_fact

__all__ = [
    "FactSnapshot",
    "Observation",
    "describe_observation",
    "normalise_observations",
    "values_of",
]

Observation = tuple[Fact, "bool | float"]
"""A fact seen true or false, or a numeric atom seen with a value (``(battery r1)``, 42.0)."""
_NO_VALUES: Mapping[Fact, float] = {}


class FactSnapshot(frozenset[Fact]):
    """The true facts at one moment, with the numeric atoms' values (``values``)."""

    values: Mapping[Fact, float]

    def __new__(
        cls, facts: Iterable[Fact] = (), values: Mapping[Fact, float] | None = None
    ) -> FactSnapshot:
        snapshot = super().__new__(cls, facts)
        snapshot.values = dict(values or {})
        return snapshot


def values_of(facts: object) -> Mapping[Fact, float]:
    """The numeric values a state carries (empty for a plain set of facts)."""
    values = getattr(facts, "values", None)
    return values if isinstance(values, Mapping) else _NO_VALUES


def normalise_observations(value: Any) -> list[Observation]:
    """Accept observations as a mapping {fact: bool} or pairs [(fact, bool), ...].

    Facts may be tuples or PDDL text ``"(at cup table)"``; a numeric atom is
    observed with a number instead of true/false: ``{"(battery r1)": 42.0}``.
    """
    if value is None:
        return []
    items: Iterable[Any] = value.items() if isinstance(value, Mapping) else value
    out: list[Observation] = []
    for item in items:
        try:
            fact, truth = item
        except (TypeError, ValueError) as exc:
            raise ValueError(
                f"observation {item!r} is not a (fact, true/false) pair; report observations "
                f"as {{'(at cup table)': True}} or [('(at cup table)', True)]"
            ) from exc
        if not isinstance(truth, (bool, int, float)):
            raise ValueError(
                f"observation {item!r}: the value must be True or False (a fact) or a "
                f"number (a numeric fluent such as (battery r1))"
            )
        out.append((parse_fact(fact), truth if isinstance(truth, bool) else float(truth)))
    return out


def describe_observation(fact: Fact, value: bool | float) -> str:
    """``(at cup table)``, ``not (at cup table)`` or ``(battery r1) = 42``."""
    if isinstance(value, bool):
        return ("" if value else "not ") + format_fact(fact)
    return f"{format_fact(fact)} = {value:g}"
