"""Operator control of a running mission: skip, replan, new goal, abort (MissionControl)."""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any

import pytest

import smach
from plan_bridge.errors import FactError
from plan_bridge.execution.control import (
    MissionControl,
    MissionControlError,
    parse_goal,
    task_with_goal,
)
from plan_bridge.execution.executive import Executive
from plan_bridge.execution.simulation import SimulatedWorld, SymbolicSkill
from plan_bridge.pddl.task import PlanningTask, load_task
from plan_bridge.planning.planner import PlanStep, get_planner
from plan_bridge.skills.registry import SkillRegistry
from smach.control import Controller

ROOMS = Path(__file__).parents[1] / "data" / "rooms"

pytestmark = pytest.mark.timeout(120)


def rooms() -> PlanningTask:
    return load_task(ROOMS / "domain.pddl", ROOMS / "problems" / "p01.pddl")


@pytest.fixture(scope="module")
def planner():  # type: ignore[no-untyped-def]
    return get_planner("fast-downward")


class HeldSkill(smach.State):
    """The symbolic skill, but the first run of ``action`` waits until released or preempted."""

    def __init__(self, world: SimulatedWorld, step: PlanStep, gate: Gate) -> None:
        super().__init__(
            outcomes=["succeeded", "aborted", "preempted"], output_keys=["observations"]
        )
        self.inner = SymbolicSkill(world, step)
        self.step = step
        self.gate = gate

    def request_preempt(self) -> None:
        super().request_preempt()
        with self.gate.cond:
            self.gate.cond.notify_all()

    def execute(self, ud: smach.UserData) -> str:
        if self.step.action == self.gate.action and not self.gate.used:
            self.gate.used = True
            with self.gate.cond:
                self.gate.running = self
                self.gate.cond.notify_all()
                while not self.gate.released and not self.preempt_requested():
                    self.gate.cond.wait(10)
                self.gate.running = None
            if self.preempt_requested():
                self.service_preempt()
                return "preempted"
        return str(self.inner.execute(ud))


class Gate:
    def __init__(self, action: str) -> None:
        self.action = action
        self.used = False
        self.released = False
        self.running: HeldSkill | None = None
        self.cond = threading.Condition()

    def wait_running(self, timeout: float = 30) -> None:
        with self.cond:
            assert self.cond.wait_for(lambda: self.running is not None, timeout)


def mission(planner: Any, action: str = "pick") -> tuple[Executive, SimulatedWorld, Gate]:
    task = rooms()
    world = SimulatedWorld(task, seed=0, fail_rate=0.0)
    gate = Gate(action)
    skills = SkillRegistry(fallback=lambda step: HeldSkill(world, step, gate))
    return Executive(task, skills, planner), world, gate


def run_in_thread(executive: Executive) -> tuple[threading.Thread, list[str | None]]:
    result: list[str | None] = []
    thread = threading.Thread(target=lambda: result.append(executive.execute()), daemon=True)
    thread.start()
    return thread, result


def finish(thread: threading.Thread, result: list[str | None]) -> str | None:
    thread.join(60)
    assert not thread.is_alive()
    return result[0]


def test_skip_with_effects_marks_the_step_done_and_the_mission_goes_on(planner: Any) -> None:
    ex, world, gate = mission(planner)
    control = MissionControl(ex)
    thread, result = run_in_thread(ex)
    gate.wait_running()
    assert gate.running is not None
    world.perform(gate.running.step)  # a person did the pick by hand
    request = control.skip(apply_effects=True, source="cli")
    assert request.kind == "skip" and "with its effects" in request.reason
    assert finish(thread, result) == "succeeded"
    report = ex.report
    assert "(pick robot1 cup kitchen)" in report.executed
    assert report.replans == 0
    assert any(d["decision"] == "operator" for d in report.decisions)
    assert ("item-at", "cup", "office") in world.facts


def test_skip_without_effects_leaves_the_belief_and_recovery_takes_over(planner: Any) -> None:
    ex, world, gate = mission(planner)
    control = MissionControl(ex)
    thread, result = run_in_thread(ex)
    gate.wait_running()
    control.skip(apply_effects=False)
    assert finish(thread, result) == "succeeded"
    # The pick did not happen in the belief: a later step was invalid, and the
    # mission recovered (the cup was picked after all).
    assert ("item-at", "cup", "office") in world.facts
    decisions = {d["decision"] for d in ex.report.decisions}
    assert decisions & {"repair", "replan"}, decisions
    assert ex.report.actions_failed >= 1  # the drop was found invalid


def test_replan_now_stops_the_plan_in_force_and_plans_from_the_belief(planner: Any) -> None:
    ex, _, gate = mission(planner)
    control = MissionControl(ex)
    thread, result = run_in_thread(ex)
    gate.wait_running()
    control.replan(source="viewer")
    assert finish(thread, result) == "succeeded"
    assert ex.report.replans == 1
    reasons = [d["reason"] for d in ex.report.decisions if d["decision"] == "operator"]
    assert reasons == ["operator (viewer) asked for a replan"]


def test_change_goal_plans_to_the_new_goal_from_the_current_belief(planner: Any) -> None:
    ex, world, gate = mission(planner)
    control = MissionControl(ex)
    thread, result = run_in_thread(ex)
    gate.wait_running()
    request = control.change_goal("(at robot1 office)")
    assert request.task is not None
    assert finish(thread, result) == "succeeded"
    assert ("at", "robot1", "office") in world.facts
    assert ("item-at", "cup", "office") not in world.facts  # the old goal was dropped
    assert ex.report.goal_reached


def test_abort_ends_the_mission_cleanly(planner: Any) -> None:
    ex, _, gate = mission(planner)
    control = MissionControl(ex)
    thread, result = run_in_thread(ex)
    gate.wait_running()
    control.abort("battery low", source="ros")
    with pytest.raises(MissionControlError, match="abort is already pending"):
        control.replan()
    assert finish(thread, result) == "aborted"
    assert ex.report.explanation == "aborted by the operator (ros): battery low"
    assert not ex.preempt_requested()


def test_requests_are_recorded_by_the_trees_controller(planner: Any) -> None:
    ex, _, gate = mission(planner)
    ctl = Controller(ex)
    control = MissionControl(ex)
    thread, result = run_in_thread(ex)
    gate.wait_running()
    control.abort()
    assert finish(thread, result) == "aborted"
    record = ctl.history[-1]
    assert record.action == "abort" and record.source == "api" and record.path == ex.path


def test_requests_on_a_mission_that_is_not_running_are_refused(planner: Any) -> None:
    ex, _, _ = mission(planner)
    control = MissionControl(ex)
    for call in (control.replan, control.abort, lambda: control.skip(apply_effects=True)):
        with pytest.raises(MissionControlError, match="not running"):
            call()
    with pytest.raises(MissionControlError, match="already has a MissionControl"):
        MissionControl(ex)
    control.close()
    assert ex.operator is None


def test_a_bad_goal_is_refused_with_what_is_allowed(planner: Any) -> None:
    task = rooms()
    with pytest.raises(FactError, match="unknown predicate 'at-robot'"):
        task_with_goal(task, parse_goal("(at-robot robot1 office)"))
    with pytest.raises(FactError, match="unknown object 'garage'"):
        task_with_goal(task, parse_goal("(at robot1 garage)"))
    with pytest.raises(FactError, match="at least one atom"):
        task_with_goal(task, [])
    with pytest.raises(FactError, match="expected atoms in parentheses"):
        parse_goal("at robot1 office")
    with pytest.raises(FactError, match="unbalanced"):
        parse_goal("(at robot1 office")


def test_task_with_goal_rewrites_the_goal_of_the_problem_text() -> None:
    task = task_with_goal(rooms(), [("at", "robot1", "office"), ("free", "robot1")])
    assert task.goal_facts == (("at", "robot1", "office"), ("free", "robot1"))
    assert task.problem_text is not None
    assert "(:goal (and (at robot1 office) (free robot1)))" in task.problem_text
    assert "item-at cup office" not in task.problem_text.split(":goal")[1]
