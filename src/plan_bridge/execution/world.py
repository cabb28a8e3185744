"""The belief: what the executive thinks is true, as a set of ground PDDL facts.

Skills change it in two ways: a succeeded skill's action effects are applied, and
any skill may report observations (facts it saw to be true or false), which override
what was believed. An optional sensing port refreshes facts from outside. Steps of a
Concurrence update it from several threads, hence the lock.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Iterable, Iterator, Mapping
from typing import Any

from plan_bridge.pddl.task import Fact, FactLike, parse_fact

__all__ = ["Observation", "WorldState", "normalise_observations"]

Observation = tuple[Fact, bool]


def normalise_observations(value: Any) -> list[Observation]:
    """Accept observations as a mapping {fact: bool} or pairs [(fact, bool), ...].

    Facts may be tuples or PDDL text ``"(at cup table)"``.
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
        if not isinstance(truth, bool):
            raise ValueError(f"observation {item!r}: the truth value must be True or False")
        out.append((parse_fact(fact), truth))
    return out


class WorldState:
    """A thread-safe set of true ground facts (closed world: absent means false)."""

    def __init__(self, facts: Iterable[FactLike] = ()) -> None:
        self._facts: set[Fact] = {parse_fact(f) for f in facts}
        self._lock = threading.Lock()
        self.version = 0

    @property
    def facts(self) -> frozenset[Fact]:
        """A snapshot of the true facts."""
        with self._lock:
            return frozenset(self._facts)

    @contextlib.contextmanager
    def locked(self) -> Iterator[set[Fact]]:
        """The live set of facts, locked: read it inside the ``with`` block only."""
        with self._lock:
            yield self._facts

    def holds(self, fact: FactLike) -> bool:
        return parse_fact(fact) in self._facts

    def apply(self, adds: Iterable[Fact], deletes: Iterable[Fact]) -> None:
        """Apply effects: deletes first, then adds (PDDL semantics)."""
        with self._lock:
            self._facts.difference_update(deletes)
            self._facts.update(adds)
            self.version += 1

    def observe(self, observations: Iterable[Observation]) -> list[Observation]:
        """Record observations; returns those that changed the belief."""
        changed: list[Observation] = []
        with self._lock:
            for fact, truth in observations:
                if (fact in self._facts) != truth:
                    changed.append((fact, truth))
                    if truth:
                        self._facts.add(fact)
                    else:
                        self._facts.discard(fact)
            if changed:
                self.version += 1
        return changed

    def replace(self, facts: Iterable[Fact]) -> None:
        with self._lock:
            self._facts = set(facts)
            self.version += 1

    def __contains__(self, fact: object) -> bool:
        return fact in self._facts

    def __len__(self) -> int:
        return len(self._facts)

    def __repr__(self) -> str:
        return f"WorldState({len(self._facts)} facts)"
