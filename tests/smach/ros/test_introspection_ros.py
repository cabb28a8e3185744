"""IntrospectionServer and IntrospectionClient over real topics; the smach_ros package."""

from __future__ import annotations

import json
import subprocess
import sys
import threading
import time
from typing import Any

import pytest

pytest.importorskip("smach.ros._api", reason="needs rclpy (the ros extra)")

from std_msgs.msg import String

import smach
from smach.ros import IntrospectionClient, IntrospectionServer
from smach.ros.introspection import FORMAT, STATUS_TOPIC, _qos
from smach.testing import BlockingState

pytestmark = pytest.mark.ros


def mission() -> tuple[smach.StateMachine, Any]:
    gate = BlockingState(outcomes=["done", "preempted"])
    sm = smach.StateMachine(outcomes=["finished"])
    sm.userdata.lock = threading.Lock()  # unpicklable: the original could not publish this
    sm.userdata.big = list(range(10_000))
    sub = smach.StateMachine(outcomes=["done"])
    with sub:
        smach.StateMachine.add("WAIT", gate, transitions={"preempted": "done"})
    with sm:
        smach.StateMachine.add(
            "FIRST", smach.CBState(lambda ud: "ok", outcomes=["ok"]), transitions={"ok": "SUB"}
        )
        smach.StateMachine.add("SUB", sub, transitions={"done": "finished"})
    return sm, gate


@pytest.mark.timeout(30)
def test_client_sees_structure_and_live_status_of_every_container(ros: Any) -> None:
    sm, gate = mission()
    server = IntrospectionServer(
        "intro_test", sm, "/SM_ROOT", node=ros.node("exec"), update_rate=0.5
    )
    client = IntrospectionClient(ros.node("viewer"))
    with server:
        structure = client.wait_for_structure("intro_test", "/SM_ROOT", timeout=10)
        assert structure is not None
        assert structure["children"] == ["FIRST", "SUB"]
        assert structure["container_outcomes"] == ["finished"]
        assert {
            "outcome": "ok",
            "source": "FIRST",
            "target": "SUB",
            "terminal": False,
        } in structure["edges"]
        assert {
            "outcome": "done",
            "source": "SUB",
            "target": "finished",
            "terminal": True,
        } in structure["edges"]
        assert client.wait_for_structure("intro_test", "/SM_ROOT/SUB", timeout=5) is not None

        thread = threading.Thread(target=sm.execute)
        thread.start()
        status = client.wait_for_status(
            "intro_test", "/SM_ROOT/SUB", lambda s: s["active_states"] == ["WAIT"], timeout=10
        )
        assert status is not None
        root = client.wait_for_status(
            "intro_test", "/SM_ROOT", lambda s: s["active_states"] == ["SUB"], timeout=5
        )
        assert root is not None
        assert root["local_data"]["lock"].startswith("<unlocked _thread.lock")
        assert len(root["local_data"]["big"]) == 21  # summarised, not 10 000 numbers
        assert "/intro_test" in client.get_servers()
        gate.release("done")
        thread.join(5)
        done = client.wait_for_status(
            "intro_test", "/SM_ROOT", lambda s: s["active_states"] == [], timeout=5
        )
        assert done is not None
        heartbeat = client.wait_for_status(
            "intro_test", "/SM_ROOT", lambda s: s["info"] == "HEARTBEAT", timeout=5
        )
        assert heartbeat is not None
    client.destroy()


@pytest.mark.timeout(30)
def test_execution_does_not_wait_for_the_publisher(ros: Any) -> None:
    sm = smach.StateMachine(outcomes=["done"])
    counter = {"n": 0}

    def tick(ud: smach.UserData) -> str:
        counter["n"] += 1
        return "again" if counter["n"] < 2000 else "done"

    with sm:
        smach.StateMachine.add(
            "TICK", smach.CBState(tick, outcomes=["again", "done"]), transitions={"again": "TICK"}
        )
    with IntrospectionServer("intro_fast", sm, node=ros.node("exec")) as server:
        start = time.monotonic()
        assert sm.execute() == "done"
        took = time.monotonic() - start
        time.sleep(0.3)
        # 2000 transitions were coalesced into far fewer messages.
        assert server.published < 500
    assert took < 2.0


@pytest.mark.timeout(30)
def test_client_ignores_messages_that_are_not_introspection_json(ros: Any) -> None:
    client = IntrospectionClient(ros.node("viewer"))
    client.watch("intro_fake")
    node = ros.node("prankster")
    pub = node.create_publisher(String, "/intro_fake" + STATUS_TOPIC, _qos(10))
    time.sleep(0.5)
    for text in (
        "not json",
        "[1, 2]",
        json.dumps({"format": "other", "path": "/x"}),
        "cos\nsystem\n(S'ls'\ntR.",
    ):
        pub.publish(String(data=text))
    pub.publish(String(data=json.dumps({"format": FORMAT, "path": "/ok", "active_states": []})))
    assert client.wait_for_status("intro_fake", "/ok", timeout=5) is not None
    assert client.ignored == 4
    assert client.status("intro_fake", "/x") is None
    client.destroy()


def test_smach_ros_reexports_smach_ros() -> None:
    import smach.ros
    import smach_ros

    for name in smach.ros.__all__:
        assert getattr(smach_ros, name) is getattr(smach.ros, name)


def test_smach_core_never_imports_rclpy() -> None:
    code = (
        "import sys, smach, smach.introspection.journal\n"
        "assert 'rclpy' not in sys.modules, 'smach imported rclpy'\n"
        "print('ok')\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60
    )
    assert result.stdout.strip() == "ok", result.stderr
