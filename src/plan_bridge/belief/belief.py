"""The belief: what the executive thinks is true of the world.

The belief is a set of ground PDDL facts (closed world: absent means false).

Skills change it in two ways: a succeeded skill's action effects are applied, and
any skill may report observations (facts it saw to be true or false), which override
what was believed. An optional sensing port refreshes facts from outside. Steps of a
Concurrence update it from several threads, hence the lock.

Numeric fluents (``(battery r1)``) are part of the belief too: :attr:`Belief.values`
maps ground numeric atoms to numbers. Snapshots (:attr:`Belief.facts`) are
:class:`~plan_bridge.belief.facts.FactSnapshot` frozensets that carry those values.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable, Iterable, Iterator, Mapping

from plan_bridge.belief.facts import FactSnapshot, Observation, values_of
from plan_bridge.belief.whereabouts import locate
from plan_bridge.pddl.task import Fact, FactLike, parse_fact

__all__ = ["Belief"]


class _LiveFacts(set[Fact]):
    """The belief's live set of facts; ``values`` holds the numeric atoms."""

    values: dict[Fact, float]


class Belief:
    """A thread-safe set of true ground facts (closed world: absent means false)."""

    def __init__(
        self,
        facts: Iterable[FactLike] = (),
        values: Mapping[Fact, float] | None = None,
        *,
        whereabouts: bool = False,
    ) -> None:
        #: Things are at one place, and a thing looked for and not seen is lost, with
        #: where it is not (:mod:`~plan_bridge.belief.whereabouts`): a world with a map.
        self.whereabouts = whereabouts
        self._facts = _LiveFacts(parse_fact(f) for f in facts)
        self._facts.values = dict(values if values is not None else values_of(facts))
        self._lock = threading.Lock()
        self.version = 0
        self._listeners: list[Callable[[], None]] = []

    @property
    def facts(self) -> FactSnapshot:
        """A snapshot of the true facts (and of the numeric values)."""
        with self._lock:
            return FactSnapshot(self._facts, self._facts.values)

    @property
    def values(self) -> dict[Fact, float]:
        """A copy of the numeric atoms' values."""
        with self._lock:
            return dict(self._facts.values)

    def set_values(self, values: Mapping[Fact, float]) -> None:
        """Set numeric atoms (numeric effects, or a sensed battery level)."""
        if not values:
            return
        with self._lock:
            self._facts.values.update(values)
            self.version += 1
        self._changed()

    @contextlib.contextmanager
    def locked(self) -> Iterator[set[Fact]]:
        """The live set of facts, locked: read it inside the ``with`` block only."""
        with self._lock:
            yield self._facts

    def add_listener(self, listener: Callable[[], None]) -> None:
        """Call ``listener()`` after every change (from the changing thread, unlocked):
        how a running durative action watches its over-all conditions without polling."""
        with self._lock:
            self._listeners = [*self._listeners, listener]

    def remove_listener(self, listener: Callable[[], None]) -> None:
        """Stop calling ``listener``. Compared by equality: ``obj.method`` makes a new
        bound method at every access, equal to (not the same as) the one added."""
        with self._lock:
            self._listeners = [cb for cb in self._listeners if cb != listener]

    def _changed(self) -> None:
        for listener in self._listeners:  # a copy-on-write list: no lock needed
            listener()

    def holds(self, fact: FactLike) -> bool:
        return parse_fact(fact) in self._facts

    def apply(self, adds: Iterable[Fact], deletes: Iterable[Fact]) -> None:
        """Apply effects: deletes first, then adds (PDDL semantics)."""
        with self._lock:
            self._facts.difference_update(deletes)
            self._facts.update(adds)
            self.version += 1
        self._changed()

    def observe(self, observations: Iterable[Observation]) -> list[Observation]:
        """Record observations; returns those that changed the belief."""
        changed: list[Observation] = []
        with self._lock:
            if self.whereabouts:
                observations = locate(self._facts, list(observations))
            for fact, truth in observations:
                if not isinstance(truth, bool):
                    if self._facts.values.get(fact) != truth:
                        changed.append((fact, truth))
                        self._facts.values[fact] = truth
                    continue
                if (fact in self._facts) != truth:
                    changed.append((fact, truth))
                    if truth:
                        self._facts.add(fact)
                    else:
                        self._facts.discard(fact)
            if changed:
                self.version += 1
        if changed:
            self._changed()
        return changed

    def forget_values(self, atoms: Iterable[Fact]) -> list[Fact]:
        """Drop numeric atoms' values (they become unknown); returns those that had one."""
        with self._lock:
            forgotten = [
                a for a in dict.fromkeys(atoms) if self._facts.values.pop(a, None) is not None
            ]
            if forgotten:
                self.version += 1
        if forgotten:
            self._changed()
        return forgotten

    def replace(self, facts: Iterable[Fact], values: Mapping[Fact, float] | None = None) -> None:
        """Believe exactly ``facts``; numeric values are replaced when ``values`` is
        given or ``facts`` carries them, else kept."""
        given = values if values is not None else values_of(facts)
        with self._lock:
            kept = self._facts.values
            self._facts = _LiveFacts(facts)
            self._facts.values = dict(given) if given or values is not None else kept
            self.version += 1
        self._changed()

    def __contains__(self, fact: object) -> bool:
        return fact in self._facts

    def __len__(self) -> int:
        return len(self._facts)

    def __repr__(self) -> str:
        return f"Belief({len(self._facts)} facts)"
