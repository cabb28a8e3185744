"""An order: a goal with an id, an arrival time, a priority and a deadline, and its life.

An :class:`Order` is what somebody asked for (from an orders file, the control API,
the viewer or ROS 2); its :class:`OrderState` is what became of it. The statuses, in
the order an order lives them:

* ``queued``: arrived and accepted; waiting for a robot (a plan);
* ``assigned``: in the plan in force, to the robots named;
* ``active``: a step of the plan that serves it has started;
* ``done``: its goal held (``latency``: arrival to done);
* ``failed``: given up after it was accepted (the reason says why);
* ``refused``: not accepted (an unknown name, a goal no robot can reach: the reason);
* ``cancelled``: cancelled by whoever may (the reason names the source).

The last four are final. Every change is an :class:`OrderChanged` event, on the stream
the journal and the viewer follow.
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

from plan_bridge.pddl.task import Fact, format_fact
from smach.introspection.events import Event

__all__ = ["FINAL", "Order", "OrderChanged", "OrderState", "OrderStatus"]


class OrderStatus(enum.StrEnum):
    """Where an order is in its life (see the module documentation)."""

    QUEUED = "queued"
    ASSIGNED = "assigned"
    ACTIVE = "active"
    DONE = "done"
    FAILED = "failed"
    REFUSED = "refused"
    CANCELLED = "cancelled"


#: Statuses an order never leaves.
FINAL = frozenset(
    {OrderStatus.DONE, OrderStatus.FAILED, OrderStatus.REFUSED, OrderStatus.CANCELLED}
)


@dataclass(frozen=True)
class Order:
    """What was asked for: ``goal`` in the target's words (atoms or a goal's name)."""

    id: str
    goal: str
    at: float = 0.0
    """Arrival, seconds of the mission's clock (simulated seconds in simulation)."""
    priority: int = 0
    """Higher first: a robot serves the highest-priority orders before the others."""
    deadline: float | None = None
    """When it should be done (the mission's clock); an order done later is done, late."""
    origin: str = ""
    """Where it was written or sent from (``orders.yaml:7``, ``api``, ``ros``)."""

    def to_json(self) -> dict[str, Any]:
        data: dict[str, Any] = {"id": self.id, "goal": self.goal, "at": self.at}
        if self.priority:
            data["priority"] = self.priority
        if self.deadline is not None:
            data["deadline"] = self.deadline
        if self.origin:
            data["origin"] = self.origin
        return data

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Order:
        """The order of :meth:`to_json`'s data."""
        deadline = data.get("deadline")
        return cls(
            str(data["id"]),
            str(data["goal"]),
            float(data["at"]),
            int(data.get("priority", 0)),
            None if deadline is None else float(deadline),
            str(data.get("origin", "")),
        )


@dataclass
class OrderState:
    """An order and what became of it (the book's record; times on the mission's clock)."""

    order: Order
    status: OrderStatus = OrderStatus.QUEUED
    atoms: tuple[Fact, ...] = ()
    """The goal as atoms of the task (empty until the order is accepted)."""
    robots: tuple[str, ...] = ()
    """The robots of the plan that serves it (assigned, active, done)."""
    reason: str = ""
    """Why it failed, was refused or cancelled (or a note on how it went)."""
    arrived: float | None = None
    started: float | None = None
    ended: float | None = None
    attempts: int = 0
    """Plans given up for it (a robot's failure its recovery could not mend)."""
    history: list[tuple[float, str]] = field(default_factory=list)
    """(time, status) of every change."""

    @property
    def id(self) -> str:
        return self.order.id

    @property
    def final(self) -> bool:
        return self.status in FINAL

    @property
    def latency(self) -> float | None:
        """Arrival to done, seconds (None unless done)."""
        if self.status is not OrderStatus.DONE or self.ended is None or self.arrived is None:
            return None
        return self.ended - self.arrived

    @property
    def late(self) -> bool:
        """Done after its deadline."""
        deadline = self.order.deadline
        return (
            self.status is OrderStatus.DONE
            and deadline is not None
            and self.ended is not None
            and self.ended > deadline + 1e-9
        )

    def to_record(self) -> dict[str, Any]:
        """Everything of the state, as JSON data (a checkpoint's)."""
        return {
            "order": self.order.to_json(),
            "status": self.status.value,
            "atoms": [list(atom) for atom in self.atoms],
            "robots": list(self.robots),
            "reason": self.reason,
            "arrived": self.arrived,
            "started": self.started,
            "ended": self.ended,
            "attempts": self.attempts,
            "history": [list(change) for change in self.history],
        }

    @classmethod
    def from_record(cls, data: Mapping[str, Any]) -> OrderState:
        """The state of :meth:`to_record`'s data."""
        return cls(
            Order.from_json(data["order"]),
            OrderStatus(data["status"]),
            tuple(tuple(str(w) for w in atom) for atom in data["atoms"]),
            tuple(str(r) for r in data["robots"]),
            str(data["reason"]),
            data["arrived"],
            data["started"],
            data["ended"],
            int(data["attempts"]),
            [(float(t), str(status)) for t, status in data["history"]],
        )

    def to_json(self) -> dict[str, Any]:
        data: dict[str, Any] = {**self.order.to_json(), "status": self.status.value}
        if self.atoms:
            data["atoms"] = [format_fact(a) for a in self.atoms]
        for name in ("robots", "reason", "arrived", "started", "ended", "latency"):
            value = getattr(self, name)
            if value not in (None, "", ()):
                data[name] = list(value) if isinstance(value, tuple) else value
        if self.late:
            data["late"] = True
        if self.attempts:
            data["attempts"] = self.attempts
        return data


@dataclass(slots=True, kw_only=True)
class OrderChanged(Event):
    """An order's status changed (``path`` is the executive's; ``at``: mission clock)."""

    kind: ClassVar[str] = "order"
    order: str
    status: str
    goal: str
    at: float
    robots: tuple[str, ...] = ()
    reason: str = ""
    priority: int = 0
    arrived: float | None = None
    """When it arrived (the mission's clock)."""
    latency: float | None = None
    """Arrival to done, seconds (a done order's)."""
    origin: str = ""
    """Where it was written or sent from (``orders.yaml:7``, ``cli``, ``ros``)."""
