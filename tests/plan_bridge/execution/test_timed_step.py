"""One step of a temporal plan reaches its dispatcher through the hooks it is given."""

from __future__ import annotations

from pathlib import Path

import pytest

import smach
from plan_bridge.belief import Belief
from plan_bridge.execution.semantics import ActionModel
from plan_bridge.execution.timed_step import StepHooks, TimedStepState
from plan_bridge.pddl.task import PlanningTask, load_task
from plan_bridge.planning.planner import PlanStep

DATA = Path(__file__).resolve().parents[1] / "data" / "temporal"

pytestmark = pytest.mark.timeout(60)


@pytest.fixture(scope="module")
def task() -> PlanningTask:
    return load_task(DATA / "domain.pddl", DATA / "problem.pddl")


class Ends(smach.State):
    """A skill that ends at once with ``outcome``."""

    def __init__(self, outcome: str) -> None:
        super().__init__(["succeeded", "aborted", "preempted"])
        self.outcome = outcome

    def execute(self, ud: smach.UserData) -> str:
        return self.outcome


def step_with(
    task: PlanningTask, step: PlanStep, outcome: str, calls: list[str]
) -> tuple[TimedStepState, Belief]:
    model = ActionModel(task)
    belief = Belief(task.initial_facts, model.initial_values())
    ticks = iter([10.0, 11.5])
    hooks = StepHooks(
        elapsed=lambda: next(ticks),
        time_scale=0.5,
        before_end=lambda: calls.append("before end"),
        on_begun=lambda: calls.append("begun"),
        on_failed=lambda failed: calls.append(f"failed {failed}"),
    )
    state = TimedStepState(1, model.ground(step), belief, None)
    state.bind(hooks)
    state.add("SKILL", Ends(outcome))
    return state, belief


def test_a_step_given_hooks_tells_its_start_point_and_holds_its_end_on_them(
    task: PlanningTask,
) -> None:
    calls: list[str] = []
    state, belief = step_with(
        task, PlanStep("undock", ("scout", "yard"), 0.0, 1.0), "succeeded", calls
    )
    assert state.execute() == "succeeded"
    assert calls == ["begun", "before end"]
    assert (state.timing.actual_start, state.timing.actual_end) == (10.0, 11.5)
    assert ("docked", "scout") not in belief  # the at-end effect, after the held end


def test_a_failed_step_tells_its_hooks_and_takes_back_its_start(task: PlanningTask) -> None:
    calls: list[str] = []
    state, belief = step_with(
        task, PlanStep("hold-light", ("lamp", "yard"), 0.0, 4.0), "aborted", calls
    )
    assert state.execute() == "aborted"
    assert calls == ["begun", "before end", "failed aborted"]
    assert ("light-on", "yard") not in belief  # its at-start effect undone


def test_a_step_without_hooks_runs_on_its_own(task: PlanningTask) -> None:
    model = ActionModel(task)
    belief = Belief(task.initial_facts, model.initial_values())
    state = TimedStepState(1, model.ground(PlanStep("undock", ("scout", "yard"))), belief, None)
    state.add("SKILL", Ends("succeeded"))
    assert state.execute() == "succeeded"
    assert state.timing.actual_start is not None and state.timing.actual_end is not None
    assert state.timing.actual_end >= state.timing.actual_start
