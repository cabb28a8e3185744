"""The viewer following a remote executive: RosSource over IntrospectionServer topics."""

from __future__ import annotations

import http.client
import json
import os
import re
import signal
import subprocess
import sys
import threading
from typing import Any

import pytest

pytest.importorskip("smach.ros._api", reason="needs rclpy (the ros extra)")

from ros_helpers import wait_for

import smach
from smach.introspection import serve
from smach.ros import IntrospectionServer
from smach.ros.viewer_source import RosSource
from smach.testing import BlockingState

pytestmark = pytest.mark.ros

EXPECTED = {
    "/SM_ROOT",
    "/SM_ROOT/FIRST",
    "/SM_ROOT/SUB",
    "/SM_ROOT/SUB/WAIT",
    "/SM_ROOT/PAR",
    "/SM_ROOT/PAR/LEFT",
    "/SM_ROOT/PAR/RIGHT",
}


def mission() -> tuple[smach.StateMachine, dict[str, BlockingState]]:
    """FIRST -> SUB (WAIT) -> PAR (LEFT || RIGHT); WAIT, LEFT and RIGHT held."""
    hold = {name: BlockingState(outcomes=["done", "preempted"], timeout=20) for name in
            ("wait", "left", "right")}  # fmt: skip
    sm = smach.StateMachine(outcomes=["finished", "failed"])
    sm.userdata.count = 0

    def first(ud: Any) -> str:
        ud.count = 42
        return "ok"

    with sm:
        smach.StateMachine.add(
            "FIRST",
            smach.CBState(first, outcomes=["ok"], output_keys=["count"]),
            transitions={"ok": "SUB"},
        )
        sub = smach.StateMachine(outcomes=["done", "preempted"])
        with sub:
            smach.StateMachine.add("WAIT", hold["wait"])
        smach.StateMachine.add("SUB", sub, transitions={"done": "PAR", "preempted": "failed"})
        par = smach.Concurrence(
            outcomes=["ok", "bad"],
            default_outcome="bad",
            outcome_map={"ok": {"LEFT": "done", "RIGHT": "done"}},
        )
        with par:
            smach.Concurrence.add("LEFT", hold["left"])
            smach.Concurrence.add("RIGHT", hold["right"])
        smach.StateMachine.add("PAR", par, transitions={"ok": "finished", "bad": "failed"})
    return sm, hold


def get_json(viewer: Any, path: str) -> Any:
    conn = http.client.HTTPConnection(viewer.host, viewer.port, timeout=10)
    try:
        conn.request("GET", path)
        response = conn.getresponse()
        assert response.status == 200
        return json.loads(response.read())
    finally:
        conn.close()


def active(viewer: Any) -> set[str]:
    return set(get_json(viewer, "/api/view")["active"])


@pytest.mark.timeout(60)
def test_viewer_follows_a_remote_executive(ros: Any) -> None:
    sm, hold = mission()
    server = IntrospectionServer(
        "viewer_test", sm, "/SM_ROOT", node=ros.node("executive"), update_rate=0.5
    )
    thread = threading.Thread(target=sm.execute, daemon=True)
    with server:
        source = RosSource("viewer_test", node=ros.node("viewer"), timeout=15)
        with serve(source, quiet=True) as viewer:
            # The structure: every state, containers recognised, edges and outcomes kept.
            tree = viewer.structure()
            assert tree is not None
            assert {n.path for n in tree.walk()} == EXPECTED
            containers = {n.path for n in tree.walk() if n.is_container}
            assert containers == {"/SM_ROOT", "/SM_ROOT/SUB", "/SM_ROOT/PAR"}
            first = tree.find("/SM_ROOT/FIRST")
            assert first is not None and first.outcomes == ("ok",)
            assert any(e.source == "FIRST" and e.target == "SUB" for e in tree.edges)
            svg = get_conn_text(viewer, "/api/svg")
            assert set(re.findall(r'data-path="([^"]+)"', svg)) >= EXPECTED
            assert get_json(viewer, "/api/info")["live"] is True

            # The active states follow execution, through every active branch. The
            # viewer has read the source once before the run starts (on a loaded machine
            # its first read could come after, and then rightly be a resync).
            assert wait_for(lambda: viewer.pump_busy_s > 0, 10)
            thread.start()
            assert wait_for(lambda: {"/SM_ROOT/SUB", "/SM_ROOT/SUB/WAIT"} <= active(viewer), 10)
            assert wait_for(
                lambda: (
                    get_json(viewer, "/api/view")["userdata"].get("/SM_ROOT", {}).get("count") == 42
                ),
                10,
            )
            assert get_json(viewer, "/api/view")["running"] is True
            hold["wait"].release("done")
            both = {"/SM_ROOT", "/SM_ROOT/PAR", "/SM_ROOT/PAR/LEFT", "/SM_ROOT/PAR/RIGHT"}
            assert wait_for(lambda: active(viewer) == both, 10), active(viewer)
            hold["left"].release("done")
            assert wait_for(lambda: "/SM_ROOT/PAR/LEFT" not in active(viewer), 10)
            assert "/SM_ROOT/PAR/RIGHT" in active(viewer)
            hold["right"].release("done")
            thread.join(10)
            assert wait_for(lambda: not get_json(viewer, "/api/view")["running"], 10)
            view = get_json(viewer, "/api/view")
            assert view["active"] == []
            assert view["root_outcome"] == "finished"
            assert view["resyncs"] == 0  # attached before the run: nothing was skipped
            records = get_json(viewer, "/api/records")
            entered = [r["path"] for r in records if r["kind"] == "state_entered"]
            assert entered.index("/SM_ROOT/SUB/WAIT") < entered.index("/SM_ROOT/PAR/LEFT")
        assert source.live is False


def get_conn_text(viewer: Any, path: str) -> str:
    conn = http.client.HTTPConnection(viewer.host, viewer.port, timeout=10)
    try:
        conn.request("GET", path)
        return conn.getresponse().read().decode("utf-8")
    finally:
        conn.close()


@pytest.mark.timeout(60)
def test_cli_serves_a_remote_executive_and_fails_cleanly(ros: Any) -> None:
    sm, _hold = mission()
    server = IntrospectionServer("cli_test", sm, "/SM_ROOT", node=ros.node("executive"))
    env = dict(os.environ)
    with server:
        process = subprocess.Popen(
            [sys.executable, "-m", "smach.introspection", "ros", "cli_test", "--timeout", "15"],
            stderr=subprocess.PIPE,
            text=True,
            env=env,
        )
        try:
            assert process.stderr is not None
            line = process.stderr.readline()
            match = re.search(r"http://127\.0\.0\.1:(\d+)/", line)
            assert match, line
            conn = http.client.HTTPConnection("127.0.0.1", int(match[1]), timeout=10)
            conn.request("GET", "/api/info")
            info = json.loads(conn.getresponse().read())
            conn.close()
            assert info["live"] is True and "/cli_test" in info["title"]
            process.send_signal(signal.SIGINT)  # Ctrl-C: the viewer closes and exits 0
            code = process.wait(30)
            assert code == 0, f"exit {code}: {process.stderr.read()}"
        finally:
            if process.poll() is None:
                process.kill()
                process.wait(10)
            if process.stderr is not None:
                process.stderr.close()

    # No such server: one line, exit 2, no traceback.
    missing = subprocess.run(
        [sys.executable, "-m", "smach.introspection", "ros", "nobody_here", "--timeout", "1"],
        capture_output=True,
        text=True,
        timeout=30,
        env=env,
    )
    assert missing.returncode == 2
    assert "no introspection server /nobody_here" in missing.stderr
    assert "Traceback" not in missing.stderr

    # Without rclpy: the same kind of error.
    no_ros = subprocess.run(
        [
            sys.executable,
            "-c",
            "import sys; sys.modules['rclpy'] = None; "
            "from smach.introspection.cli import main; sys.exit(main(['ros', 'x']))",
        ],
        capture_output=True,
        text=True,
        timeout=30,
        env=env,
    )
    assert no_ros.returncode == 2
    assert "needs rclpy" in no_ros.stderr and "Traceback" not in no_ros.stderr


@pytest.mark.timeout(60)
def test_attaching_to_a_running_executive_resyncs(ros: Any) -> None:
    sm, hold = mission()
    server = IntrospectionServer("late_test", sm, "/SM_ROOT", node=ros.node("executive"))
    thread = threading.Thread(target=sm.execute, daemon=True)
    with server:
        thread.start()
        assert hold["wait"].started.wait(10)
        source = RosSource("late_test", node=ros.node("viewer"), timeout=15)
        try:
            with serve(source, quiet=True) as viewer:
                assert wait_for(lambda: "/SM_ROOT/SUB/WAIT" in active(viewer), 10)
                view = get_json(viewer, "/api/view")
                assert view["running"] is True and view["resyncs"] == 1
                hold["wait"].release("done")
                assert wait_for(lambda: "/SM_ROOT/PAR/RIGHT" in active(viewer), 10)
                assert "/SM_ROOT/SUB/WAIT" not in active(viewer)
                hold["left"].release("done")
                hold["right"].release("done")
                thread.join(10)
                assert wait_for(
                    lambda: get_json(viewer, "/api/view")["root_outcome"] == "finished", 10
                )
        finally:
            source.close()
