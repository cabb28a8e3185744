"""The skill server in process: its ``perform`` service (repeats, lost replies,
timeouts) and its heartbeat."""

from __future__ import annotations

import secrets
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("smach.ros.rclpy_api", reason="needs rclpy (the ros extra)")

from plan_bridge.execution.simulation import SimulatedWorld
from plan_bridge.pddl.task import load_task
from plan_bridge.planning.planner import PlanStep
from plan_bridge.ros import ros_skill
from plan_bridge.ros.protocol import HEARTBEAT_TOPIC
from plan_bridge.ros.skill_server import SkillServer
from smach.ros.executor import SmachExecutor, subscription_events, wait_for_callbacks
from smach.ros.rclpy_api import MultiThreadedExecutor, StringMsg, rclpy
from waiting import wait_until

pytestmark = pytest.mark.ros

ROOMS = Path(__file__).resolve().parents[1] / "data" / "rooms"
MOVE = PlanStep("move", ("robot1", "hall", "kitchen"))


class ForgetfulServer(SkillServer):
    """Answers its first ``lose`` perform calls too late: the client has given up on them."""

    def __init__(self, *args: Any, lose: int, late: float, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.lose = lose
        self.late = late
        self.calls = 0

    def _on_perform(self, request: Any, response: Any) -> Any:
        self.calls += 1
        answer = super()._on_perform(request, response)
        if self.calls <= self.lose:
            time.sleep(self.late)
        return answer


class Robot:
    """A skill server node spun in this process, and the client node beside it."""

    def __init__(self, prefix: str, **options: Any) -> None:
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.client = rclpy.create_node("executive", context=self.context)
        self.server_node = rclpy.create_node("robot", context=self.context)
        self.world = SimulatedWorld(
            load_task(ROOMS / "domain.pddl", ROOMS / "problems" / "p01.pddl"), seed=0
        )
        self.lines: list[str] = []
        server_type = ForgetfulServer if "lose" in options else SkillServer
        self.server = server_type(
            self.server_node, self.world, prefix=prefix, log=self.lines.append, **options
        )
        self.executor = MultiThreadedExecutor(num_threads=4, context=self.context)
        self.executor.add_node(self.server_node)
        self.stop = threading.Event()
        self.spinning = threading.Thread(target=self._spin, daemon=True)
        self.spinning.start()

    def _spin(self) -> None:
        while self.context.ok() and not self.stop.is_set():
            self.executor.spin_once(timeout_sec=0.05)

    def close(self) -> None:
        # Nothing is destroyed under a running callback: stop spinning, let the
        # callbacks end, then destroy (else InvalidHandle in an executor thread).
        helper = SmachExecutor._instances.get(id(self.context))
        if helper is not None:
            helper.shutdown()
        self.stop.set()
        self.spinning.join(5)
        self.server.halt_all()
        assert wait_for_callbacks(self.executor, 10)
        self.executor.shutdown(timeout_sec=0)
        self.server.destroy()
        self.client.destroy_node()
        self.server_node.destroy_node()
        rclpy.shutdown(context=self.context)


@pytest.fixture
def robot(request: pytest.FixtureRequest) -> Iterator[Robot]:
    options = getattr(request, "param", {})
    # Every test has its own prefix: no endpoint of another test's server can answer.
    robot = Robot(f"perform_{secrets.token_hex(4)}", **options)
    try:
        yield robot
    finally:
        robot.close()


@pytest.mark.timeout(60)
@pytest.mark.parametrize("robot", [{"action_time": 0.05, "lose": 1, "late": 3.5}], indirect=True)
def test_a_lost_perform_reply_is_asked_for_again_and_the_action_runs_once(robot: Robot) -> None:
    state = ros_skill(robot.client, MOVE, prefix=robot.server.prefix, transport="service")
    assert state.execute() == "succeeded"
    assert robot.server.calls >= 2
    assert robot.lines.count(f"goal {MOVE}") == 1
    assert robot.world.actions_run == 1
    assert ("at", "robot1", "kitchen") in robot.world.facts


@pytest.mark.timeout(60)
@pytest.mark.parametrize("robot", [{"action_time": 1.6}], indirect=True)
def test_a_long_action_is_polled_until_done_and_a_retry_performs_it_again(robot: Robot) -> None:
    state = ros_skill(robot.client, MOVE, prefix=robot.server.prefix, transport="service")
    assert state.execute() == "succeeded"
    # The same state executed again (a skill retry) is a new request: the move runs again.
    back = ros_skill(
        robot.client,
        PlanStep("move", ("robot1", "kitchen", "hall")),
        prefix=robot.server.prefix,
        transport="service",
    )
    assert back.execute() == "succeeded"
    assert state.execute() == "succeeded"
    assert robot.lines.count(f"goal {MOVE}") == 2
    assert robot.world.actions_run == 3


@pytest.mark.timeout(60)
@pytest.mark.parametrize("robot", [{"action_time": 5.0}], indirect=True)
def test_a_perform_past_its_exec_timeout_aborts_while_the_robot_finishes(robot: Robot) -> None:
    state = ros_skill(
        robot.client, MOVE, prefix=robot.server.prefix, transport="service", exec_timeout=1.0
    )
    start = time.monotonic()
    assert state.execute() == "aborted"
    assert time.monotonic() - start < 4.0
    # The robot goes on with the move (no cancel); when it ends is its own business.
    # Its line comes from its executor's thread, maybe after the client gave up.
    assert wait_until(lambda: robot.lines[:1] == [f"goal {MOVE}"]), robot.lines
    assert not any(line.startswith(("canceled", "failed")) for line in robot.lines)


@pytest.mark.timeout(60)
@pytest.mark.parametrize("robot", [{"action_time": 0.05}], indirect=True)
def test_a_perform_of_an_unknown_action_aborts_and_runs_nothing(robot: Robot) -> None:
    state = ros_skill(
        robot.client, PlanStep("fly", ("robot1",)), prefix=robot.server.prefix, transport="service"
    )
    assert state.execute() == "aborted"
    assert robot.world.actions_run == 0


@pytest.mark.timeout(60)
@pytest.mark.parametrize("robot", [{"action_time": 0.05}], indirect=True)
def test_the_robot_publishes_a_counting_heartbeat_while_it_is_spun(robot: Robot) -> None:
    beats: list[int] = []
    helper = SmachExecutor.for_node(robot.client)
    topic = f"/{robot.server.prefix}/{HEARTBEAT_TOPIC}"
    helper.node.create_subscription(
        StringMsg,
        topic,
        lambda message: beats.append(int(message.data)),
        10,
        callback_group=helper.callback_group,
        event_callbacks=subscription_events(topic),
    )
    deadline = time.monotonic() + 20
    while len(beats) < 3 and time.monotonic() < deadline:
        time.sleep(0.05)
    assert len(beats) >= 3
    assert beats == sorted(beats) and len(set(beats)) == len(beats)
