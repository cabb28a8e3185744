"""A planned mission across processes: the executive here, the skill server in another."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("smach.ros.rclpy_api", reason="needs rclpy (the ros extra)")

from ros_context import nodes_in_own_context

from plan_bridge.execution.executive import Executive, ReplanPolicy
from plan_bridge.pddl.task import PlanningTask, load_task
from plan_bridge.planning.planner import PlanStep, get_planner
from plan_bridge.ros import decode_result, encode_result, remote_facts, ros_skill, ros_skills
from plan_bridge.ros.protocol import action_topic
from smach.ros.dds import profile_environment

pytestmark = pytest.mark.ros

ROOT = Path(__file__).resolve().parents[3]
ROOMS = ROOT / "tests" / "plan_bridge" / "data" / "rooms"
SHORT_LEASE = ROOT / "tests" / "smach" / "ros" / "short_lease.xml"


def rooms() -> PlanningTask:
    return load_task(ROOMS / "domain.pddl", ROOMS / "problems" / "p01.pddl")


class SkillServerProcess:
    def __init__(self, *args: str) -> None:
        env = dict(os.environ, **profile_environment(SHORT_LEASE))
        self.process = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "plan_bridge.ros.skill_server",
                str(ROOMS / "domain.pddl"),
                str(ROOMS / "problems" / "p01.pddl"),
                *args,
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
            cwd=ROOT,
        )
        assert self.process.stdout is not None
        first = self.process.stdout.readline().strip()
        if first != "ready":
            self.process.kill()
            raise RuntimeError(
                f"skill server did not start: {first!r} {self.process.stderr.read()}"
            )  # type: ignore[union-attr]
        self.lines: list[str] = []
        threading.Thread(target=self._pump, daemon=True).start()

    def _pump(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            self.lines.append(line.strip())

    def wait_for_line(self, prefix: str, timeout: float = 10.0) -> bool:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if any(line.startswith(prefix) for line in self.lines):
                return True
            time.sleep(0.02)
        return False

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
        try:
            self.process.wait(5)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait(5)
        for stream in (self.process.stdout, self.process.stderr):
            if stream is not None:
                stream.close()


@pytest.fixture
def node() -> Iterator[Any]:
    with nodes_in_own_context("executive") as (executive_node,):
        yield executive_node


@pytest.fixture(scope="module")
def planner() -> Any:
    return get_planner("fast-downward")


@pytest.mark.timeout(90)
def test_planned_mission_runs_on_a_remote_skill_server(node: Any, planner: Any) -> None:
    server = SkillServerProcess("--action-time", "0.05", "--prefix", "robot")
    try:
        task = rooms()
        ex = Executive(task, ros_skills(node, task, prefix="robot"), planner)
        assert ex.execute() == "succeeded"
        assert ex.report.executed[-1] == "(drop robot1 cup office)"
        assert ex.report.actions_failed == 0
        assert "(item-at cup office)" in remote_facts(node, prefix="robot")
        assert server.wait_for_line("succeeded (drop robot1 cup office)")
    finally:
        server.stop()


@pytest.mark.timeout(90)
def test_remote_faults_trigger_replanning_until_the_goal_is_reached(
    node: Any, planner: Any
) -> None:
    server = SkillServerProcess(
        "--action-time", "0.05", "--fail-rate", "0.3", "--seed", "3", "--prefix", "faulty"
    )
    try:
        task = rooms()
        ex = Executive(
            task,
            ros_skills(node, task, prefix="faulty"),
            planner,
            policy=ReplanPolicy.named("replan-only"),
        )
        assert ex.execute() == "succeeded"
        assert ex.report.actions_failed >= 1
        assert ex.report.replans >= 1
        assert {d["decision"] for d in ex.report.decisions} == {"replan"}
        assert "(item-at cup office)" in remote_facts(node, prefix="faulty")
        assert server.wait_for_line("failed")
    finally:
        server.stop()


@pytest.mark.timeout(90)
def test_preempting_the_mission_cancels_the_remote_goal(node: Any, planner: Any) -> None:
    server = SkillServerProcess("--action-time", "5.0", "--prefix", "slow")
    try:
        task = rooms()
        ex = Executive(task, ros_skills(node, task, prefix="slow"), planner)
        box: dict[str, Any] = {}
        thread = threading.Thread(target=lambda: box.update(outcome=ex.execute()))
        thread.start()
        assert server.wait_for_line("goal (move robot1 hall kitchen)", 30)
        time.sleep(0.3)
        asked = time.monotonic()
        ex.request_preempt()
        thread.join(10)
        assert box["outcome"] == "preempted"
        assert time.monotonic() - asked < 2.0
        assert server.wait_for_line("canceled (move robot1 hall kitchen)", 5)
        # The world did not change: the cancelled move had no effect.
        assert "(at robot1 hall)" in remote_facts(node, prefix="slow")
    finally:
        server.stop()


@pytest.mark.timeout(90)
def test_service_transport_runs_the_mission_too(node: Any, planner: Any) -> None:
    # Every test has its own prefix: no endpoint of another test's server can answer.
    server = SkillServerProcess("--action-time", "0.05", "--prefix", "by_service")
    try:
        task = rooms()
        ex = Executive(
            task, ros_skills(node, task, prefix="by_service", transport="service"), planner
        )
        assert ex.execute() == "succeeded"
        assert "(item-at cup office)" in remote_facts(node, prefix="by_service")
    finally:
        server.stop()


@pytest.mark.timeout(60)
def test_a_skill_for_a_server_that_is_not_there_aborts_within_its_wait(node: Any) -> None:
    state = ros_skill(
        node,
        PlanStep("move", ("robot1", "hall", "kitchen")),
        prefix="nobody",
        server_wait_timeout=0.5,
    )
    start = time.monotonic()
    assert state.execute() == "aborted"
    assert time.monotonic() - start < 3.0


def test_result_payloads_round_trip_and_malformed_ones_are_refused() -> None:
    text = encode_result(True, [(("at", "robot1", "hall"), False)], "fine")
    assert decode_result(text) == ("succeeded", [(("at", "robot1", "hall"), False)], "fine")
    for bad in (
        "[]",
        "{}",
        '{"outcome": "maybe"}',
        '{"outcome": "aborted", "observations": [["(x)", 1]]}',
        "x" * 2_000_000,
    ):
        with pytest.raises(ValueError):
            decode_result(bad)
    assert action_topic("robot/", "switch-on") == "robot/switch_on"
