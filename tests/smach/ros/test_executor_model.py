"""Threading: states work however (and whether) the user's node is spun (#128)."""

from __future__ import annotations

import threading
import time
from typing import Any

import pytest

pytest.importorskip("smach.ros._api", reason="needs rclpy (the ros extra)")

import ros_servers
from std_srvs.srv import SetBool, Trigger
from test_msgs.action import Fibonacci

import smach
from smach.ros import ServiceState, SimpleActionState, SmachNode
from smach.ros._api import SingleThreadedExecutor

pytestmark = pytest.mark.ros


def machine(node: Any) -> smach.StateMachine:
    sm = smach.StateMachine(outcomes=["succeeded", "aborted", "preempted"])
    with sm:
        smach.StateMachine.add(
            "FIB",
            SimpleActionState(node, "exec_fib", Fibonacci, goal=Fibonacci.Goal(order=4)),
            transitions={"succeeded": "SET"},
        )
        smach.StateMachine.add(
            "SET", ServiceState(node, "exec_set", SetBool, request=SetBool.Request(data=True))
        )
    return sm


def servers(ros: Any) -> None:
    node = ros.node("servers")
    ros_servers.fibonacci(node, "exec_fib", "normal", 0.02, stop=ros.closing)
    ros_servers.setbool(node, "exec_set", "normal")
    ros.spin(node)


@pytest.mark.timeout(30)
def test_states_work_when_the_users_node_is_never_spun(ros: Any) -> None:
    servers(ros)
    assert machine(ros.node("lonely")).execute() == "succeeded"


@pytest.mark.timeout(30)
def test_machine_run_inside_a_callback_of_a_single_threaded_executor_does_not_deadlock(
    ros: Any,
) -> None:
    # The user's node is spun by one thread, and the machine runs *inside* one of its
    # service callbacks: that thread is blocked for the whole run. With the original,
    # the action client's callbacks needed that very thread.
    servers(ros)
    node = ros.node("single")
    sm = machine(node)
    outcomes: list[str | None] = []

    def run_mission(request: Any, response: Any) -> Any:
        outcome = sm.execute()
        outcomes.append(outcome)
        response.success = outcome == "succeeded"
        response.message = str(outcome)
        return response

    node.create_service(Trigger, "run_mission", run_mission)
    ros.spin(node, SingleThreadedExecutor(context=ros.context))

    caller = ros.node("caller", spin=True)
    client = caller.create_client(Trigger, "run_mission")
    assert client.wait_for_service(timeout_sec=10)
    future = client.call_async(Trigger.Request())
    deadline = time.monotonic() + 15
    while not future.done() and time.monotonic() < deadline:
        time.sleep(0.02)
    assert future.done(), "the machine deadlocked inside the executor's callback"
    assert future.result().success
    assert outcomes == ["succeeded"]


@pytest.mark.timeout(30)
def test_machine_runs_while_a_single_threaded_executor_spins_the_node_elsewhere(ros: Any) -> None:
    servers(ros)
    node = ros.node("spun")
    ros.spin(node, SingleThreadedExecutor(context=ros.context))
    results: list[str | None] = []
    thread = threading.Thread(target=lambda: results.append(machine(node).execute()))
    thread.start()
    thread.join(15)
    assert results == ["succeeded"]


@pytest.mark.timeout(30)
def test_smach_node_spins_itself(ros: Any) -> None:
    servers(ros)
    node = SmachNode("smach_node", context=ros.context)
    node.start()
    try:
        assert machine(node).execute() == "succeeded"
    finally:
        node.stop()
        node.destroy_node()


@pytest.mark.timeout(20)
def test_a_node_argument_that_is_not_a_node_is_refused() -> None:
    with pytest.raises(smach.InvalidStateError, match="rclpy Node"):
        SimpleActionState(node="not a node", action_name="x", action_spec=Fibonacci)
