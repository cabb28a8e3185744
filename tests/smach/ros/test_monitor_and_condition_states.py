"""MonitorState and ConditionState with real topics."""

from __future__ import annotations

import threading
import time
from typing import Any

import pytest

pytest.importorskip("smach.ros._api", reason="needs rclpy (the ros extra)")

from ros_helpers import wait_for
from std_msgs.msg import String

import smach
from smach.ros import ConditionState, MonitorState

pytestmark = pytest.mark.ros


class Talker:
    """Publishes 'message N' on a topic from a thread, 50 times a second."""

    def __init__(self, ros: Any, topic: str, text: str = "message") -> None:
        self.node = ros.node(f"talker_{topic}")
        self.pub = self.node.create_publisher(String, topic, 10)
        self.text = text
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self.run, daemon=True)
        self.thread.start()

    def run(self) -> None:
        n = 0
        while not self.stop.wait(0.02):
            n += 1
            self.pub.publish(String(data=f"{self.text} {n}"))

    def close(self) -> None:
        self.stop.set()
        self.thread.join(2)


def execute_in_thread(state: smach.State) -> tuple[threading.Thread, dict[str, Any]]:
    box: dict[str, Any] = {}

    def run() -> None:
        box["outcome"] = state.execute(smach.UserData())
        box["finished"] = time.monotonic()

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    return thread, box


@pytest.mark.timeout(30)
def test_monitor_is_valid_after_max_checks_and_writes_userdata(ros: Any) -> None:
    talker = Talker(ros, "chatter_ok")
    seen: list[str] = []

    def cond(ud: smach.UserData, msg: Any) -> bool:
        seen.append(msg.data)
        ud.last = msg.data
        return True

    state = MonitorState(
        ros.node("watcher"), "chatter_ok", String, cond, max_checks=3, output_keys=["last"]
    )
    ud = smach.UserData()
    try:
        assert state.execute(ud) == "valid"
    finally:
        talker.close()
    assert len(seen) == 3
    assert ud.last == seen[-1]


@pytest.mark.timeout(30)
def test_monitor_ignores_messages_before_the_first_execute(ros: Any) -> None:
    calls: list[str] = []
    state = MonitorState(
        ros.node("watcher"),
        "chatter_early",
        String,
        lambda ud, msg: calls.append(msg.data) or True,
        max_checks=1,
    )
    talker = Talker(ros, "chatter_early")
    try:
        time.sleep(0.5)  # messages arrive while the state is idle: dropped, no error
        assert calls == []
        assert state.execute(smach.UserData()) == "valid"
    finally:
        talker.close()
    assert len(calls) == 1


@pytest.mark.timeout(30)
def test_monitor_is_invalid_when_cond_cb_says_no_or_raises(ros: Any) -> None:
    talker = Talker(ros, "chatter_bad", text="garbage")
    node = ros.node("watcher")

    def parse(ud: smach.UserData, msg: Any) -> bool:
        return int(msg.data.split()[0]) > 0  # a malformed message raises ValueError

    try:
        assert (
            MonitorState(node, "chatter_bad", String, lambda ud, msg: False).execute(
                smach.UserData()
            )
            == "invalid"
        )
        assert (
            MonitorState(node, "chatter_bad", String, parse).execute(smach.UserData()) == "invalid"
        )
    finally:
        talker.close()


@pytest.mark.timeout(30)
def test_monitor_preempt_while_waiting_is_prompt_and_never_lost(ros: Any) -> None:
    node = ros.node("watcher")
    state = MonitorState(node, "silence", String, lambda ud, msg: True)
    for delay in (0.0, 0.001, 0.05, 0.2):
        thread, box = execute_in_thread(state)
        time.sleep(delay)
        asked = time.monotonic()
        state.request_preempt()
        thread.join(5)
        assert box["outcome"] == "preempted"
        assert box["finished"] - asked < 0.3


@pytest.mark.timeout(30)
def test_monitor_timeout_bounds_the_wait(ros: Any) -> None:
    state = MonitorState(ros.node("watcher"), "silence2", String, lambda ud, msg: True, timeout=0.3)
    start = time.monotonic()
    assert state.execute(smach.UserData()) == "invalid"
    assert time.monotonic() - start < 1.5


@pytest.mark.timeout(30)
def test_monitor_with_a_publisher_in_another_process(ros: Any) -> None:
    process = ros.server("publish", "chatter_remote", "--rate", "50")
    del process
    state = MonitorState(
        ros.node("watcher"),
        "chatter_remote",
        String,
        lambda ud, msg: msg.data.startswith("message"),
        max_checks=5,
    )
    assert state.execute(smach.UserData()) == "valid"


@pytest.mark.timeout(20)
def test_condition_state_true_false_timeout_and_preempt(ros: Any) -> None:
    node = ros.node("cond")
    flag = {"value": False}
    calls: list[int] = []

    def cond(ud: smach.UserData) -> bool:
        calls.append(1)
        return flag["value"]

    assert (
        ConditionState(node, cond, max_checks=3, poll_rate=100).execute(smach.UserData()) == "false"
    )
    assert len(calls) == 3  # the original checked max_checks + 1 times
    start = time.monotonic()
    assert (
        ConditionState(node, cond, max_checks=-1, timeout=0.3).execute(smach.UserData()) == "false"
    )
    assert 0.25 <= time.monotonic() - start < 1.0
    flag["value"] = True
    assert ConditionState(node, cond).execute(smach.UserData()) == "true"
    flag["value"] = False
    state = ConditionState(node, cond, max_checks=-1, poll_rate=1)
    thread, box = execute_in_thread(state)
    assert wait_for(lambda: len(calls) > 0)
    time.sleep(0.1)
    asked = time.monotonic()
    state.request_preempt()
    thread.join(3)
    assert box["outcome"] == "preempted"
    assert box["finished"] - asked < 0.2
