"""Orders sent to a running mission: the one reading of a request, whoever sends it.

The control API (``plan-bridge control URL order GOAL``), the viewer's queue panel and
ROS 2 (:mod:`plan_bridge.ros.order_services`) all send plain data; :class:`OrderDesk`
reads it, checks it and passes it to the mission's
:class:`~plan_bridge.orders.book.OrderBook`:

* ``order``: ``{"goal": "(At soda0 counter0_left)", "id": "soda-7", "priority": 2,
  "within": 300}`` (only ``goal`` is required) -> the order's id;
* ``cancel``: ``{"id": "soda-7", "reason": "..."}`` -> what became of it;
* ``orders``: ``{}`` -> every order with its status (the queue panel's rows).

A refused request raises :class:`~plan_bridge.orders.book.OrderBookError` (a
ValueError: the viewer answers 400, ROS ``False``) saying what is wrong and allowed.
Whether its goal makes sense is checked when the order arrives: a bad one is
refused in the book with the reason.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from plan_bridge.orders.book import OrderBook, OrderBookError

__all__ = ["SOURCES", "OrderDesk"]

#: Who may send requests (the journal records it).
SOURCES = ("viewer", "cli", "ros", "api")


class OrderDesk:
    """Order requests for ``book``; ``now()`` is the mission's clock (a cancel's time)."""

    def __init__(self, book: OrderBook, now: Callable[[], float]) -> None:
        self.book = book
        self.now = now

    def actions(self) -> dict[str, Callable[[Mapping[str, Any]], object]]:
        """The requests as control actions (``enable_controls(actions=...)``)."""
        return {"order": self.order, "cancel": self.cancel, "orders": self.listing}

    def order(self, body: Mapping[str, Any]) -> object:
        goal = body.get("goal")
        if not isinstance(goal, str) or not goal.strip():
            raise OrderBookError(
                "order needs 'goal': atoms like (At soda0 counter0_left) or a goal's name"
            )
        name = body.get("id", "")
        if not isinstance(name, str):
            raise OrderBookError(f"'id' is a name, got {name!r}")
        priority = body.get("priority", 0)
        if isinstance(priority, bool) or not isinstance(priority, int):
            raise OrderBookError(f"'priority' is an integer, got {priority!r}")
        within = body.get("within")
        if within is not None and (
            isinstance(within, bool) or not isinstance(within, int | float) or not within > 0
        ):
            raise OrderBookError(f"'within' is seconds > 0, got {within!r}")
        order = self.book.submit(
            goal,
            id=name,
            priority=priority,
            within=None if within is None else float(within),
            origin=_source(body),
        )
        return {"id": order.id, "goal": order.goal}

    def cancel(self, body: Mapping[str, Any]) -> object:
        name = body.get("id")
        if not isinstance(name, str) or not name.strip():
            raise OrderBookError("cancel needs 'id': the order's id")
        reason = body.get("reason", "")
        state = self.book.cancel(
            name.strip(),
            self.now(),
            source=_source(body),
            reason=reason[:500] if isinstance(reason, str) else "",
        )
        return state.to_json()

    def listing(self, body: Mapping[str, Any]) -> object:
        del body  # (every request carries one)
        return [state.to_json() for state in self.book.states()]


def _source(body: Mapping[str, Any]) -> str:
    value = body.get("source", "api")
    return value if value in SOURCES else "api"
