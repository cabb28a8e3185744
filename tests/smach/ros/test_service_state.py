"""ServiceState against real ROS 2 services."""

from __future__ import annotations

import threading
import time
from typing import Any

import pytest

pytest.importorskip("smach.ros._api", reason="needs rclpy (the ros extra)")

import ros_servers
from ros_helpers import read_lines, wait_for
from std_srvs.srv import SetBool

import smach
from smach.ros import ServiceState

pytestmark = pytest.mark.ros


def serve(ros: Any, name: str, mode: str = "normal") -> None:
    node = ros.node(f"server_{name}")
    ros_servers.setbool(node, name, mode)
    ros.spin(node)


@pytest.mark.timeout(30)
def test_calls_the_service_with_request_slots_and_writes_response_slots(ros: Any) -> None:
    serve(ros, "set_ok")
    state = ServiceState(
        ros.node("client"),
        "set_ok",
        SetBool,
        request_slots=["data"],
        response_slots=["success", "message"],
        response_key="response",
    )
    sm = smach.StateMachine(outcomes=["succeeded", "aborted", "preempted"])
    sm.userdata.data = True
    with sm:
        smach.StateMachine.add("CALL", state)
    assert sm.execute() == "succeeded"
    assert sm.userdata.success is True
    assert sm.userdata.message == "got True"
    assert sm.userdata.response.success is True


@pytest.mark.timeout(30)
def test_response_cb_chooses_the_outcome(ros: Any) -> None:
    serve(ros, "set_cb")

    @smach.cb_interface(outcomes=["refused"])
    def judge(ud: smach.UserData, response: Any) -> str:
        return "succeeded" if response.success else "refused"

    state = ServiceState(
        ros.node("client"),
        "set_cb",
        SetBool,
        request=SetBool.Request(data=False),
        response_cb=judge,
    )
    assert state.execute(smach.UserData()) == "refused"


@pytest.mark.timeout(20)
def test_service_that_never_appears_aborts_after_server_wait_timeout(ros: Any) -> None:
    state = ServiceState(ros.node("client"), "nobody", SetBool, server_wait_timeout=0.4)
    start = time.monotonic()
    assert state.execute(smach.UserData()) == "aborted"
    assert 0.4 <= time.monotonic() - start < 1.5


@pytest.mark.timeout(30)
def test_failing_callbacks_abort_instead_of_raising_name_error(ros: Any) -> None:
    serve(ros, "set_fail")
    node = ros.node("client")

    def boom(*args: Any) -> Any:
        raise RuntimeError("broken callback")

    assert (
        ServiceState(node, "set_fail", SetBool, request_cb=boom).execute(smach.UserData())
        == "aborted"
    )
    assert (
        ServiceState(node, "set_fail", SetBool, response_cb=boom).execute(smach.UserData())
        == "aborted"
    )
    rogue = ServiceState(node, "set_fail", SetBool, response_cb=lambda ud, r: "unheard_of")
    assert rogue.execute(smach.UserData()) == "aborted"
    missing = ServiceState(node, "set_fail", SetBool, request_key="req")
    assert missing.execute(smach.UserData()) == "aborted"


@pytest.mark.timeout(40)
def test_server_crashing_in_its_callback_aborts_the_call(ros: Any) -> None:
    process = ros.server("setbool", "set_crash", "--mode", "crash")
    lines = read_lines(process)
    state = ServiceState(
        ros.node("client"), "set_crash", SetBool, liveness_period=0.2, call_timeout=20
    )
    start = time.monotonic()
    assert state.execute(smach.UserData()) == "aborted"
    assert time.monotonic() - start < 8
    # The server printed it before crashing; our reader thread may get to it later.
    assert wait_for(lambda: "request" in lines, 5), lines
    assert wait_for(lambda: process.poll() is not None, 5)


@pytest.mark.timeout(30)
def test_call_timeout_aborts_a_call_that_takes_too_long(ros: Any) -> None:
    process = ros.server("setbool", "set_slow", "--mode", "slow")
    read_lines(process)
    state = ServiceState(ros.node("client"), "set_slow", SetBool, call_timeout=0.5)
    start = time.monotonic()
    assert state.execute(smach.UserData()) == "aborted"
    assert 0.5 <= time.monotonic() - start < 2.0


@pytest.mark.timeout(30)
def test_call_attempts_send_the_request_again_when_no_answer_came(ros: Any) -> None:
    process = ros.server("setbool", "set_slow_first", "--mode", "slow_first")
    lines = read_lines(process)
    state = ServiceState(
        ros.node("client"),
        "set_slow_first",
        SetBool,
        request=SetBool.Request(data=True),
        response_key="response",
        call_timeout=0.5,
        call_attempts=3,
    )
    ud = smach.UserData()
    assert state.execute(ud) == "succeeded"
    assert ud.response.message == "got True"
    assert wait_for(lambda: lines.count("request") == 2, 5)


@pytest.mark.timeout(30)
def test_every_unanswered_attempt_ends_in_aborted(ros: Any, caplog: Any) -> None:
    process = ros.server("setbool", "set_slow3", "--mode", "slow")
    lines = read_lines(process)
    state = ServiceState(
        ros.node("client"), "set_slow3", SetBool, call_timeout=0.3, call_attempts=2
    )
    assert state.execute(smach.UserData()) == "aborted"
    assert wait_for(lambda: lines.count("request") == 2, 5)
    assert "did not answer within 0.3 s (call_timeout), 2 attempts" in caplog.text


def test_call_attempts_need_a_call_timeout(ros: Any) -> None:
    with pytest.raises(smach.InvalidStateError, match="needs a call_timeout"):
        ServiceState(ros.node("client"), "x", SetBool, call_attempts=2)
    with pytest.raises(smach.InvalidStateError, match="integer >= 1"):
        ServiceState(ros.node("client2"), "x", SetBool, call_timeout=1, call_attempts=0)


@pytest.mark.timeout(30)
def test_preempt_during_a_call_returns_preempted_at_once(ros: Any) -> None:
    process = ros.server("setbool", "set_slow2", "--mode", "slow")
    lines = read_lines(process)
    state = ServiceState(ros.node("client"), "set_slow2", SetBool)
    box: dict[str, Any] = {}
    thread = threading.Thread(target=lambda: box.update(outcome=state.execute(smach.UserData())))
    thread.start()
    assert wait_for(lambda: "request" in lines, 10)
    asked = time.monotonic()
    state.request_preempt()
    thread.join(5)
    assert box["outcome"] == "preempted"
    assert time.monotonic() - asked < 0.5


@pytest.mark.timeout(30)
def test_peer_alive_saying_the_server_died_aborts_a_pending_call(ros: Any) -> None:
    process = ros.server("setbool", "set_slow_peer", "--mode", "slow")
    lines = read_lines(process)
    alive = threading.Event()
    alive.set()
    state = ServiceState(
        ros.node("client"),
        "set_slow_peer",
        SetBool,
        call_timeout=25,
        liveness_period=0.1,
        peer_alive=alive.is_set,
    )
    box: dict[str, Any] = {}
    thread = threading.Thread(target=lambda: box.update(outcome=state.execute(smach.UserData())))
    thread.start()
    assert wait_for(lambda: "request" in lines, 10)
    alive.clear()  # the caller's own check (a heartbeat, a process) says it is gone
    thread.join(10)
    assert box["outcome"] == "aborted"


@pytest.mark.timeout(30)
def test_a_failing_peer_alive_aborts_the_call(ros: Any, caplog: Any) -> None:
    process = ros.server("setbool", "set_slow_broken", "--mode", "slow")
    read_lines(process)

    def broken() -> bool:
        raise OSError("no such process")

    state = ServiceState(
        ros.node("client"), "set_slow_broken", SetBool, liveness_period=0.1, peer_alive=broken
    )
    assert state.execute(smach.UserData()) == "aborted"
    assert "peer_alive raised OSError: no such process" in caplog.text
