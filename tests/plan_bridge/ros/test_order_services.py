"""Orders over ROS 2 with real rclpy: the submit, cancel and list services and the
status topic of a mission of orders (plan_bridge.ros.order_services), through the
Python API and through `plan-bridge run --ros --orders-open`."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("smach.ros.rclpy_api", reason="needs rclpy (the ros extra)")

from order_operator import Operator
from ros_context import nodes_in_own_context

from plan_bridge.execution.control import OperatorConsole
from plan_bridge.missions.mission import load_target
from plan_bridge.missions.runner import MissionOptions, prepare_mission
from plan_bridge.orders.order_executive import OrderExecutive
from plan_bridge.ros.order_services import OrderServices

ROOMS = Path(__file__).parents[1] / "data" / "rooms"

pytestmark = [pytest.mark.ros, pytest.mark.timeout(180)]


def wait_until(predicate: Callable[[], bool], what: str, timeout: float = 60.0) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.02)


@pytest.fixture
def mission_node() -> Iterator[Any]:
    with nodes_in_own_context("mission") as (node,):
        yield node


def test_orders_are_submitted_cancelled_and_listed_over_ros_and_each_change_published(
    mission_node: Any,
) -> None:
    target = load_target(str(ROOMS / "domain.pddl"), str(ROOMS / "problems" / "p02.pddl"))
    mission = prepare_mission(target, MissionOptions(orders_open=True, planner="fast-downward"))
    executive = mission.executive
    assert isinstance(executive, OrderExecutive)
    # Paused: a plan is made for the orders and held before its first step.
    console = OperatorConsole(executive, paused=True, source="api")
    services = OrderServices(mission_node, executive.desk(), name="shop/orders")
    assert services.names == {
        "submit": "/shop/orders/submit",
        "cancel": "/shop/orders/cancel",
        "list": "/shop/orders/list",
        "status": "/shop/orders/status",
    }
    operator = Operator("/shop/orders")
    outcome: list[str | None] = []
    runner = threading.Thread(target=lambda: outcome.append(mission.run()), daemon=True)
    runner.start()
    try:
        assert operator.call("submit", "(at r2 office)") == (True, "o1")
        wait_until(lambda: "assigned" in operator.statuses("o1"), "o1 assigned")
        ok, text = operator.call("cancel", "o1")
        assert ok, text
        cancelled = json.loads(text)
        assert (cancelled["id"], cancelled["status"]) == ("o1", "cancelled")
        assert cancelled["reason"] == "cancelled (ros)" and cancelled["origin"] == "ros"
        ok, text = operator.call("cancel", json.dumps({"id": "o1", "reason": "twice"}))
        assert not ok and "order 'o1' is cancelled already" in text
        order = {"goal": "(item-at cup office)", "id": "cup", "priority": 2, "within": 100}
        assert operator.call("submit", json.dumps(order)) == (True, "cup")
        ok, text = operator.call("submit", json.dumps({**order, "priority": 1}))
        assert not ok and text == "order id 'cup' is already used; ids must be unique"
        for bad, refusal in (
            ("", "order needs 'goal'"),
            ('{"goal": "(at r1 hall)", "priority": "high"}', "'priority' is an integer"),
            ('{"goal": ', "the request is not JSON"),
            ('{"within": 5}', "order needs 'goal'"),
        ):
            ok, text = operator.call("submit", bad)
            assert not ok and refusal in text, (bad, text)
        ok, text = operator.call("cancel", "nope")
        assert (ok, text) == (False, "no order 'nope'")
        console.controller.resume()
        wait_until(lambda: "done" in operator.statuses("cup"), "cup done on the status topic")
        ok, text = operator.call("list")
        assert ok
        listed = {o["id"]: o for o in json.loads(text)}
        assert listed["cup"]["status"] == "done" and listed["cup"]["robots"] == ["r1"]
        assert listed["cup"]["deadline"] == listed["cup"]["arrived"] + 100
        assert listed["o1"]["status"] == "cancelled"
        # Each change once, in the order it happened.
        assert operator.statuses("o1") == ["queued", "assigned", "cancelled"]
        assert operator.statuses("cup") == ["queued", "assigned", "active", "done"]
        last = [m for m in operator.status if m["id"] == "cup"][-1]
        assert last["goal"] == "(item-at cup office)" and last["priority"] == 2
        assert isinstance(last["changed"], float) and last["latency"] >= 0
    finally:
        executive.orders.close()  # nothing more may come: the mission ends
        runner.join(60)
        services.close()
        console.close()
        operator.close()
    assert outcome == ["succeeded"]


def test_run_with_ros_and_orders_open_serves_the_order_services(tmp_path: Path) -> None:
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    process = subprocess.Popen(
        [sys.executable, "-m", "plan_bridge", "run", str(ROOMS), "--problem", "p02.pddl",
         "--ros", "--orders-open"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )  # fmt: skip
    lines: list[str] = []

    def read() -> None:
        assert process.stderr is not None
        for line in process.stderr:
            lines.append(line.rstrip("\n"))

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    operator = None
    try:
        wait_until(
            lambda: (
                any(line.startswith("[wait] no open order") for line in lines)
                or process.poll() is not None
            ),
            "the mission to wait for orders",
            120,
        )
        served = next((line for line in lines if line.startswith("ros: orders served")), "")
        assert re.fullmatch(
            r"ros: orders served: /orders/submit, /orders/cancel, /orders/list; "
            r"status on /orders/status",
            served,
        ), "\n".join(lines)
        operator = Operator("/orders")
        assert operator.call("submit", "(item-at cup office)") == (True, "o1")
        wait_until(lambda: "done" in operator.statuses("o1"), "o1 done", 120)
        assert operator.statuses("o1") == ["queued", "assigned", "active", "done"]
        ok, text = operator.call("list")
        assert ok and json.loads(text)[0]["origin"] == "ros"
        # The run prints it on its stderr, which our reader thread gets when it gets to
        # it: maybe after the status topic said so.
        wait_until(
            lambda: any(line.startswith("[order] o1 done") for line in lines),
            "the run's [order] o1 done line",
            10,
        )
    finally:
        if operator is not None:
            operator.close()
        if process.poll() is None:
            process.send_signal(signal.SIGINT)  # open for orders: it runs until stopped
        try:
            process.wait(30)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(10)
        reader.join(10)
        assert process.stderr is not None
        process.stderr.close()
