"""A robot's skills in one rclpy context, its body in the world's (body_link), over real rclpy."""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("smach.ros.rclpy_api", reason="needs rclpy (the ros extra)")
pytest.importorskip("pyrobosim", reason="pyrobosim is not installed (the sim extra)")

from ros_context import nodes_in_own_context

import smach
from plan_bridge.robosim.skills import skill_for
from plan_bridge.robosim.world import RobosimWorld
from plan_bridge.ros.body_link import ORPHAN_S, BodyServer, RemoteBody
from plan_bridge.ros.protocol import PERFORM_DONE, interfaces
from smach.ros.rclpy_api import MultiThreadedExecutor

pytestmark = pytest.mark.ros

FETCH = Path(__file__).resolve().parents[3] / "domains" / "robosim_fetch"


@pytest.fixture
def world() -> Iterator[RobosimWorld]:
    """robosim_fetch's world served under ``/w`` by a node spun in a context of its own."""
    world = RobosimWorld(FETCH / "world.yaml", seed=0, fail_rate=0.0)
    with nodes_in_own_context("world_node") as (node,):
        server = BodyServer(node, world, prefix="w")
        executor = MultiThreadedExecutor(num_threads=4, context=node.context)
        executor.add_node(node)
        spinner = threading.Thread(target=executor.spin, daemon=True)
        spinner.start()
        try:
            yield world
        finally:
            server.destroy()
            executor.shutdown(timeout_sec=2)
            spinner.join(5)
            world.close()


@pytest.fixture
def body(world: RobosimWorld) -> Iterator[RemoteBody]:
    with nodes_in_own_context("robot_node") as (node,):
        yield RemoteBody(node, "w", server_wait_timeout=5.0)


@pytest.mark.timeout(60)
def test_a_skill_run_elsewhere_drives_the_worlds_robot_and_sees_through_it(
    world: RobosimWorld, body: RemoteBody
) -> None:
    ud = smach.UserData()
    outcome = skill_for(body, "navigate", "robot", "living_room", "charger_dock").execute(ud)
    assert outcome == "succeeded"
    assert world.spot_of(world.robot("robot")) == "charger_dock" and world.distance_m > 0.5
    seen = dict(ud.observations)
    assert seen[("at", "robot", "charger_dock")] is True
    assert isinstance(seen[("battery-level", "robot")], float)
    # Already there: PLAN says so, nothing is driven.
    driven = world.distance_m
    again = skill_for(body, "navigate", "robot", "charger_dock", "charger_dock")
    assert again.execute(smach.UserData()) == "succeeded" and world.distance_m == driven


@pytest.mark.timeout(60)
def test_a_preempt_stops_the_worlds_drive_where_the_robot_is(
    world: RobosimWorld, body: RemoteBody
) -> None:
    world.time_scale = 3.0  # slower than real time: the drive to the charger takes 10 s
    skill = skill_for(body, "navigate", "robot", "living_room", "charger_dock")
    box: dict[str, Any] = {}
    runner = threading.Thread(target=lambda: box.update(outcome=skill.execute(smach.UserData())))
    runner.start()
    time.sleep(1.5)
    skill.request_preempt()
    runner.join(10)
    # Preempted 1.5 s into a 10 s drive: stopped on the way.
    assert box["outcome"] == "preempted"
    assert world.spot_of(world.robot("robot")) != "charger_dock"
    assert 0.0 < world.distance_m < 0.9


@pytest.mark.timeout(60)
@pytest.mark.parametrize(
    ("call", "reason"),
    [
        ({"op": "fly", "robot": "robot", "action": "", "args": []}, "op 'fly' is not one of"),
        ({"op": "look", "robot": "zed", "action": "", "args": []}, "no robot 'zed'; robots: robot"),
        (
            {"op": "act", "robot": "robot", "action": "pick", "args": ["robot"]},
            "'pick' with 1 arguments is not a robosim action",
        ),
        (
            {"op": "drive", "robot": "robot", "action": "navigate", "args": ["robot", "a", "b"]},
            "no planned route None to drive",
        ),
    ],
    ids=["op", "robot", "arity", "route"],
)
def test_a_bad_body_call_is_refused_with_the_reason(
    body: RemoteBody, call: dict[str, Any], reason: str
) -> None:
    reply = body._ask(call)
    assert reply["status"] == "INVALID_ACTION" and reason in reply["message"]


@pytest.mark.timeout(60)
def test_a_call_its_robot_stopped_asking_about_is_cancelled(world: RobosimWorld) -> None:
    """A robot node that dies mid-drive stops asking: the world stops its robot."""
    world.time_scale = 3.0  # the drive takes about 10 s
    _, basic_types, _ = interfaces()
    with nodes_in_own_context("dying_robot") as (node,):
        body = RemoteBody(node, "w")
        route = body.plan("robot", "navigate", ["robot", "living_room", "charger_dock"])[0]
        request = basic_types.Request()
        request.string_value = json.dumps(
            {"op": "drive", "robot": "robot", "action": "navigate",
             "args": ["robot", "living_room", "charger_dock"], "route": route}
        )  # fmt: skip
        request.int64_value = 7
        request.float64_value = 0.1
        first = body._wait(body._client.call_async(request), 5.0)
        assert first is not None and first.int64_value != PERFORM_DONE
        time.sleep(ORPHAN_S + 1.0)  # nobody asks: the drive is cancelled
        request.float64_value = 2.0
        last = body._wait(body._client.call_async(request), 5.0)
    assert last is not None and last.int64_value == PERFORM_DONE
    assert json.loads(last.string_value)["status"] == "CANCELED"
    assert world.spot_of(world.robot("robot")) != "charger_dock"
