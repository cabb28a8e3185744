"""The knowledge base's ROS 2 services over real rclpy (PlanSys2's problem expert shape)."""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("smach.ros.rclpy_api", reason="needs rclpy (the ros extra)")

from ros_context import call_text_service
from std_msgs.msg import String
from std_srvs.srv import Trigger
from test_msgs.srv import BasicTypes

import smach
from plan_bridge.execution.executive import Executive
from plan_bridge.execution.simulation import SimulatedWorld, SymbolicSkill
from plan_bridge.missions.mission import MissionSetup, load_target
from plan_bridge.missions.runner import MissionOptions, prepare_mission
from plan_bridge.pddl.knowledge import KnowledgeBase
from plan_bridge.pddl.task import load_task, load_task_from_text
from plan_bridge.planning.planner import PlanStep, get_planner
from plan_bridge.ros import remote_facts
from plan_bridge.ros.connection import RobotConnection
from plan_bridge.ros.knowledge_services import KnowledgeServices
from plan_bridge.skills.registry import SkillRegistry
from smach.ros.executor import SmachExecutor
from smach.ros.rclpy_api import DurabilityPolicy, QoSProfile, ReliabilityPolicy, rclpy

ROOMS = Path(__file__).parents[1] / "data" / "rooms"

pytestmark = [pytest.mark.ros, pytest.mark.timeout(120)]

HOUSE = """\
; A robot with a battery in a house of rooms.
(define (domain house)
  (:requirements :strips :typing :numeric-fluents)
  (:types robot room)
  (:predicates (robot_at ?r - robot ?x - room) (connected ?a ?b - room))
  (:functions (battery ?r - robot))
  (:action move
    :parameters (?r - robot ?a ?b - room)
    :precondition (and (robot_at ?r ?a) (connected ?a ?b) (> (battery ?r) 5))
    :effect (and (robot_at ?r ?b) (not (robot_at ?r ?a)) (decrease (battery ?r) 5))))
"""


@pytest.fixture
def nodes() -> Iterator[tuple[Any, Any]]:
    """The mission's node and an operator's node (another context, as another process)."""
    mission_context, operator_context = rclpy.Context(), rclpy.Context()
    rclpy.init(context=mission_context)
    rclpy.init(context=operator_context)
    mission = rclpy.create_node("mission", context=mission_context)
    operator = rclpy.create_node("operator", context=operator_context)
    try:
        yield mission, operator
    finally:
        for context, node in ((mission_context, mission), (operator_context, operator)):
            helper = SmachExecutor._instances.get(id(context))
            if helper is not None:
                helper.shutdown()
            node.destroy_node()
            rclpy.shutdown(context=context)


class Client:
    """Calls the knowledge services from the operator's node."""

    def __init__(self, node: Any, base: str) -> None:
        self.node, self.base = node, base
        self.executor = rclpy.executors.SingleThreadedExecutor(context=node.context)
        self.executor.add_node(node)

    def __call__(self, service: str, text: str = "", flag: bool = False) -> tuple[bool, str]:
        kind = Trigger if service.startswith(("get_", "clear_")) else BasicTypes
        return call_text_service(
            self.node,
            f"{self.base}/{service}",
            kind,
            text,
            flag,
            timeout=10,
            wait=lambda future: self.executor.spin_until_future_complete(future, timeout_sec=10),
        )

    def close(self) -> None:
        self.executor.remove_node(self.node)
        self.executor.shutdown()


def test_every_service_changes_or_reads_the_knowledge_base(nodes: tuple[Any, Any]) -> None:
    mission, operator = nodes
    kb = KnowledgeBase.from_text(HOUSE, name="tour")
    services = KnowledgeServices(mission, kb)
    assert services.names["add_problem_goal"] == "/knowledge/add_problem_goal"
    notes: list[dict[str, Any]] = []
    qos = QoSProfile(
        depth=10,
        reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.TRANSIENT_LOCAL,
    )
    operator.create_subscription(
        String, "/knowledge/update_notify", lambda m: notes.append(json.loads(m.data)), qos
    )
    call = Client(operator, "/knowledge")
    try:
        assert call("add_problem_instance", "leia robot") == (
            True,
            "instance leia - robot (version 1)",
        )
        assert call("add_problem_instance", "leia - robot") == (
            True,
            "nothing changed: instance leia - robot",
        )
        for room in ("kitchen", "bathroom"):
            assert call("add_problem_instance", f"{room} room")[0]
        ok, text = call("add_problem_instance", "r2d2 droid")
        assert not ok and "unknown type 'droid'" in text and "types of domain house" in text
        ok, text = call(
            "add_problem_predicate", "(robot_at leia kitchen) (connected kitchen bathroom)"
        )
        assert ok and text.startswith("added: (robot_at leia kitchen) (connected kitchen bathroom)")
        ok, text = call("add_problem_predicate", "(robot_at leia garage)")
        assert not ok and "unknown object 'garage'" in text
        assert call("add_problem_function", "(= (battery leia) 80)")[0]
        ok, text = call("add_problem_function", "(= (battery leia) full)")
        assert not ok and "'full' is not a number" in text
        assert call("set_problem_goal", "(and (robot_at leia bathroom))") == (
            True,
            "goal (and (robot_at leia bathroom)) (version 6)",
        )
        assert call("get_problem_instances") == (
            True,
            json.dumps({"leia": "robot", "kitchen": "room", "bathroom": "room"}),
        )
        predicates = json.loads(call("get_problem_predicates")[1])
        assert predicates == ["(connected kitchen bathroom)", "(robot_at leia kitchen)"]
        assert json.loads(call("get_problem_functions")[1]) == [["(battery leia)", 80.0]]
        assert json.loads(call("get_problem_goal")[1]) == ["(robot_at leia bathroom)"]
        ok, pddl = call("get_problem")
        assert ok and pddl == kb.problem_pddl()
        task = load_task_from_text(HOUSE, pddl)  # what the service gives is PDDL UP reads
        assert task.goal_facts == (("robot_at", "leia", "bathroom"),)
        # Removing: the goal's atoms, a value, a fact, an instance (refused while used).
        assert call("add_problem_goal", "(robot_at leia kitchen)")[0]
        assert call("remove_problem_goal", "(robot_at leia kitchen)")[0]
        assert kb.goal == (("robot_at", "leia", "bathroom"),)
        assert call("remove_problem_function", "(battery leia)")[0]
        assert kb.values == {}
        ok, text = call("remove_problem_instance", "kitchen")
        assert not ok and "instance 'kitchen' is used by 2 fact(s)" in text
        assert call("remove_problem_instance", "kitchen", flag=True)[0]  # cascade
        assert kb.facts == frozenset()
        assert call("remove_problem_goal", "") == (True, "goal (and) (version 11)")
        assert call("clear_problem_knowledge") == (True, "the problem is empty (version 12)")
        assert kb.instances == {}
        deadline = time.monotonic() + 10
        while len(notes) < 12 and time.monotonic() < deadline:
            call.executor.spin_once(timeout_sec=0.1)
        assert notes[0] == {
            "version": 1,
            "kind": "instance",
            "change": "instance leia - robot added",
            "source": "ros",
        }
        assert [n["version"] for n in notes] == list(range(1, 13))
        assert notes[-1] == {
            "version": 12,
            "kind": "problem",
            "change": "problem cleared",
            "source": "ros",
        }
    finally:
        call.close()
        services.close()


class WaitAtPick(smach.State):
    """The symbolic skill; the first pick waits until preempted (30 s at most)."""

    def __init__(self, world: SimulatedWorld, step: PlanStep, started: threading.Event) -> None:
        super().__init__(
            outcomes=["succeeded", "aborted", "preempted"], output_keys=["observations"]
        )
        self.inner, self.step, self.started = SymbolicSkill(world, step), step, started

    def execute(self, ud: smach.UserData) -> str:
        if self.step.action == "pick" and not self.started.is_set():
            self.started.set()
            if self.preempt_event.wait(30):
                self.service_preempt()
                return "preempted"
        return str(self.inner.execute(ud))


def test_a_goal_added_over_ros_while_the_mission_runs_is_planned_for(
    nodes: tuple[Any, Any],
) -> None:
    mission, operator = nodes
    task = load_task(ROOMS / "domain.pddl", ROOMS / "problems" / "p01.pddl")
    world = SimulatedWorld(task, seed=0, fail_rate=0.0)
    started = threading.Event()
    kb = KnowledgeBase.from_task(task)
    executive = Executive(
        task,
        SkillRegistry(fallback=lambda step: WaitAtPick(world, step, started)),
        get_planner("fast-downward"),
        world=world,
        knowledge=kb,
    )
    services = KnowledgeServices(mission, kb, name="robot1/knowledge")
    call = Client(operator, "/robot1/knowledge")
    result: list[str | None] = []
    runner = threading.Thread(target=lambda: result.append(executive.execute()), daemon=True)
    try:
        runner.start()
        assert started.wait(60)
        ok, text = call("add_problem_goal", "(at robot1 garage)")
        assert not ok and "unknown object 'garage'" in text
        assert call("add_problem_goal", "(at robot1 kitchen)")[0]
        runner.join(60)
        assert result == ["succeeded"]
        assert {("item-at", "cup", "office"), ("at", "robot1", "kitchen")} <= world.facts
        reasons = [d["reason"] for d in executive.report.decisions if d["decision"] == "knowledge"]
        assert reasons == [
            "the knowledge base changed: goal atoms added: (at robot1 kitchen) (ros)"
        ]
        assert json.loads(call("get_problem_goal")[1]) == [
            "(item-at cup office)",
            "(at robot1 kitchen)",
        ]
    finally:
        runner.join(30)
        call.close()
        services.close()


def test_the_robot_connection_serves_the_knowledge_base_of_a_mission_across_processes() -> None:
    target = load_target(ROOMS, "p01")
    robot = RobotConnection(target, fail_rate=0.0, time_scale=0.0, echo_robot=False)
    context = rclpy.Context()
    rclpy.init(context=context)
    operator = rclpy.create_node("operator", context=context)
    call = Client(operator, f"/{robot.prefix}/knowledge")
    try:
        robot.open()
        setup = MissionSetup(skills=robot.skills(), world=robot.world(), concurrent=False)
        run = prepare_mission(target, MissionOptions(planner="fast-downward"), setup=setup)
        kb = run.attach_knowledge()
        robot.serve_knowledge(kb, name=f"{robot.prefix}/knowledge")
        assert call("set_problem_goal", "(and (at robot1 kitchen))")[0]
        assert run.run() == "succeeded"
        assert run.executive.report.executed == ["(move robot1 hall kitchen)"]
        assert "(at robot1 kitchen)" in remote_facts(robot.node, prefix=robot.prefix)
    finally:
        call.close()
        robot.close()
        operator.destroy_node()
        rclpy.shutdown(context=context)
