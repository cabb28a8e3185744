"""The viewer's queue panel without a browser: ``order`` records folded into rows, the
rows in the view the page gets, and extra control actions that answer with data."""

from __future__ import annotations

import http.client
import json
from collections.abc import Iterator
from typing import Any

import pytest

import smach
from smach.control import Controller
from smach.introspection import serve
from smach.introspection.control_api import ViewerControls
from smach.introspection.model import MAX_ORDERS, History, ViewModel
from smach.testing import ScriptedState


def order(name: str, status: str, at: float, **more: Any) -> dict[str, Any]:
    """An ``order`` record as plan_bridge's OrderChanged event writes it."""
    record = {"kind": "order", "path": "/ROOT", "time": 100.0 + at, "order": name}
    record.update(status=status, goal=more.pop("goal", "(at r1 office)"), at=at)
    record.update(robots=more.pop("robots", []), reason=more.pop("reason", ""))
    record.update(priority=more.pop("priority", 0), **more)
    return record


def rows(model: ViewModel) -> dict[str, dict[str, Any]]:
    return {row["id"]: row for row in model.to_json()["orders"]}


def test_order_records_become_one_row_per_order_in_arrival_order() -> None:
    model = ViewModel()
    cup = {"goal": "(item-at cup office)", "priority": 2}  # every record of it says so
    for record in (
        order("cup", "queued", 0.0, **cup),
        order("r2", "queued", 1.5),
        order("cup", "assigned", 1.5, robots=["r1"], **cup),
        order("bad", "refused", 2.0, reason="(at r9 office): unknown object 'r9'"),
        order("cup", "active", 2.0, robots=["r1"], **cup),
        order("cup", "done", 6.25, robots=["r1"], **cup),
        order("r2", "cancelled", 7.0, reason="cancelled (viewer)"),
    ):
        model.apply(record)
    shown = model.to_json()["orders"]
    assert [row["id"] for row in shown] == ["cup", "r2", "bad"]
    done, r2, bad = shown
    assert done["status"] == "done" and done["robots"] == ["r1"] and done["priority"] == 2
    assert done["goal"] == "(item-at cup office)"
    assert (done["arrived"], done["ended"], done["latency"]) == (0.0, 6.25, 6.25)
    assert r2["status"] == "cancelled" and r2["reason"] == "cancelled (viewer)"
    assert r2["ended"] == 7.0 and "latency" not in r2
    assert bad["status"] == "refused" and "unknown object 'r9'" in bad["reason"]


def test_a_record_that_names_its_arrival_and_latency_is_taken_at_its_word() -> None:
    model = ViewModel()
    model.apply(order("gear", "queued", 11.5, arrived=5.0))
    model.apply(order("gear", "done", 73.75, latency=68.75))
    assert rows(model)["gear"]["arrived"] == 5.0
    assert rows(model)["gear"]["latency"] == 68.75


def test_replay_at_an_earlier_event_shows_the_orders_as_they_were() -> None:
    history = History(every=2)
    for record in (
        order("a", "queued", 0.0),
        order("a", "assigned", 0.0, robots=["r1"]),
        order("b", "queued", 1.0),
        order("a", "done", 3.0, robots=["r1"]),
    ):
        history.add(record)
    assert rows(history.view_at(0)) == {}
    assert rows(history.view_at(2))["a"]["status"] == "assigned"
    assert set(rows(history.view_at(2))) == {"a"}
    assert rows(history.view_at(3))["a"]["status"] == "assigned"
    assert rows(history.view_at(4))["a"]["status"] == "done"
    # A copy taken earlier keeps its rows when the view goes on.
    earlier = history.view_at(3)
    history.add(order("b", "done", 5.0))
    assert rows(earlier)["b"]["status"] == "queued"


def test_records_without_an_order_name_change_nothing() -> None:
    model = ViewModel()
    model.apply({"kind": "order", "status": "queued", "at": 0.0})
    model.apply({"kind": "order", "order": 7, "status": "queued", "at": 0.0})
    assert model.to_json()["orders"] == [] and model.index == 2


def test_the_oldest_final_orders_go_when_there_are_too_many() -> None:
    model = ViewModel()
    model.apply(order("open", "queued", 0.0))
    for n in range(MAX_ORDERS + 5):
        model.apply(order(f"o{n}", "done", float(n)))
    kept = rows(model)
    assert len(kept) == MAX_ORDERS
    assert "open" in kept and "o0" not in kept and f"o{MAX_ORDERS + 4}" in kept


@pytest.fixture
def controller() -> Iterator[Controller]:
    sm = smach.StateMachine(outcomes=["done"])
    sm.add("A", ScriptedState(["ok"], outcomes=["ok"]), transitions={"ok": "done"})
    with Controller(sm) as ctl:
        yield ctl


def test_an_extra_action_that_returns_data_answers_with_it_as_json(
    controller: Controller,
) -> None:
    listing = [{"id": "o1", "status": "done", "latency": 2.0}]
    controls = ViewerControls(
        controller,
        actions={"orders": lambda body: listing, "order": lambda body: {"id": "o2"}},
    )
    answer = controls.perform({"action": "orders"})
    assert answer["data"] == listing and json.loads(answer["result"]) == listing
    assert controls.perform({"action": "order", "goal": "x"})["data"] == {"id": "o2"}


def test_the_page_loads_the_queue_panel_script_and_style() -> None:
    sm = smach.StateMachine(outcomes=["done"])
    sm.add("A", ScriptedState(["ok"], outcomes=["ok"]), transitions={"ok": "done"})
    with serve(sm, quiet=True) as viewer:
        for path, kind in (("/static/orders.js", "javascript"), ("/static/orders.css", "css")):
            conn = http.client.HTTPConnection(viewer.host, viewer.port, timeout=10)
            conn.request("GET", path)
            response = conn.getresponse()
            body = response.read().decode("utf-8")
            conn.close()
            assert response.status == 200 and kind in (response.getheader("Content-Type") or "")
            assert "orders" in body
        conn = http.client.HTTPConnection(viewer.host, viewer.port, timeout=10)
        conn.request("GET", "/")
        page = conn.getresponse().read().decode("utf-8")
        conn.close()
    assert '<script src="/static/orders.js">' in page
    assert '<link rel="stylesheet" href="/static/orders.css">' in page
