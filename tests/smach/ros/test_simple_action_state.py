"""SimpleActionState against real ROS 2 action servers, in this process and in others."""

from __future__ import annotations

import signal
import threading
import time
from typing import Any

import pytest

pytest.importorskip("smach.ros._api", reason="needs rclpy (the ros extra)")

import ros_servers
from ros_helpers import read_lines, wait_for
from test_msgs.action import Fibonacci

import smach
from smach.ros import SimpleActionState
from smach.ros._api import GoalStatus, MultiThreadedExecutor, rclpy
from smach.ros.executor import SmachExecutor

pytestmark = pytest.mark.ros


def serve(ros: Any, name: str, mode: str = "normal", step: float = 0.05) -> Any:
    """An in-process Fibonacci server on its own node and executor."""
    node = ros.node(f"server_{name}")
    server = ros_servers.fibonacci(node, name, mode, step, stop=ros.closing)
    ros.spin(node, MultiThreadedExecutor(num_threads=4, context=ros.context))
    return server


def run_in_thread(
    state: smach.State, ud: smach.UserData | None = None
) -> tuple[threading.Thread, dict[str, Any]]:
    box: dict[str, Any] = {}

    def run() -> None:
        start = time.monotonic()
        box["outcome"] = state.execute(ud if ud is not None else smach.UserData())
        box["finished"] = time.monotonic()
        box["took"] = box["finished"] - start

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    return thread, box


@pytest.mark.timeout(30)
def test_succeeds_with_goal_slots_result_key_feedback_and_status(ros: Any, capsys: Any) -> None:
    serve(ros, "fib_ok")
    node = ros.node("client")
    feedback: list[list[int]] = []
    statuses: list[int] = []

    def on_result(ud: smach.UserData, status: int, result: Any) -> None:
        statuses.append(status)

    state = SimpleActionState(
        node,
        "fib_ok",
        Fibonacci,
        goal_slots=["order"],
        result_key="fib",
        result_slots=["sequence"],
        result_cb=on_result,
        feedback_cb=lambda ud, fb: feedback.append(list(fb.sequence)),
        server_wait_timeout=10.0,
    )
    sm = smach.StateMachine(outcomes=["succeeded", "aborted", "preempted"])
    sm.userdata.order = 5
    with sm:
        smach.StateMachine.add("FIB", state, remapping={"order": "order"})
    assert sm.execute() == "succeeded"
    assert list(sm.userdata.sequence) == [0, 1, 1, 2, 3, 5]
    assert list(sm.userdata.fib.sequence) == [0, 1, 1, 2, 3, 5]
    assert statuses == [GoalStatus.STATUS_SUCCEEDED]
    # Feedback (a topic) that arrives after the result (a service) is not delivered: the
    # sequences received are the result's beginnings, the last one maybe not all of it.
    assert feedback and all(fb == [0, 1, 1, 2, 3, 5][: len(fb)] for fb in feedback), feedback
    capsys.readouterr()


@pytest.mark.timeout(20)
def test_server_that_never_appears_aborts_after_server_wait_timeout(ros: Any) -> None:
    state = SimpleActionState(
        ros.node("client"), "nobody_serves_this", Fibonacci, server_wait_timeout=0.5
    )
    start = time.monotonic()
    assert state.execute(smach.UserData()) == "aborted"
    assert 0.5 <= time.monotonic() - start < 2.0


@pytest.mark.timeout(20)
def test_timeouts_accept_rclpy_durations(ros: Any) -> None:
    duration = rclpy.duration.Duration(seconds=0.3)
    state = SimpleActionState(ros.node("client"), "nobody", Fibonacci, server_wait_timeout=duration)
    start = time.monotonic()
    assert state.execute(smach.UserData()) == "aborted"
    assert 0.3 <= time.monotonic() - start < 1.5


@pytest.mark.timeout(20)
def test_bad_timeout_values_are_refused_at_construction(ros: Any) -> None:
    node = ros.node("client")
    with pytest.raises(TypeError, match="exec_timeout"):
        SimpleActionState(node, "x", Fibonacci, exec_timeout="soon")
    with pytest.raises(ValueError, match="server_wait_timeout"):
        SimpleActionState(node, "x", Fibonacci, server_wait_timeout=-1)


@pytest.mark.timeout(20)
def test_unknown_goal_slot_is_a_construction_error(ros: Any) -> None:
    with pytest.raises(smach.InvalidStateError, match="not fields of"):
        SimpleActionState(ros.node("client"), "x", Fibonacci, goal_slots=["speed"])


@pytest.mark.timeout(30)
def test_rejected_goal_aborts_instead_of_hanging(ros: Any) -> None:
    process = ros.server("fibonacci", "fib_reject", "--mode", "reject")
    lines = read_lines(process)
    state = SimpleActionState(
        ros.node("client"), "fib_reject", Fibonacci, goal=Fibonacci.Goal(order=3)
    )
    start = time.monotonic()
    assert state.execute(smach.UserData()) == "aborted"
    assert time.monotonic() - start < 5
    assert wait_for(lambda: "goal" in lines, 2)


@pytest.mark.timeout(30)
def test_server_abort_is_aborted_not_preempted(ros: Any) -> None:
    process = ros.server("fibonacci", "fib_abort", "--mode", "abort")
    read_lines(process)
    statuses: list[int] = []
    state = SimpleActionState(
        ros.node("client"),
        "fib_abort",
        Fibonacci,
        goal=Fibonacci.Goal(order=10),
        result_key="partial",
        result_cb=lambda ud, status, result: statuses.append(status),
    )
    ud = smach.UserData()
    assert state.execute(ud) == "aborted"
    assert statuses == [GoalStatus.STATUS_ABORTED]
    assert list(ud.partial.sequence) == [0, 1, 1]


@pytest.mark.timeout(40)
def test_server_killed_mid_goal_aborts_within_the_lease_bound(ros: Any) -> None:
    # The server runs with a 2 s DDS lease (short_lease.xml); the default is 20 s.
    process = ros.server("fibonacci", "fib_killed", "--step", "1.0")
    lines = read_lines(process)
    state = SimpleActionState(
        ros.node("client"),
        "fib_killed",
        Fibonacci,
        goal=Fibonacci.Goal(order=100),
        liveness_period=0.2,
    )
    thread, box = run_in_thread(state)
    assert wait_for(lambda: "goal" in lines, 10)
    time.sleep(0.3)
    process.send_signal(signal.SIGKILL)
    killed = time.monotonic()
    thread.join(15)
    assert box.get("outcome") == "aborted"
    detected = box["finished"] - killed
    print(f"server killed mid-goal detected after {detected:.2f} s")
    assert detected < 6.0


@pytest.mark.timeout(20)
def test_preempt_while_waiting_for_the_server_is_prompt(ros: Any) -> None:
    state = SimpleActionState(ros.node("client"), "fib_later", Fibonacci, server_wait_timeout=30)
    thread, box = run_in_thread(state)
    time.sleep(0.3)
    asked = time.monotonic()
    state.request_preempt()
    assert time.monotonic() - asked < 0.05  # request_preempt does not block
    thread.join(5)
    assert box["outcome"] == "preempted"
    assert box["finished"] - asked < 0.5
    assert not state.preempt_requested()


@pytest.mark.timeout(30)
def test_preempt_of_an_active_goal_cancels_it_on_the_server(ros: Any) -> None:
    process = ros.server("fibonacci", "fib_cancel", "--step", "0.2")
    lines = read_lines(process)
    statuses: list[int] = []
    state = SimpleActionState(
        ros.node("client"),
        "fib_cancel",
        Fibonacci,
        goal=Fibonacci.Goal(order=100),
        result_cb=lambda ud, status, result: statuses.append(status),
    )
    thread, box = run_in_thread(state)
    assert wait_for(lambda: "goal" in lines, 10)
    time.sleep(0.3)
    asked = time.monotonic()
    state.request_preempt()
    returned = time.monotonic() - asked
    thread.join(10)
    assert box["outcome"] == "preempted"
    assert returned < 0.05
    latency = box["finished"] - asked
    print(f"preempt latency over ROS (cancel round trip): {latency:.3f} s")
    assert latency < 2.0
    assert wait_for(lambda: "canceled" in lines, 2)
    assert "cancel" in lines
    assert statuses == [GoalStatus.STATUS_CANCELED]


@pytest.mark.timeout(30)
def test_preempt_during_a_slow_cancel_waits_for_the_server_to_finish(ros: Any) -> None:
    serve(ros, "fib_slow_cancel", mode="slow-cancel", step=0.1)
    state = SimpleActionState(
        ros.node("client"), "fib_slow_cancel", Fibonacci, goal=Fibonacci.Goal(order=200)
    )
    thread, box = run_in_thread(state)
    time.sleep(0.5)
    asked = time.monotonic()
    state.request_preempt()
    time.sleep(0.2)
    state.request_preempt()  # a second request while cancelling changes nothing
    thread.join(10)
    assert box["outcome"] == "preempted"
    assert 0.6 <= box["finished"] - asked < 3.0


@pytest.mark.timeout(30)
def test_cancel_refused_by_the_server_aborts_after_preempt_timeout(ros: Any) -> None:
    serve(ros, "fib_stubborn", mode="ignore-cancel", step=0.1)
    state = SimpleActionState(
        ros.node("client"),
        "fib_stubborn",
        Fibonacci,
        goal=Fibonacci.Goal(order=25),
        preempt_timeout=0.8,
    )
    thread, box = run_in_thread(state)
    time.sleep(0.4)
    asked = time.monotonic()
    state.request_preempt()
    thread.join(10)
    assert box["outcome"] == "aborted"
    assert 0.8 <= box["finished"] - asked < 2.5
    # Not serviced: the request stays for whoever runs next (the container).
    assert state.preempt_requested()


@pytest.mark.timeout(30)
def test_exec_timeout_cancels_the_goal_and_aborts(ros: Any) -> None:
    serve(ros, "fib_long", step=0.1)
    statuses: list[int] = []
    state = SimpleActionState(
        ros.node("client"),
        "fib_long",
        Fibonacci,
        goal=Fibonacci.Goal(order=200),
        exec_timeout=0.5,
        result_cb=lambda ud, status, result: statuses.append(status),
    )
    start = time.monotonic()
    assert state.execute(smach.UserData()) == "aborted"
    assert 0.5 <= time.monotonic() - start < 3.0
    assert statuses == [GoalStatus.STATUS_CANCELED]


@pytest.mark.timeout(30)
def test_failing_goal_cb_and_missing_goal_key_abort(ros: Any) -> None:
    serve(ros, "fib_cb")
    node = ros.node("client")

    def broken(ud: smach.UserData, goal: Any) -> Any:
        raise ValueError("no goal today")

    assert (
        SimpleActionState(node, "fib_cb", Fibonacci, goal_cb=broken).execute(smach.UserData())
        == "aborted"
    )
    state = SimpleActionState(node, "fib_cb", Fibonacci, goal_key="goal")
    assert state.execute(smach.UserData()) == "aborted"


@pytest.mark.timeout(30)
def test_result_cb_outcome_overrides_and_must_be_registered(ros: Any) -> None:
    serve(ros, "fib_outcome")
    node = ros.node("client")

    @smach.cb_interface(outcomes=["long"])
    def judge(ud: smach.UserData, status: int, result: Any) -> str:
        return "long" if len(result.sequence) > 3 else "succeeded"

    state = SimpleActionState(
        node, "fib_outcome", Fibonacci, goal=Fibonacci.Goal(order=4), result_cb=judge
    )
    assert "long" in state.get_registered_outcomes()
    assert state.execute(smach.UserData()) == "long"
    rogue = SimpleActionState(
        node, "fib_outcome", Fibonacci, goal=Fibonacci.Goal(order=2), result_cb=lambda *a: "unheard"
    )
    assert rogue.execute(smach.UserData()) == "aborted"


@pytest.mark.timeout(30)
def test_state_machine_preempt_reaches_the_action_state(ros: Any) -> None:
    serve(ros, "fib_sm", step=0.1)
    sm = smach.StateMachine(outcomes=["succeeded", "aborted", "preempted"])
    with sm:
        smach.StateMachine.add(
            "FIB",
            SimpleActionState(
                ros.node("client"), "fib_sm", Fibonacci, goal=Fibonacci.Goal(order=300)
            ),
        )
    thread, box = run_in_thread(sm)
    time.sleep(0.5)
    asked = time.monotonic()
    sm.request_preempt()
    assert time.monotonic() - asked < 0.05
    thread.join(10)
    assert box["outcome"] == "preempted"
    assert box["finished"] - asked < 2.0


@pytest.mark.timeout(30)
def test_peer_alive_turning_false_aborts_an_active_goal(ros: Any) -> None:
    serve(ros, "fib_peer", step=0.5)
    alive = threading.Event()
    alive.set()
    feedback: list[int] = []
    state = SimpleActionState(
        ros.node("client"),
        "fib_peer",
        Fibonacci,
        goal=Fibonacci.Goal(order=100),
        liveness_period=0.1,
        peer_alive=alive.is_set,
        feedback_cb=lambda ud, fb: feedback.append(len(fb.sequence)),
    )
    thread, box = run_in_thread(state)
    assert wait_for(lambda: bool(feedback), 10)
    alive.clear()  # e.g. the server's heartbeat stopped; it is still in the ROS graph
    thread.join(10)
    assert box["outcome"] == "aborted"


def test_peer_alive_must_be_callable(ros: Any) -> None:
    with pytest.raises(smach.InvalidStateError, match="peer_alive must be callable"):
        SimpleActionState(ros.node("client"), "fib", Fibonacci, peer_alive=True)  # type: ignore[arg-type]


@pytest.mark.timeout(30)
def test_a_state_whose_node_is_destroyed_while_it_waits_aborts_without_a_thread_error(
    ros: Any,
) -> None:
    node = ros.node("client")
    state = SimpleActionState(node, "fib_never", Fibonacci, server_wait_timeout=30)
    thread, box = run_in_thread(state)
    time.sleep(0.3)
    # What a program's shutdown does: smach's helper node (the state's client) goes.
    assert SmachExecutor.for_node(node).shutdown()
    thread.join(10)
    assert box["outcome"] == "aborted"
