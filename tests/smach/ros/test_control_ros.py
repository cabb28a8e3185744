"""Runtime-control services on the introspection node, over real rclpy (no mocks)."""

from __future__ import annotations

import json
import threading
from typing import Any

import pytest

pytest.importorskip("smach.ros._api", reason="needs rclpy (the ros extra)")

from std_srvs.srv import Trigger
from test_msgs.srv import BasicTypes

import smach
from smach.control import Controller
from smach.ros import IntrospectionServer
from smach.testing import BlockingState, ScriptedState

pytestmark = [pytest.mark.ros, pytest.mark.timeout(60)]


def call(client_node: Any, kind: Any, name: str, **fields: Any) -> Any:
    """Call service ``name`` and wait for the answer (10 s at most)."""
    client = client_node.create_client(kind, name)
    try:
        assert client.wait_for_service(timeout_sec=10), f"no service {name}"
        request = kind.Request()
        for key, value in fields.items():
            setattr(request, key, value)
        done = threading.Event()
        future = client.call_async(request)
        future.add_done_callback(lambda _: done.set())
        assert done.wait(10), f"{name} did not answer"
        return future.result()
    finally:
        client_node.destroy_client(client)


def machine() -> tuple[smach.StateMachine, BlockingState]:
    sm = smach.StateMachine(outcomes=["done", "failed", "preempted"])
    sm.add("A", ScriptedState(["ok"], outcomes=["ok"]), transitions={"ok": "GRASP"})
    grasp = BlockingState(outcomes=("grasped", "missed", "preempted"))
    sm.add("GRASP", grasp, transitions={"grasped": "done", "missed": "failed"})
    return sm, grasp


def test_pause_breakpoint_step_force_and_status_over_services(ros: Any) -> None:
    sm, grasp = machine()
    ctl = Controller(sm)
    client = ros.node("operator", spin=True)
    with IntrospectionServer("ctl_test", sm, "/SM_ROOT", node=ros.node("exec")) as server:
        services = server.serve_control(ctl)
        base = services.names["pause"].rsplit("/", 1)[0]
        assert base == "/ctl_test/control"
        reply = call(
            client, BasicTypes, f"{base}/set_breakpoint", string_value="*/GRASP", bool_value=True
        )
        assert reply.bool_value and json.loads(reply.string_value)["breakpoints"] == ["*/GRASP"]
        result: list[str | None] = []
        runner = threading.Thread(target=lambda: result.append(sm.execute()), daemon=True)
        runner.start()
        assert ctl.wait_for("at_breakpoint", timeout=10)
        status = json.loads(call(client, Trigger, f"{base}/status").message)
        assert status["state"] == "at_breakpoint" and status["breakpoint"] == "/ROOT/GRASP"
        reply = call(client, Trigger, f"{base}/step")
        assert reply.success
        assert grasp.started.wait(10)
        reply = call(client, BasicTypes, f"{base}/force_outcome", string_value="dropped")
        assert (
            not reply.bool_value
            and "its outcomes: grasped, missed, preempted" in reply.string_value
        )
        reply = call(client, BasicTypes, f"{base}/force_outcome", string_value="grasped")
        assert reply.bool_value
        runner.join(10)
        assert result == ["done"]
    actions = [(r.action, r.source) for r in ctl.history]
    assert ("add_breakpoint", "ros") in actions and ("step", "ros") in actions
    assert ("force_outcome", "ros") in actions


def test_pause_resume_preempt_and_bad_requests(ros: Any) -> None:
    sm, grasp = machine()
    ctl = Controller(sm)
    client = ros.node("operator", spin=True)
    with IntrospectionServer("ctl_test2", sm, "/SM_ROOT", node=ros.node("exec")) as server:
        base = server.serve_control(ctl).names["pause"].rsplit("/", 1)[0]
        assert call(client, Trigger, f"{base}/pause").success
        result: list[str | None] = []
        runner = threading.Thread(target=lambda: result.append(sm.execute()), daemon=True)
        runner.start()
        assert ctl.wait_for("paused", timeout=10)
        assert call(client, Trigger, f"{base}/resume").success
        assert grasp.started.wait(10)
        bad = call(client, BasicTypes, f"{base}/request", string_value="not json")
        assert not bad.bool_value and "not JSON" in bad.string_value
        unknown = call(client, BasicTypes, f"{base}/request", string_value='{"action": "fly"}')
        assert not unknown.bool_value and "unknown control action 'fly'" in unknown.string_value
        assert call(client, Trigger, f"{base}/preempt").success
        runner.join(10)
        assert result == ["preempted"]
