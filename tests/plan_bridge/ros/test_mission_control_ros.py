"""The mission's control services over real rclpy: change the goal, skip, abort."""

from __future__ import annotations

import json
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("smach.ros.rclpy_api", reason="needs rclpy (the ros extra)")

from ros_context import nodes_in_own_context
from test_msgs.srv import BasicTypes

import smach
from plan_bridge.execution.control import OperatorConsole
from plan_bridge.execution.executive import Executive
from plan_bridge.execution.simulation import SimulatedWorld, SymbolicSkill
from plan_bridge.pddl.task import load_task
from plan_bridge.planning.planner import PlanStep, get_planner
from plan_bridge.skills.registry import SkillRegistry
from smach.ros import IntrospectionServer
from smach.ros.rclpy_api import rclpy

ROOMS = Path(__file__).parents[1] / "data" / "rooms"

pytestmark = [pytest.mark.ros, pytest.mark.timeout(120)]


@pytest.fixture
def nodes() -> Iterator[tuple[Any, Any]]:
    with nodes_in_own_context("executive", "operator") as (executive_node, operator):
        yield executive_node, operator


class WaitAtPick(smach.State):
    """The symbolic skill; the first pick waits until preempted (30 s at most)."""

    started = threading.Event()

    def __init__(self, world: SimulatedWorld, step: PlanStep) -> None:
        super().__init__(
            outcomes=["succeeded", "aborted", "preempted"], output_keys=["observations"]
        )
        self.inner = SymbolicSkill(world, step)
        self.step = step

    def execute(self, ud: smach.UserData) -> str:
        if self.step.action == "pick" and not WaitAtPick.started.is_set():
            WaitAtPick.started.set()
            if self.preempt_event.wait(30):
                self.service_preempt()
                return "preempted"
        return str(self.inner.execute(ud))


def call(operator: Any, name: str, text: str) -> Any:
    client = operator.create_client(BasicTypes, name)
    try:
        executor = rclpy.executors.SingleThreadedExecutor(context=operator.context)
        executor.add_node(operator)
        assert client.wait_for_service(timeout_sec=10), f"no service {name}"
        future = client.call_async(BasicTypes.Request(string_value=text))
        executor.spin_until_future_complete(future, timeout_sec=10)
        executor.remove_node(operator)
        executor.shutdown()
        assert future.done(), f"{name} did not answer"
        return future.result()
    finally:
        operator.destroy_client(client)


def test_the_goal_changes_over_a_ros_service_and_the_mission_follows(
    nodes: tuple[Any, Any],
) -> None:
    executive_node, operator = nodes
    WaitAtPick.started.clear()
    task = load_task(ROOMS / "domain.pddl", ROOMS / "problems" / "p01.pddl")
    world = SimulatedWorld(task, seed=0, fail_rate=0.0)
    ex = Executive(
        task,
        SkillRegistry(fallback=lambda step: WaitAtPick(world, step)),
        get_planner("fast-downward"),
    )
    console = OperatorConsole(ex, source="ros")
    result: list[str | None] = []
    with IntrospectionServer("mission", ex, "/MISSION", node=executive_node) as server:
        services = server.serve_control(console.controller, actions=console.viewer_actions())
        assert services.names["change_goal"] == "/mission/control/change_goal"
        runner = threading.Thread(target=lambda: result.append(ex.execute()), daemon=True)
        runner.start()
        assert WaitAtPick.started.wait(60)
        bad = call(operator, "/mission/control/change_goal", "(at robot1 garage)")
        assert not bad.bool_value and "unknown object 'garage'" in bad.string_value
        reply = call(operator, "/mission/control/change_goal", "(at robot1 office)")
        assert reply.bool_value, reply.string_value
        assert "changed the goal to (at robot1 office)" in reply.string_value
        runner.join(60)
        assert result == ["succeeded"]
        assert ("at", "robot1", "office") in world.facts
        status = call(operator, "/mission/control/request", json.dumps({"action": "replan"}))
        assert not status.bool_value and "not running" in status.string_value
    console.close()
    actions = [(r.action, r.source) for r in console.controller.history]
    assert ("goal", "ros") in actions
