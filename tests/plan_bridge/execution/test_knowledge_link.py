"""An executive following a knowledge base: one belief, and the mission follows its
objects and goal (execution/knowledge_link.py, ``Executive.attach_knowledge``)."""

from __future__ import annotations

import threading
from collections.abc import Callable
from pathlib import Path

import pytest

import smach
from plan_bridge.execution.control import MissionControl
from plan_bridge.execution.executive import Executive
from plan_bridge.execution.simulation import SimulatedWorld, SymbolicSkill
from plan_bridge.pddl.knowledge import KnowledgeBase
from plan_bridge.pddl.task import PlanningTask, load_task
from plan_bridge.planning.planner import PlanStep, get_planner
from plan_bridge.skills.registry import SkillRegistry

ROOMS = Path(__file__).parents[1] / "data" / "rooms"

pytestmark = pytest.mark.timeout(120)


def rooms() -> PlanningTask:
    return load_task(ROOMS / "domain.pddl", ROOMS / "problems" / "p01.pddl")


class Gate:
    """Holds the first step of ``action`` until released (or preempted)."""

    def __init__(self, action: str) -> None:
        self.action = action
        self.holding = threading.Event()
        self.release = threading.Event()


class Held(smach.State):
    """``inner``, except that the first step of the gate's action waits at the gate."""

    def __init__(self, inner: Callable[[smach.UserData], str], step: PlanStep, gate: Gate) -> None:
        super().__init__(
            outcomes=["succeeded", "aborted", "preempted"], output_keys=["observations"]
        )
        self.inner, self.step, self.gate = inner, step, gate

    def request_preempt(self) -> None:
        super().request_preempt()
        self.gate.release.set()

    def execute(self, ud: smach.UserData) -> str:
        if self.step.action == self.gate.action and not self.gate.holding.is_set():
            self.gate.holding.set()
            assert self.gate.release.wait(30)
            if self.preempt_requested():
                self.service_preempt()
                return "preempted"
        return self.inner(ud)


def simulated(task: PlanningTask, gate: Gate) -> tuple[SimulatedWorld, SkillRegistry]:
    world = SimulatedWorld(task, seed=0, fail_rate=0.0)
    skills = SkillRegistry(
        fallback=lambda step: Held(
            lambda ud: str(SymbolicSkill(world, step).execute(ud)), step, gate
        )
    )
    return world, skills


def trusting(gate: Gate) -> SkillRegistry:
    """Skills that just succeed: the executive applies the actions' effects to the belief."""
    return SkillRegistry(fallback=lambda step: Held(lambda ud: "succeeded", step, gate))


def run(executive: Executive) -> tuple[threading.Thread, list[str | None]]:
    result: list[str | None] = []
    runner = threading.Thread(target=lambda: result.append(executive.execute()), daemon=True)
    runner.start()
    return runner, result


def decisions(executive: Executive, kind: str) -> list[str]:
    return [d["reason"] for d in executive.report.decisions if d["decision"] == kind]


def gated_mission() -> tuple[Gate, SimulatedWorld, KnowledgeBase, Executive]:
    """The rooms mission on a simulated world, following a knowledge base, its skills
    held at the first pick (``gate``)."""
    task = rooms()
    gate = Gate("pick")
    world, skills = simulated(task, gate)
    kb = KnowledgeBase.from_task(task)
    executive = Executive(task, skills, get_planner("fast-downward"), world=world, knowledge=kb)
    return gate, world, kb, executive


def test_the_belief_holds_the_knowledge_bases_facts() -> None:
    task = rooms()
    kb = KnowledgeBase.from_task(task)
    kb.add_fact("(lights-on hall)")
    executive = Executive(task, trusting(Gate("none")), "fast-downward", knowledge=kb)
    assert executive.knowledge is kb
    assert executive.belief.facts == kb.facts
    assert ("lights-on", "hall") in executive.belief
    kb.remove_fact("(lights-on hall)")  # through the knowledge base: into the belief
    assert ("lights-on", "hall") not in executive.belief
    executive.belief.observe([(("lights-on", "office"), True)])  # as a skill reports it
    assert ("lights-on", "office") in kb.facts
    assert kb.version == 2  # the belief's own changes are not the knowledge base's
    executive.detach_knowledge()
    executive.belief.observe([(("lights-on", "kitchen"), True)])
    assert ("lights-on", "kitchen") not in kb.facts  # it keeps a copy of its own
    assert ("lights-on", "office") in kb.facts


def test_a_goal_added_while_the_mission_runs_stops_the_plan_and_is_planned_for() -> None:
    gate, world, kb, executive = gated_mission()
    runner, result = run(executive)
    assert gate.holding.wait(60)
    kb.add_goal("(at robot1 kitchen)", source="test")
    runner.join(60)
    assert result == ["succeeded"]
    assert {("item-at", "cup", "office"), ("at", "robot1", "kitchen")} <= world.facts
    (reason,) = decisions(executive, "knowledge")
    assert reason == "the knowledge base changed: goal atoms added: (at robot1 kitchen) (test)"
    assert executive.report.replans == 1
    assert executive.task.goal_facts == (("item-at", "cup", "office"), ("at", "robot1", "kitchen"))


def test_a_fact_asserted_while_the_mission_runs_is_believed_without_a_replan() -> None:
    gate, _world, kb, executive = gated_mission()
    runner, result = run(executive)
    assert gate.holding.wait(60)
    kb.add_fact("(lights-on office)", source="operator")
    assert ("lights-on", "office") in executive.belief
    gate.release.set()
    runner.join(60)
    assert result == ["succeeded"]
    assert executive.report.replans == 0
    assert decisions(executive, "knowledge") == []


def test_an_instance_and_a_goal_naming_it_are_planned_for_mid_mission() -> None:
    task = rooms()
    gate = Gate("move")
    kb = KnowledgeBase.from_task(task)
    executive = Executive(task, trusting(gate), get_planner("fast-downward"), knowledge=kb)
    runner, result = run(executive)
    assert gate.holding.wait(60)
    kb.add_instance("mug", "item", source="perception")
    kb.add_fact("(item-at mug office)", source="perception")
    kb.add_goal("(item-at mug hall)", source="operator")
    runner.join(60)
    assert result == ["succeeded"]
    assert {("item-at", "mug", "hall"), ("item-at", "cup", "office")} <= executive.belief.facts
    assert executive.task.objects["mug"] == "item"
    # One replan per batch of news the executive took (the changes came one by one).
    reason = " | ".join(decisions(executive, "knowledge"))
    assert 1 <= executive.report.replans <= 2
    assert "instance mug - item added (perception)" in reason
    assert "goal atoms added: (item-at mug hall) (operator)" in reason
    assert "facts added" not in reason  # facts are in the belief: no news


def test_an_operators_new_goal_goes_into_the_knowledge_base() -> None:
    gate, world, kb, executive = gated_mission()
    control = MissionControl(executive)
    runner, result = run(executive)
    assert gate.holding.wait(60)
    control.change_goal("(at robot1 office)", source="cli")
    runner.join(60)
    control.close()
    assert result == ["succeeded"]
    assert kb.goal == (("at", "robot1", "office"),)
    assert ("at", "robot1", "office") in world.facts
    assert decisions(executive, "operator") == [
        "operator (cli) changed the goal to (at robot1 office)"
    ]
    assert decisions(executive, "knowledge") == []  # one decision for one change


def test_changes_before_the_run_are_the_problem_the_mission_plans_for() -> None:
    task = rooms()
    kb = KnowledgeBase.from_task(task)
    executive = Executive(task, trusting(Gate("none")), get_planner("fast-downward"), knowledge=kb)
    kb.set_goal("(and (at robot1 kitchen))", source="ros")
    assert executive.execute() == "succeeded"
    assert executive.report.decisions[0] == {
        "decision": "knowledge",
        "reason": "planning for the knowledge base's problem (goal set to "
        "(and (at robot1 kitchen)) (ros))",
        "step": "",
    }
    assert executive.report.executed == ["(move robot1 hall kitchen)"]
    assert executive.report.replans == 0
    # A knowledge base of another problem than the executive's task: followed from the start.
    other = KnowledgeBase(task)
    other.add_instance("robot1", "robot")
    executive = Executive(
        task, trusting(Gate("none")), get_planner("fast-downward"), knowledge=other
    )
    assert executive.belief.facts == frozenset()
    assert executive.execute() == "succeeded"  # the empty goal holds at once
    assert executive.task.objects == {"robot1": "robot"}
