"""The belief (what the executive thinks is true) and the :class:`World` it acts on.

The belief is a set of ground PDDL facts.

Skills change it in two ways: a succeeded skill's action effects are applied, and
any skill may report observations (facts it saw to be true or false), which override
what was believed. An optional sensing port refreshes facts from outside. Steps of a
Concurrence update it from several threads, hence the lock.

Numeric fluents (``(battery r1)``) are part of the belief too: :attr:`WorldState.values`
maps ground numeric atoms to numbers. Snapshots (:attr:`WorldState.facts`) are
:class:`FactSnapshot` frozensets that carry those values along, so everything that
reads a state (conditions, the planner's initial state for a replan) sees them.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from typing import TYPE_CHECKING, Any, Protocol

from plan_bridge.pddl.task import Fact, FactLike, format_fact, parse_fact

if TYPE_CHECKING:
    from plan_bridge.execution.clock import Clock
    from plan_bridge.planning.types import PlanStep

__all__ = [
    "FactSnapshot",
    "Observation",
    "World",
    "WorldState",
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


class _LiveFacts(set[Fact]):
    """The belief's live set of facts; ``values`` holds the numeric atoms."""

    values: dict[Fact, float]


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


class World(Protocol):
    """The world a mission acts on, as the executive and the mission runner see it.

    Implemented by the symbolic :class:`~plan_bridge.execution.simulation.SimulatedWorld`
    (and its subclasses: :class:`~plan_bridge.execution.timed_world.TimedWorld`, the
    domains' worlds) and by the ROS 2 robot seen from the executive
    (:class:`~plan_bridge.ros.connection.RobotWorld`). Skills act on the world; the
    executive never reads its truth, only what skills observe and what :meth:`sense`
    returns. The skill contract (docs/plan-bridge.md) says what each call means.
    """

    #: Wall seconds per simulated second (0: as fast as it goes). A world on the wall
    #: clock (a real robot) keeps 0 and ignores it.
    time_scale: float

    @property
    def clock(self) -> Clock:
        """The world's clock: a simulated world's :class:`~plan_bridge.execution.clock.SimClock`
        (steps take turns on it in simulated-time order), a robot's wall clock."""
        ...

    def now(self) -> float:
        """The world's time in seconds: simulated time, or wall time for a real robot."""
        ...

    def adopt(self, step: PlanStep, observations: Sequence[Observation]) -> None:
        """``step`` was done by a skill that is not the world's own (a user's skill)
        and succeeded: a simulated world takes the action's declared effects into its
        truth, then ``observations`` (they win); a real world has changed by itself."""
        ...

    def sense(self, steps: Sequence[PlanStep]) -> list[Observation]:
        """What the robot can observe now of the atoms ``steps`` read or change."""
        ...

    @property
    def faults_injected(self) -> int | None:
        """Faults the world injected so far (None: it does not know, e.g. a robot)."""
        ...

    def goal_reached(self) -> bool:
        """Whether the task's goal holds in the world's truth (for reports and the study)."""
        ...

    def snapshot(self) -> dict[str, Any] | None:
        """What a checkpoint keeps of the world (JSON data); None: it cannot be saved
        (its state lives elsewhere, as a robot's does), so a run cannot be resumed."""
        ...

    def restore(self, data: dict[str, Any]) -> None:
        """Put back a :meth:`snapshot`."""
        ...

    def abandon_running(self) -> None:
        """After :meth:`restore` into a new process: the actions that were in progress
        stopped with the old one (a drive is back where it began)."""
        ...

    def figures(self) -> dict[str, Any]:
        """The world's numbers for a run's report (``sim_time_s``, faults, ...)."""
        ...


class WorldState:
    """A thread-safe set of true ground facts (closed world: absent means false)."""

    def __init__(
        self, facts: Iterable[FactLike] = (), values: Mapping[Fact, float] | None = None
    ) -> None:
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
        with self._lock:
            self._listeners = [cb for cb in self._listeners if cb is not listener]

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
        return f"WorldState({len(self._facts)} facts)"
