"""ActionServerWrapper: a state machine served as a ROS 2 action."""

from __future__ import annotations

import threading
import time
from typing import Any

import pytest

pytest.importorskip("smach.ros._api", reason="needs rclpy (the ros extra)")

from ros_helpers import wait_for
from test_msgs.action import Fibonacci

import smach
from smach.ros import ActionServerWrapper, SimpleActionState
from smach.ros._api import ActionClient, GoalStatus

pytestmark = pytest.mark.ros


class Step(smach.State):
    """Appends one Fibonacci number per execution, publishing it as feedback."""

    def __init__(self, pause: float = 0.05) -> None:
        super().__init__(
            outcomes=["more", "done", "preempted"],
            input_keys=["action_goal", "action_feedback"],
            output_keys=["action_feedback", "action_result"],
        )
        self.pause = pause

    def execute(self, ud: smach.UserData) -> str:
        if self.sleep(self.pause):
            self.service_preempt()
            return "preempted"
        seq = list(ud.action_feedback.sequence) or [0, 1]
        seq.append(seq[-1] + seq[-2])
        ud.action_feedback = Fibonacci.Feedback(sequence=seq)
        if len(seq) > ud.action_goal.order:
            ud.action_result = Fibonacci.Result(sequence=seq)
            return "done"
        return "more"


def fibonacci_machine(pause: float = 0.05) -> smach.StateMachine:
    sm = smach.StateMachine(outcomes=["succeeded", "preempted", "aborted"])
    with sm:
        smach.StateMachine.add(
            "STEP", Step(pause), transitions={"more": "STEP", "done": "succeeded"}
        )
    return sm


def wrap(ros: Any, name: str, pause: float = 0.05) -> ActionServerWrapper:
    return ActionServerWrapper(
        ros.node(f"wrapper_{name}"),
        name,
        Fibonacci,
        fibonacci_machine(pause),
        succeeded_outcomes=["succeeded"],
        aborted_outcomes=["aborted"],
        preempted_outcomes=["preempted"],
    )


def send(ros: Any, name: str, order: int, feedback: list[Any] | None = None) -> tuple[Any, Any]:
    node = ros.node(f"caller_{name}_{len(ros._nodes)}", spin=True)
    client = ActionClient(node, Fibonacci, name)
    assert client.wait_for_server(timeout_sec=10)
    future = client.send_goal_async(
        Fibonacci.Goal(order=order),
        feedback_callback=(lambda msg: feedback.append(list(msg.feedback.sequence)))
        if feedback is not None
        else None,
    )
    assert wait_for(future.done, 10)
    return client, future.result()


@pytest.mark.timeout(30)
def test_goal_runs_the_machine_with_feedback_and_result(ros: Any) -> None:
    wrap(ros, "sm_fib")
    feedback: list[list[int]] = []
    _, handle = send(ros, "sm_fib", 6, feedback)
    assert handle.accepted
    result = handle.get_result_async()
    assert wait_for(result.done, 10)
    assert result.result().status == GoalStatus.STATUS_SUCCEEDED
    assert list(result.result().result.sequence) == [0, 1, 1, 2, 3, 5, 8]
    assert wait_for(lambda: feedback and feedback[-1][-1] == 8, 2)


@pytest.mark.timeout(30)
def test_cancel_preempts_the_machine_and_the_goal_ends_canceled(ros: Any) -> None:
    wrap(ros, "sm_cancel", pause=0.1)
    _, handle = send(ros, "sm_cancel", 1000)
    time.sleep(0.3)
    asked = time.monotonic()
    cancel = handle.cancel_goal_async()
    result = handle.get_result_async()
    assert wait_for(result.done, 10)
    # The cancel's answer and the result come on their own channels, in either order.
    assert wait_for(cancel.done, 10)
    assert result.result().status == GoalStatus.STATUS_CANCELED
    assert time.monotonic() - asked < 1.0


@pytest.mark.timeout(30)
def test_a_second_goal_while_one_runs_is_rejected(ros: Any) -> None:
    wrap(ros, "sm_busy", pause=0.1)
    _, first = send(ros, "sm_busy", 1000)
    assert first.accepted
    time.sleep(0.2)
    _, second = send(ros, "sm_busy", 3)
    assert not second.accepted
    first.cancel_goal_async()
    assert wait_for(first.get_result_async().done, 10)


@pytest.mark.timeout(30)
def test_container_exception_aborts_the_goal(ros: Any) -> None:
    sm = smach.StateMachine(outcomes=["succeeded"])
    with sm:
        smach.StateMachine.add("BOOM", smach.CBState(lambda ud: 1 / 0, outcomes=["succeeded"]))
    ActionServerWrapper(
        ros.node("wrapper_boom"), "sm_boom", Fibonacci, sm, succeeded_outcomes=["succeeded"]
    )
    _, handle = send(ros, "sm_boom", 3)
    result = handle.get_result_async()
    assert wait_for(result.done, 10)
    assert result.result().status == GoalStatus.STATUS_ABORTED


@pytest.mark.timeout(40)
def test_simple_action_state_drives_a_wrapped_machine_in_the_same_process(ros: Any) -> None:
    # The old deadlock: a wrapped machine's action client waits for callbacks that the
    # single executor running the goal would have to serve. Both sides share smach's
    # executor here, and a preempt of the outer machine cancels the inner one.
    wrap(ros, "sm_inner", pause=0.05)
    node = ros.node("outer")
    outer = smach.StateMachine(outcomes=["succeeded", "aborted", "preempted"])
    with outer:
        smach.StateMachine.add(
            "REMOTE",
            SimpleActionState(
                node, "sm_inner", Fibonacci, goal=Fibonacci.Goal(order=5), result_key="r"
            ),
        )
    assert outer.execute() == "succeeded"
    assert list(outer.userdata.r.sequence)[-1] == 5

    long_outer = smach.StateMachine(outcomes=["succeeded", "aborted", "preempted"])
    with long_outer:
        smach.StateMachine.add(
            "REMOTE",
            SimpleActionState(node, "sm_inner", Fibonacci, goal=Fibonacci.Goal(order=10_000)),
        )
    box: dict[str, Any] = {}
    thread = threading.Thread(target=lambda: box.update(outcome=long_outer.execute()))
    thread.start()
    time.sleep(0.4)
    long_outer.request_preempt()
    thread.join(10)
    assert box["outcome"] == "preempted"
