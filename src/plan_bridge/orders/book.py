"""The order book: every order of a mission and its status, from any thread.

Orders come in two ways: scheduled (an orders file: each arrives when the mission's
clock reaches its time) and live (:meth:`OrderBook.submit`, from the control API, the
viewer or ROS 2: each arrives when the mission next looks). The mission takes what
has arrived (:meth:`~OrderBook.arrivals`), accepts or refuses each, and moves the
accepted ones through their statuses (:mod:`plan_bridge.orders.order`); a
:meth:`~OrderBook.cancel` may come at any time. Every change reaches the book's
listeners (the mission's events, a ROS topic) in the order it happened.

The book is *closed* when no live order may come any more (only the file's): the
mission ends when a closed book has nothing scheduled and every order is final.
"""

from __future__ import annotations

import itertools
import math
import threading
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any

from plan_bridge.errors import PlanBridgeError
from plan_bridge.orders.order import FINAL, Order, OrderState, OrderStatus
from plan_bridge.pddl.task import Fact

__all__ = ["OrderBook", "OrderBookError", "percentile"]

Listener = Callable[[OrderState], None]


class OrderBookError(PlanBridgeError, ValueError):
    """A request the book cannot take (an unknown or repeated id, a final order)."""


def percentile(values: Sequence[float], q: float) -> float | None:
    """The ``q``-th percentile (0-100) of ``values``, nearest rank; None when empty."""
    if not values:
        return None
    ordered = sorted(values)
    rank = max(1, math.ceil(q / 100.0 * len(ordered)))
    return ordered[min(rank, len(ordered)) - 1]


class OrderBook:
    """Every order of one mission (see the module documentation)."""

    def __init__(self, scheduled: Iterable[Order] = (), *, closed: bool = True) -> None:
        self._lock = threading.RLock()
        self._scheduled = sorted(scheduled, key=lambda o: o.at)
        self._next_scheduled = 0
        self._live: list[Order] = []
        self._states: dict[str, OrderState] = {}
        self._ids = {o.id for o in self._scheduled}
        if len(self._ids) != len(self._scheduled):
            names = [o.id for o in self._scheduled]
            twice = next(name for name in names if names.count(name) > 1)
            raise OrderBookError(f"order id {twice!r} is scheduled twice; ids must be unique")
        self._listeners: list[Listener] = []
        self._wakers: list[Callable[[], None]] = []
        self._counter = itertools.count(1)
        self._closed = closed
        self._changed = False

    # -- listeners -------------------------------------------------------------------------
    def add_listener(self, listener: Listener) -> None:
        """Call ``listener(state)`` after every change of an order (in the changer's
        thread, under no lock of the book's)."""
        with self._lock:
            self._listeners = [*self._listeners, listener]

    def remove_listener(self, listener: Listener) -> None:
        with self._lock:
            self._listeners = [x for x in self._listeners if x != listener]  # bound methods

    def add_waker(self, wake: Callable[[], None]) -> None:
        """Call ``wake()`` when something arrives or is cancelled from outside the
        mission's loop (a live order, a cancel): the mission looks at the book."""
        with self._lock:
            self._wakers = [*self._wakers, wake]

    # -- what arrives ------------------------------------------------------------------------
    @property
    def closed(self) -> bool:
        """No live order may come any more (the mission ends when all are final)."""
        with self._lock:
            return self._closed

    def close(self) -> None:
        """Take no more live orders (those already submitted are still taken)."""
        with self._lock:
            self._closed = True
        self._wake()

    def open(self) -> None:
        """Take live orders until :meth:`close` (the mission waits for them)."""
        with self._lock:
            self._closed = False

    def submit(
        self,
        goal: str,
        *,
        id: str = "",
        priority: int = 0,
        within: float | None = None,
        origin: str = "api",
        even_if_closed: bool = False,
    ) -> Order:
        """A live order: it arrives when the mission next looks (its time is then; a
        deadline ``within`` seconds of it). Raises :class:`OrderBookError` for a
        repeated id, an empty goal or a closed book (``even_if_closed``: an operator's
        new goal, taken all the same)."""
        if not goal.strip():
            raise OrderBookError("an order needs a goal: atoms or a goal's name")
        if within is not None and not within > 0:
            raise OrderBookError(f"within: must be seconds > 0, got {within!r}")
        with self._lock:
            if self._closed and not even_if_closed:
                raise OrderBookError(
                    "the mission takes no more orders (it runs its orders file only; run it "
                    "with --orders-open to send orders while it runs)"
                )
            name = id.strip() or self._fresh_id()
            if name in self._ids:
                raise OrderBookError(f"order id {name!r} is already used; ids must be unique")
            # Until it arrives, ``deadline`` holds the seconds it is due within.
            order = Order(name, " ".join(goal.split()), 0.0, priority, within, origin)
            self._ids.add(name)
            self._live.append(order)
        self._wake()
        return order

    def _fresh_id(self) -> str:
        while True:
            name = f"o{next(self._counter)}"
            if name not in self._ids:
                return name

    def next_arrival(self) -> float | None:
        """When the next scheduled order arrives (None: none is left); live orders
        waiting to be taken arrive now (``-inf``)."""
        with self._lock:
            if self._live:
                return -math.inf
            self._skip_taken()
            if self._next_scheduled < len(self._scheduled):
                return self._scheduled[self._next_scheduled].at
            return None

    def _skip_taken(self) -> None:
        """Move past scheduled orders already in the book (cancelled before arriving)."""
        while (
            self._next_scheduled < len(self._scheduled)
            and self._scheduled[self._next_scheduled].id in self._states
        ):
            self._next_scheduled += 1

    def arrivals(self, now: float) -> list[Order]:
        """Take the orders that have arrived by ``now`` (scheduled ones in time order,
        then live ones stamped ``now``); each must then be :meth:`accept`-ed or
        :meth:`refuse`-d."""
        with self._lock:
            taken: list[Order] = []
            self._skip_taken()
            while (
                self._next_scheduled < len(self._scheduled)
                and self._scheduled[self._next_scheduled].at <= now + 1e-9
            ):
                taken.append(self._scheduled[self._next_scheduled])
                self._next_scheduled += 1
                self._skip_taken()
            for order in self._live:
                within = order.deadline
                deadline = None if within is None else round(now + within, 3)
                taken.append(
                    Order(order.id, order.goal, now, order.priority, deadline, order.origin)
                )
            self._live = []
            for order in taken:
                self._states[order.id] = OrderState(order, arrived=order.at)
            return taken

    def finished(self) -> bool:
        """Closed, nothing left to arrive, and every order final."""
        with self._lock:
            self._skip_taken()
            return (
                self._closed
                and not self._live
                and self._next_scheduled >= len(self._scheduled)
                and all(state.final for state in self._states.values())
            )

    # -- statuses ----------------------------------------------------------------------------
    def get(self, order_id: str) -> OrderState:
        with self._lock:
            state = self._states.get(order_id)
            if state is None:
                raise OrderBookError(self._unknown(order_id))
            return state

    def _unknown(self, order_id: str) -> str:
        from plan_bridge.pddl.constructs import did_you_mean

        waiting = [
            o.id for o in self._scheduled[self._next_scheduled :] if o.id not in self._states
        ] + [o.id for o in self._live]
        if order_id in waiting:
            return f"order {order_id!r} has not arrived yet"
        return f"no order {order_id!r}{did_you_mean(order_id, self._states)}"

    def states(self) -> list[OrderState]:
        """Every order that has arrived, in arrival order."""
        with self._lock:
            return list(self._states.values())

    def open_orders(self) -> list[OrderState]:
        """Accepted orders not final yet, highest priority first, then by arrival."""
        with self._lock:
            states = [s for s in self._states.values() if not s.final and s.atoms]
        return sorted(states, key=lambda s: (-s.order.priority, s.arrived or 0.0))

    def accept(self, order_id: str, atoms: Sequence[Fact], now: float) -> OrderState:
        """The order's goal is ``atoms``: it is queued."""
        with self._lock:
            state = self.get(order_id)
            state.atoms = tuple(atoms)
        return self._set(state, OrderStatus.QUEUED, now)

    def refuse(self, order_id: str, reason: str, now: float) -> OrderState:
        return self._set(self.get(order_id), OrderStatus.REFUSED, now, reason=reason)

    def assign(self, order_id: str, robots: Sequence[str], now: float) -> OrderState:
        state = self.get(order_id)
        robots = tuple(robots)
        if state.status is OrderStatus.ACTIVE and set(robots) == set(state.robots):
            return state  # the same robots go on with it
        if state.status is OrderStatus.ASSIGNED and robots == state.robots:
            return state
        return self._set(state, OrderStatus.ASSIGNED, now, robots=robots)

    def activate(self, order_id: str, now: float) -> OrderState:
        state = self.get(order_id)
        if state.status is not OrderStatus.ASSIGNED:
            return state
        with self._lock:
            if state.started is None:
                state.started = now
        return self._set(state, OrderStatus.ACTIVE, now)

    def requeue(self, order_id: str, now: float, reason: str = "") -> OrderState:
        """Back to ``queued`` (no plan serves it now: a robot lost it, or orders of a
        higher priority came first)."""
        state = self.get(order_id)
        if state.status is OrderStatus.QUEUED:
            return state
        return self._set(state, OrderStatus.QUEUED, now, robots=(), reason=reason)

    def done(self, order_id: str, now: float) -> OrderState:
        state = self.get(order_id)
        with self._lock:
            state.ended = now
            if state.started is None:
                state.started = now
        return self._set(state, OrderStatus.DONE, now)

    def fail(self, order_id: str, reason: str, now: float) -> OrderState:
        state = self.get(order_id)
        with self._lock:
            state.ended = now
        return self._set(state, OrderStatus.FAILED, now, reason=reason)

    def note_attempt(self, order_id: str) -> int:
        """One more plan given up for the order; how many so far."""
        with self._lock:
            state = self.get(order_id)
            state.attempts += 1
            return state.attempts

    def cancel(
        self, order_id: str, now: float, *, source: str = "api", reason: str = ""
    ) -> OrderState:
        """Cancel an order that waits (not arrived yet, or queued) or runs. Raises
        :class:`OrderBookError` for an unknown or final order."""
        with self._lock:
            pending = [o for o in self._live if o.id == order_id]
            if pending:  # not taken yet: it arrives cancelled
                self._live.remove(pending[0])
                order = Order(
                    order_id, pending[0].goal, now, pending[0].priority, None, pending[0].origin
                )
                self._states[order_id] = OrderState(order, arrived=now)
            else:
                for order in self._scheduled[self._next_scheduled :]:
                    if order.id == order_id and order_id not in self._states:
                        # It will not arrive: arrivals skip ids the book has.
                        self._states[order_id] = OrderState(order, arrived=now)
                        break
            state = self.get(order_id)
            if state.final:
                raise OrderBookError(
                    f"order {order_id!r} is {state.status.value} already; only an order that "
                    f"waits or runs can be cancelled"
                )
            state.ended = now
        why = f"cancelled ({source})" + (f": {reason}" if reason else "")
        changed = self._set(state, OrderStatus.CANCELLED, now, reason=why)
        self._wake()
        return changed

    def take_changed(self) -> bool:
        """Whether the open orders changed since the last call (arrived, cancelled,
        final): the plan should be made again."""
        with self._lock:
            changed, self._changed = self._changed, False
            return changed

    def _set(
        self,
        state: OrderState,
        status: OrderStatus,
        now: float,
        *,
        robots: tuple[str, ...] | None = None,
        reason: str | None = None,
    ) -> OrderState:
        with self._lock:
            if state.final:
                raise OrderBookError(
                    f"order {state.id!r} is {state.status.value}; it cannot become {status.value}"
                )
            if status is OrderStatus.REFUSED and state.started is not None:
                raise OrderBookError(f"order {state.id!r} has started; it cannot be refused")
            state.status = status
            if robots is not None:
                state.robots = robots
            if reason is not None:
                state.reason = reason
            state.history.append((now, status.value))
            if status in FINAL or (status is OrderStatus.QUEUED and len(state.history) == 1):
                self._changed = True
            listeners = self._listeners
        for listener in listeners:
            listener(state)
        return state

    def _wake(self) -> None:
        for wake in self._wakers:
            wake()

    # -- checkpoints ---------------------------------------------------------------------------
    def snapshot(self) -> dict[str, Any]:
        """What a resumed mission needs of the book (JSON data): every order that has
        arrived with its life, how far the schedule got, live orders not taken yet."""
        with self._lock:
            return {
                "next": self._next_scheduled,
                "closed": self._closed,
                "live": [o.to_json() for o in self._live],
                "states": [s.to_record() for s in self._states.values()],
            }

    def restore(self, data: Mapping[str, Any]) -> None:
        """Take up a :meth:`snapshot` (of a book built with the same schedule)."""
        with self._lock:
            self._next_scheduled = int(data["next"])
            self._closed = bool(data["closed"])
            self._live = [Order.from_json(item) for item in data["live"]]
            self._states = {}
            for record in data["states"]:
                state = OrderState.from_record(record)
                self._states[state.id] = state
            self._ids |= set(self._states) | {o.id for o in self._live}
            self._changed = True

    # -- accounts ------------------------------------------------------------------------------
    def counts(self) -> dict[str, int]:
        """Orders by status (every status, 0 included), and ``late``."""
        with self._lock:
            states = list(self._states.values())
        counts = {status.value: 0 for status in OrderStatus}
        for state in states:
            counts[state.status.value] += 1
        counts["late"] = sum(1 for s in states if s.late)
        return counts

    def summary(
        self,
        elapsed_s: float,
        busy_s: Mapping[str, float] | None = None,
        robots: Iterable[str] = (),
    ) -> dict[str, Any]:
        """Counts by status, latency (arrival to done) p50/p95 and orders done per hour
        of the mission's clock over ``elapsed_s``; with ``busy_s`` (seconds each robot
        spent at work), each of ``robots``' share of ``elapsed_s`` (``busy_share``). The
        ``orders`` figures of a run, planned or scripted."""
        with self._lock:
            states = list(self._states.values())
            waiting = len(self._live) + sum(
                1 for o in self._scheduled[self._next_scheduled :] if o.id not in self._states
            )
        latencies = [s.latency for s in states if s.latency is not None]
        done = sum(1 for s in states if s.status is OrderStatus.DONE)
        p50, p95 = percentile(latencies, 50), percentile(latencies, 95)
        data: dict[str, Any] = {
            "orders": len(states),
            "not_arrived": waiting,
            **self.counts(),
            "latency_p50_s": None if p50 is None else round(p50, 3),
            "latency_p95_s": None if p95 is None else round(p95, 3),
            "orders_per_hour": round(done / (elapsed_s / 3600.0), 3) if elapsed_s > 0 else None,
        }
        if busy_s is not None and elapsed_s > 0:
            data["busy_share"] = {
                robot: round(busy_s.get(robot, 0.0) / elapsed_s, 4) for robot in sorted(robots)
            }
        return data
