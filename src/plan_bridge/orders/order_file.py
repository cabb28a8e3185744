"""Orders files: the orders that reach a mission over time (``plan-bridge run --orders``).

A YAML mapping with ``orders:`` (a list written out) and/or ``streams:`` (Poisson
arrivals drawn from the run's seed), or just the list::

    orders:
      - id: soda-1                     # optional (default: o1, o2, ... in file order)
        at: 30                         # arrival, seconds of the mission's clock
        goal: (At soda0 counter0_left) # atoms in the target's words, or a goal's name
        priority: 2                    # optional, higher first (default 0)
        deadline: 400                  # optional: done by then (mission clock) ...
      - at: [60, 120]                  # a window: the time is drawn from the run's seed
        goal: fetch_apple              # a named goal (a world folder's goals.yaml)
        within: 300                    # ... or: done within 300 s of arriving
    streams:
      - rate_per_hour: 12              # Poisson arrivals, this many per hour on average
        start: 0                       # optional (default 0)
        until: 28800                   # no arrival after this (seconds)
        goals: [fetch_apple, fetch_soda, "(At bread0 table0_tabletop)"]  # one drawn each time
        weights: [2, 1, 1]             # optional
        id: stream                     # optional prefix of the ids (stream-1, stream-2, ...)
        priority: 0                    # optional, as for orders
        within: 600                    # optional

Errors name the file, the item's line and what is allowed (:class:`OrderFileError`).
The goals are not checked here: the mission checks each order when it arrives, and
refuses a bad one with the reason while the others go on.
"""

from __future__ import annotations

import math
import random
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from plan_bridge.errors import PlanBridgeError
from plan_bridge.orders.order import Order
from plan_bridge.pddl.constructs import did_you_mean
from plan_bridge.seeded_time import draw_time, is_seconds, read_time
from plan_bridge.yaml_files import read_yaml_with_lines

__all__ = ["OrderFileError", "OrderSchedule", "OrderStream", "load_orders", "parse_orders"]

_ORDER_KEYS = ("id", "at", "goal", "priority", "deadline", "within")
_STREAM_KEYS = ("rate_per_hour", "start", "until", "goals", "weights", "id", "priority", "within")
_ALLOWED_ORDER = (
    "an order is a mapping with at: SECONDS or [LO, HI], goal: ATOMS or a goal's name, and "
    "optionally id:, priority: INTEGER, deadline: SECONDS or within: SECONDS"
)
_ALLOWED_STREAM = (
    "a stream is a mapping with rate_per_hour: NUMBER > 0, until: SECONDS, goals: [GOAL, ...], "
    "and optionally start:, weights: [NUMBER, ...], id:, priority:, within:"
)
_ALLOWED_FILE = (
    "an orders file is a YAML list of orders, or a mapping with orders: [...] and/or streams: [...]"
)


class OrderFileError(PlanBridgeError):
    """An orders file that cannot be read (what, where, what is allowed)."""


@dataclass(frozen=True)
class _Timed:
    """An order as written: a fixed time, or a window drawn per run."""

    order: Order
    window: tuple[float, float] | None = None
    within: float | None = None


@dataclass(frozen=True)
class OrderStream:
    """Poisson arrivals: on average ``rate_per_hour`` orders an hour from ``start`` to
    ``until``, each with a goal drawn from ``goals`` (by ``weights``)."""

    rate_per_hour: float
    until: float
    goals: tuple[str, ...]
    start: float = 0.0
    weights: tuple[float, ...] = ()
    prefix: str = "stream"
    priority: int = 0
    within: float | None = None
    origin: str = ""

    def draw(self, seed: int, number: int = 1) -> list[Order]:
        """The orders of this stream in a run with ``seed`` (``number``: the stream's
        place in its file, so two streams of a file draw apart)."""
        rng = random.Random(f"order-stream:{seed}:{number}")
        rate = self.rate_per_hour / 3600.0
        orders: list[Order] = []
        t = self.start
        weights = list(self.weights) or None
        while True:
            t += rng.expovariate(rate)
            if t > self.until:
                return orders
            goal = rng.choices(self.goals, weights=weights)[0]
            at = round(t, 3)
            orders.append(
                Order(
                    f"{self.prefix}-{len(orders) + 1}",
                    goal,
                    at,
                    self.priority,
                    None if self.within is None else round(at + self.within, 3),
                    self.origin,
                )
            )


@dataclass(frozen=True)
class OrderSchedule:
    """What an orders file says: orders written out and streams, until drawn for a run."""

    source: str = ""
    written: tuple[_Timed, ...] = ()
    streams: tuple[OrderStream, ...] = field(default_factory=tuple)

    def draw(self, seed: int) -> list[Order]:
        """The orders of a run with ``seed``, in arrival order (ties: file order).
        Raises :class:`OrderFileError` when two orders have the same id."""
        orders: list[Order] = []
        for item in self.written:
            order = item.order
            if item.window is not None:
                order = replace(order, at=draw_time(item.window, seed, f"order:{order.id}"))
            if item.within is not None:
                order = replace(order, deadline=round(order.at + item.within, 3))
            orders.append(order)
        for number, stream in enumerate(self.streams, start=1):
            orders.extend(stream.draw(seed, number))
        seen: dict[str, Order] = {}
        for order in orders:
            if order.id in seen:
                raise OrderFileError(
                    f"{order.origin}: order id {order.id!r} is used twice (also "
                    f"{seen[order.id].origin}); ids must be unique"
                )
            seen[order.id] = order
        return sorted(orders, key=lambda o: o.at)

    def __len__(self) -> int:
        return len(self.written) + len(self.streams)


def load_orders(path: str | Path) -> OrderSchedule:
    """The orders file at ``path`` (raises :class:`OrderFileError`)."""
    data, lines = read_yaml_with_lines(path, "orders", OrderFileError)
    if "" in lines:  # a bare list: the orders
        lines["orders"] = lines.pop("")
    return parse_orders(data, str(Path(path)), lines)


def parse_orders(
    data: Any, origin: str = "orders", lines: Mapping[str, Sequence[int]] | None = None
) -> OrderSchedule:
    """An :class:`OrderSchedule` from YAML data; ``lines``: each item's line by section."""
    lines = lines or {}
    if data is None:
        return OrderSchedule(origin)
    if isinstance(data, list):
        data = {"orders": data}
    if not isinstance(data, Mapping):
        raise OrderFileError(f"{origin}: {_ALLOWED_FILE}; got {type(data).__name__}")
    unknown = [str(k) for k in data if k not in ("orders", "streams")]
    if unknown:
        hint = did_you_mean(unknown[0], ("orders", "streams"))
        raise OrderFileError(f"{origin}: unknown key {unknown[0]!r}{hint}; {_ALLOWED_FILE}")
    written: list[_Timed] = []
    streams: list[OrderStream] = []
    for section in ("orders", "streams"):
        items = data.get(section)
        if items is None:
            continue
        if not isinstance(items, list):
            raise OrderFileError(f"{origin}: {section}: must be a list; {_ALLOWED_FILE}")
        at_lines = lines.get(section, ())
        for index, item in enumerate(items):
            line = at_lines[index] if index < len(at_lines) else None
            where = (
                f"{origin}:{line}" if line is not None else f"{origin}: {section} item {index + 1}"
            )
            if section == "orders":
                written.append(_order(item, where, len(written) + 1))
            else:
                streams.append(_stream(item, where, len(streams) + 1))
    return OrderSchedule(origin, tuple(written), tuple(streams))


def _mapping(item: Any, where: str, keys: Sequence[str], allowed: str) -> Mapping[str, Any]:
    if not isinstance(item, Mapping):
        raise OrderFileError(f"{where}: {item!r} is not a mapping; {allowed}")
    unknown = [str(k) for k in item if k not in keys]
    if unknown:
        raise OrderFileError(
            f"{where}: unknown key {unknown[0]!r}{did_you_mean(unknown[0], keys)}; {allowed}"
        )
    return item


def _goal_text(value: Any, where: str, allowed: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise OrderFileError(
            f"{where}: goal: must be atoms such as (At apple0 table0_tabletop) or a goal's "
            f"name, got {value!r}; {allowed}"
        )
    return " ".join(value.split())


def _priority(item: Mapping[str, Any], where: str, allowed: str) -> int:
    value = item.get("priority", 0)
    if isinstance(value, bool) or not isinstance(value, int):
        raise OrderFileError(f"{where}: priority: must be an integer, got {value!r}; {allowed}")
    return value


def _within(item: Mapping[str, Any], where: str, allowed: str) -> float | None:
    value = item.get("within")
    if value is None:
        return None
    if not is_seconds(value) or value == 0:
        raise OrderFileError(f"{where}: within: must be seconds > 0, got {value!r}; {allowed}")
    return float(value)


def _order(item: Any, where: str, number: int) -> _Timed:
    item = _mapping(item, where, _ORDER_KEYS, _ALLOWED_ORDER)
    if "at" not in item:
        raise OrderFileError(f"{where}: the order has no at: (its arrival); {_ALLOWED_ORDER}")
    time = read_time(item["at"])
    if isinstance(time, str):
        raise OrderFileError(f"{where}: {time}; {_ALLOWED_ORDER}")
    at, window = time
    goal = _goal_text(item.get("goal"), where, _ALLOWED_ORDER)
    raw_id = item.get("id", f"o{number}")
    if not isinstance(raw_id, (str, int)) or isinstance(raw_id, bool) or not str(raw_id).strip():
        raise OrderFileError(f"{where}: id: must be a name or a number, got {raw_id!r}")
    deadline = item.get("deadline")
    within = _within(item, where, _ALLOWED_ORDER)
    if deadline is not None:
        if within is not None:
            raise OrderFileError(f"{where}: give deadline: or within:, not both")
        if not is_seconds(deadline):
            raise OrderFileError(
                f"{where}: deadline: must be seconds >= 0, got {deadline!r}; {_ALLOWED_ORDER}"
            )
        deadline = float(deadline)
    order = Order(
        str(raw_id).strip(), goal, at, _priority(item, where, _ALLOWED_ORDER), deadline, where
    )
    return _Timed(order, window, within)


def _stream(item: Any, where: str, number: int) -> OrderStream:
    item = _mapping(item, where, _STREAM_KEYS, _ALLOWED_STREAM)
    rate = item.get("rate_per_hour")
    if not is_seconds(rate) or rate == 0:
        raise OrderFileError(
            f"{where}: rate_per_hour: must be a number > 0, got {rate!r}; {_ALLOWED_STREAM}"
        )
    start = item.get("start", 0)
    until = item.get("until")
    for name, value in (("start", start), ("until", until)):
        if not is_seconds(value):
            raise OrderFileError(
                f"{where}: {name}: must be seconds >= 0, got {value!r}; {_ALLOWED_STREAM}"
            )
    if until <= start:
        raise OrderFileError(f"{where}: until: {until} is not after start: {start}")
    goals = item.get("goals")
    if not isinstance(goals, list) or not goals:
        raise OrderFileError(f"{where}: goals: must be a non-empty list; {_ALLOWED_STREAM}")
    texts = tuple(_goal_text(goal, where, _ALLOWED_STREAM) for goal in goals)
    weights = item.get("weights", [])
    if not isinstance(weights, list) or (
        weights
        and (
            len(weights) != len(texts)
            or not all(is_seconds(w) for w in weights)
            or not math.fsum(weights) > 0
        )
    ):
        raise OrderFileError(
            f"{where}: weights: must be {len(texts)} numbers >= 0 (one per goal), not all 0, "
            f"got {weights!r}"
        )
    prefix = item.get("id", f"stream{number}" if number > 1 else "stream")
    if not isinstance(prefix, str) or not prefix.strip():
        raise OrderFileError(f"{where}: id: must be a name (the ids' prefix), got {prefix!r}")
    return OrderStream(
        float(rate),
        float(until),
        texts,
        float(start),
        tuple(float(w) for w in weights),
        prefix.strip(),
        _priority(item, where, _ALLOWED_STREAM),
        _within(item, where, _ALLOWED_STREAM),
        where,
    )
