"""The order book: arrivals, statuses, cancels, live orders and the accounts."""

from __future__ import annotations

import threading

import pytest

from plan_bridge.orders.book import OrderBook, OrderBookError, percentile
from plan_bridge.orders.order import Order, OrderState, OrderStatus
from plan_bridge.orders.requests import OrderDesk

ATOMS = (("lies", "p1", "annex"),)


def book_of(*orders: Order, closed: bool = True) -> OrderBook:
    return OrderBook(orders, closed=closed)


def test_scheduled_orders_arrive_when_the_clock_reaches_their_time() -> None:
    book = book_of(Order("late", "g", 50.0), Order("early", "g", 10.0))
    assert book.next_arrival() == 10.0
    assert book.arrivals(9.0) == []
    assert [o.id for o in book.arrivals(60.0)] == ["early", "late"]
    assert book.next_arrival() is None
    assert [s.arrived for s in book.states()] == [10.0, 50.0]


def test_an_order_lives_queued_assigned_active_done_and_reports_its_latency() -> None:
    book = book_of(Order("a", "g", 10.0))
    seen: list[tuple[str, str]] = []
    book.add_listener(lambda s: seen.append((s.id, s.status.value)))
    book.arrivals(12.0)
    book.accept("a", ATOMS, 12.0)
    book.assign("a", ["ann"], 12.0)
    book.activate("a", 14.0)
    state = book.done("a", 40.0)
    assert seen == [("a", "queued"), ("a", "assigned"), ("a", "active"), ("a", "done")]
    assert (state.robots, state.started, state.latency) == (("ann",), 14.0, 30.0)
    assert state.final and book.finished()


def test_a_final_order_changes_no_more() -> None:
    book = book_of(Order("a", "g", 0.0))
    book.arrivals(0.0)
    book.refuse("a", "unknown object", 0.0)
    with pytest.raises(OrderBookError, match=r"order 'a' is refused; it cannot become done"):
        book.done("a", 1.0)
    with pytest.raises(OrderBookError, match=r"only an order that waits or runs can be cancelled"):
        book.cancel("a", 1.0)


def test_an_order_that_started_cannot_be_refused_but_can_fail() -> None:
    book = book_of(Order("a", "g", 0.0))
    book.arrivals(0.0)
    book.accept("a", ATOMS, 0.0)
    book.assign("a", ["ann"], 0.0)
    book.activate("a", 1.0)
    with pytest.raises(OrderBookError, match=r"has started; it cannot be refused"):
        book.refuse("a", "no plan", 2.0)
    assert book.fail("a", "the courier broke down", 3.0).reason == "the courier broke down"


def test_orders_can_be_cancelled_before_they_arrive_and_while_they_wait() -> None:
    book = book_of(Order("soon", "g", 5.0), Order("later", "g", 100.0))
    wakes: list[str] = []
    book.add_waker(lambda: wakes.append("woken"))
    book.arrivals(5.0)
    book.accept("soon", ATOMS, 5.0)
    assert book.cancel("soon", 6.0, source="cli").reason == "cancelled (cli)"
    state = book.cancel("later", 7.0, reason="not needed")
    assert (state.status, state.reason) == (OrderStatus.CANCELLED, "cancelled (api): not needed")
    assert book.next_arrival() is None and book.finished()
    assert wakes == ["woken", "woken"]


def test_a_live_order_arrives_when_the_mission_next_looks_with_its_deadline() -> None:
    book = book_of(closed=False)
    order = book.submit("(lies p1 annex)", priority=3, within=60.0)
    assert order.id == "o1" and book.next_arrival() == float("-inf")
    (arrived,) = book.arrivals(25.0)
    assert (arrived.at, arrived.deadline, arrived.priority) == (25.0, 85.0, 3)
    with pytest.raises(OrderBookError, match=r"order id 'o1' is already used"):
        book.submit("g", id="o1")
    assert not book.finished()  # open: more may come
    book.close()
    book.accept("o1", ATOMS, 25.0)
    assert not book.finished()  # its order is not final yet


def test_a_closed_book_refuses_live_orders_but_takes_an_operators_goal() -> None:
    book = book_of()
    with pytest.raises(OrderBookError, match=r"takes no more orders .* --orders-open"):
        book.submit("g")
    assert book.submit("g", origin="operator", even_if_closed=True).origin == "operator"


def test_open_orders_come_highest_priority_first_then_by_arrival() -> None:
    book = book_of(Order("a", "g", 0.0), Order("b", "g", 1.0, priority=5), Order("c", "g", 2.0))
    book.arrivals(3.0)
    for name in "abc":
        book.accept(name, ATOMS, 3.0)
    assert [s.id for s in book.open_orders()] == ["b", "a", "c"]


def test_the_summary_counts_statuses_latency_and_orders_per_hour() -> None:
    book = book_of(*(Order(f"o{i}", "g", 0.0, deadline=15.0) for i in range(4)))
    book.arrivals(0.0)
    for i, ended in enumerate((10.0, 20.0, 30.0)):
        book.accept(f"o{i}", ATOMS, 0.0)
        book.done(f"o{i}", ended)
    book.refuse("o3", "unknown", 0.0)
    summary = book.summary(elapsed_s=1800.0)
    assert summary["done"] == 3 and summary["refused"] == 1 and summary["late"] == 2
    assert (summary["latency_p50_s"], summary["latency_p95_s"]) == (20.0, 30.0)
    assert summary["orders_per_hour"] == 6.0


def test_percentile_is_the_nearest_rank() -> None:
    assert percentile([], 50) is None
    assert percentile([4.0, 1.0, 3.0, 2.0], 50) == 2.0
    assert percentile([4.0, 1.0, 3.0, 2.0], 95) == 4.0


def test_the_desk_reads_requests_from_the_viewer_cli_and_ros() -> None:
    book = book_of(closed=False)
    desk = OrderDesk(book, now=lambda: 42.0)
    reply = desk.order({"goal": "(lies p1 annex)", "priority": 1, "source": "viewer"})
    assert reply == {"id": "o1", "goal": "(lies p1 annex)"}
    book.arrivals(42.0)
    cancelled = desk.cancel({"id": "o1", "reason": "wrong room", "source": "cli"})
    assert isinstance(cancelled, dict) and cancelled["reason"] == "cancelled (cli): wrong room"
    listing = desk.listing({})
    assert isinstance(listing, list) and listing[0]["status"] == "cancelled"
    for body, message in (
        ({}, r"order needs 'goal'"),
        ({"goal": "g", "priority": "high"}, r"'priority' is an integer"),
        ({"goal": "g", "within": -1}, r"'within' is seconds > 0"),
    ):
        with pytest.raises(OrderBookError, match=message):
            desk.order(body)
    with pytest.raises(OrderBookError, match=r"no order 'o9'"):
        desk.cancel({"id": "o9"})


def test_live_orders_from_many_threads_each_arrive_once() -> None:
    book = book_of(closed=False)

    def send(n: int) -> None:
        for i in range(50):
            book.submit("g", id=f"t{n}-{i}")

    threads = [threading.Thread(target=send, args=(n,)) for n in range(4)]
    for thread in threads:
        thread.start()
    taken: list[str] = []
    while any(t.is_alive() for t in threads) or book.next_arrival() is not None:
        taken.extend(o.id for o in book.arrivals(0.0))
    for thread in threads:
        thread.join(timeout=10)
    assert sorted(taken) == sorted(f"t{n}-{i}" for n in range(4) for i in range(50))
    assert all(isinstance(s, OrderState) for s in book.states())


def test_a_listener_added_as_a_bound_method_is_removed_by_the_same_expression() -> None:
    class Panel:
        def __init__(self) -> None:
            self.seen: list[str] = []

        def changed(self, state: OrderState) -> None:
            self.seen.append(state.status.value)

    book, panel = book_of(Order("a", "g", 0.0)), Panel()
    book.add_listener(panel.changed)
    book.arrivals(1.0)
    book.accept("a", ATOMS, 1.0)
    book.remove_listener(panel.changed)  # a new bound method object, equal to the first
    book.assign("a", ["ann"], 2.0)
    assert panel.seen == ["queued"]
