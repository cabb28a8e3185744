"""A step of a later plan keeps its own planned times: the same action planned again
(after a replan, at other times) reported the times of the plan that grounded it
first (``ActionModel.ground`` caches by action and arguments, and steps compare
without their times), so `run` printed, and the timeline recorded, stale times."""

from __future__ import annotations

from pathlib import Path

import pytest

import smach
from plan_bridge.belief import Belief
from plan_bridge.execution.compile import compile_plan
from plan_bridge.execution.semantics import ActionModel
from plan_bridge.execution.temporal import TimedStepState
from plan_bridge.pddl.task import load_task
from plan_bridge.planning.planner import PlanStep
from plan_bridge.skills.registry import SkillRegistry

DATA = Path(__file__).resolve().parents[1] / "data" / "temporal"

pytestmark = pytest.mark.timeout(60)


class Done(smach.State):
    def __init__(self) -> None:
        super().__init__(["succeeded", "aborted", "preempted"])

    def execute(self, ud: smach.UserData) -> str:
        return "succeeded"


def test_the_same_action_grounded_again_at_other_times_keeps_the_new_times() -> None:
    model = ActionModel(load_task(DATA / "domain.pddl", DATA / "problem.pddl"))
    first = model.ground(PlanStep("undock", ("scout", "yard"), 5.0, 1.0))
    again = model.ground(PlanStep("undock", ("scout", "yard"), 0.0, 2.0))
    assert (first.step.start, first.step.duration) == (5.0, 1.0)
    assert (again.step.start, again.step.duration) == (0.0, 2.0)
    assert model.ground(PlanStep("undock", ("scout", "yard"), 5.0, 1.0)) is first  # cached


def test_a_replanned_temporal_step_reports_the_times_of_its_own_plan() -> None:
    task = load_task(DATA / "domain.pddl", DATA / "problem.pddl")
    model = ActionModel(task)
    belief = Belief(task.initial_facts, model.initial_values())
    skills = SkillRegistry()
    skills.fallback = lambda step: Done()
    compile_plan([PlanStep("undock", ("scout", "yard"), 7.0, 1.0)], skills, model, belief)
    later = compile_plan([PlanStep("undock", ("scout", "yard"), 0.0, 1.0)], skills, model, belief)
    (state,) = later.step_states
    assert isinstance(state, TimedStepState)
    assert (state.timing.planned_start, state.timing.planned_duration) == (0.0, 1.0)
