"""The executive: planning, executing, recovering, preempting, reporting."""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any

import pytest

import smach
from plan_bridge.execution.events import ExecutiveDecision, PlanComputed, StepFinished
from plan_bridge.execution.executive import Executive, ReplanPolicy
from plan_bridge.execution.simulation import SimulatedWorld, symbolic_skills
from plan_bridge.pddl.task import PlanningTask, load_task
from plan_bridge.planning.planner import get_planner
from plan_bridge.skills.registry import SkillRegistry
from smach.testing import EventRecorder

DATA = Path(__file__).parents[1] / "data"
ROOMS = DATA / "rooms"


def rooms(problem: str = "p01.pddl") -> PlanningTask:
    return load_task(ROOMS / "domain.pddl", ROOMS / "problems" / problem)


@pytest.fixture(scope="module")
def planner():  # type: ignore[no-untyped-def]
    return get_planner("fast-downward")


def executive(task: PlanningTask, planner: Any, **kwargs: Any) -> tuple[Executive, SimulatedWorld]:
    world = SimulatedWorld(task, seed=kwargs.pop("seed", 0), fail_rate=kwargs.pop("fail_rate", 0.0))
    return Executive(task, symbolic_skills(world), planner, **kwargs), world


@pytest.mark.timeout(60)
def test_reaches_the_goal_without_faults_and_reports_numbers(planner) -> None:  # type: ignore[no-untyped-def]
    ex, world = executive(rooms(), planner)
    assert ex.execute() == "succeeded"
    report = ex.report
    assert report.goal_reached
    assert report.actions_executed == len(report.final_plan) == 5
    assert report.actions_failed == 0 and report.replans == 0
    assert report.planner_calls == 1
    assert report.executed[-1] == "(drop robot1 cup office)"
    assert ("item-at", "cup", "office") in world.facts


@pytest.mark.timeout(120)
def test_recovers_from_injected_faults_through_retry_and_replanning(planner) -> None:  # type: ignore[no-untyped-def]
    reached = 0
    decisions: set[str] = set()
    for seed in range(6):
        ex, world = executive(rooms(), planner, seed=seed, fail_rate=0.4)
        outcome = ex.execute()
        assert outcome in ("succeeded", "aborted")
        reached += ex.report.goal_reached
        decisions |= {d["decision"] for d in ex.report.decisions}
        assert ex.report.actions_failed == world.faults_injected
    assert reached >= 5
    assert "retry" in decisions


@pytest.mark.timeout(60)
def test_no_replan_policy_fails_on_the_first_fault(planner) -> None:  # type: ignore[no-untyped-def]
    ex, _ = executive(
        rooms(), planner, seed=1, fail_rate=1.0, policy=ReplanPolicy.named("no-replan")
    )
    assert ex.execute() == "aborted"
    assert ex.report.actions_executed == 1
    assert "no further recovery" in ex.report.explanation


@pytest.mark.timeout(60)
@pytest.mark.parametrize("reuse", [True, False])
def test_replan_budget_bounds_the_planner_calls(planner, reuse: bool) -> None:  # type: ignore[no-untyped-def]
    policy = ReplanPolicy(max_step_retries=0, max_replans=2, reuse_plans=reuse)
    ex, _ = executive(rooms(), planner, fail_rate=1.0, policy=policy)
    assert ex.execute() == "aborted"
    # Every failure leaves the state as it was: replans from it reuse the first plan.
    assert ex.report.planner_calls == (1 if reuse else 3)
    assert ex.report.plans_reused == (2 if reuse else 0)
    assert ex.report.replans == 2
    assert "budget exhausted" in ex.report.explanation


@pytest.mark.timeout(60)
def test_unsolvable_goal_aborts_with_the_planners_explanation(planner) -> None:  # type: ignore[no-untyped-def]
    task = load_task(ROOMS / "domain.pddl", DATA / "unsolvable.pddl")
    ex, _ = executive(task, planner)
    assert ex.execute() == "aborted"
    assert ex.report.explanation.startswith("no plan (unsolvable)")
    assert "item-at" in ex.report.explanation


@pytest.mark.timeout(60)
def test_goal_that_already_holds_needs_no_plan(planner) -> None:  # type: ignore[no-untyped-def]
    task = rooms()
    task = task.with_initial_state([*task.initial_facts, ("item-at", "cup", "office")])
    ex, _ = executive(task, planner)
    assert ex.execute() == "succeeded"
    assert ex.report.planner_calls == 0
    assert ex.report.decisions[0]["reason"] == "the goal already holds"


@pytest.mark.timeout(60)
def test_an_observation_that_invalidates_the_plan_triggers_recovery(planner) -> None:  # type: ignore[no-untyped-def]
    task = rooms()
    world = SimulatedWorld(task)
    skills = symbolic_skills(world)
    moved = threading.Event()

    class MoveAndNotice(smach.State):
        """Moves, and sees that somebody carried the cup to the hall meanwhile."""

        def __init__(self, *args: str) -> None:
            super().__init__(
                outcomes=["succeeded", "aborted", "preempted"], output_keys=["observations"]
            )
            self.args = args

        def execute(self, ud: smach.UserData) -> str:
            ok, obs = world.perform(_step("move", self.args))
            if not moved.is_set() and self.args[2] == "kitchen":
                moved.set()
                world._facts.discard(("item-at", "cup", "kitchen"))
                world._facts.add(("item-at", "cup", "hall"))
                obs += [(("item-at", "cup", "kitchen"), False), (("item-at", "cup", "hall"), True)]
            ud.observations = obs
            return "succeeded" if ok else "aborted"

    skills.add("move", MoveAndNotice)
    ex = Executive(task, skills, planner)
    assert ex.execute() == "succeeded"
    assert moved.is_set()
    kinds = [d["decision"] for d in ex.report.decisions]
    assert kinds and kinds[0] in ("repair", "replan")
    assert ("item-at", "cup", "office") in world.facts


def _step(action: str, args: tuple[str, ...]):  # type: ignore[no-untyped-def]
    from plan_bridge.planning.planner import PlanStep

    return PlanStep(action, args)


@pytest.mark.timeout(60)
def test_preempt_reaches_the_running_skill_and_ends_the_mission(planner) -> None:  # type: ignore[no-untyped-def]
    task = rooms()
    world = SimulatedWorld(task)
    skills = symbolic_skills(world)
    started = threading.Event()

    class SlowMove(smach.State):
        def __init__(self, *args: str) -> None:
            super().__init__(outcomes=["succeeded", "aborted", "preempted"])

        def execute(self, ud: smach.UserData) -> str:
            started.set()
            if self.sleep(30):
                self.service_preempt()
                return "preempted"
            return "succeeded"

    skills.add("move", SlowMove)
    ex = Executive(task, skills, planner)
    result: list[str | None] = []
    runner = threading.Thread(target=lambda: result.append(ex.execute()))
    runner.start()
    assert started.wait(30)
    ex.request_preempt()
    runner.join(10)
    assert not runner.is_alive()
    assert result == ["preempted"]
    assert ex.report.decisions[-1]["decision"] == "stop"


@pytest.mark.timeout(60)
def test_events_name_plans_steps_and_decisions(planner) -> None:  # type: ignore[no-untyped-def]
    ex, _ = executive(rooms(), planner, seed=2, fail_rate=0.5)
    recorder = EventRecorder()
    ex.add_listener(recorder)
    ex.execute()
    plans = [e for e in recorder.events if isinstance(e, PlanComputed)]
    steps = [e for e in recorder.events if isinstance(e, StepFinished)]
    decisions = [e for e in recorder.events if isinstance(e, ExecutiveDecision)]
    assert plans[0].reason == "initial plan" and plans[0].path == "/ROOT"
    assert steps[0].path.startswith("/ROOT/PLAN/01_")
    assert len(decisions) == len(ex.report.decisions)


@pytest.mark.timeout(60)
def test_executive_runs_nested_in_a_hand_written_machine(planner) -> None:  # type: ignore[no-untyped-def]
    ex, _ = executive(rooms(), planner)
    sm = smach.StateMachine(outcomes=["done", "failed"])
    with sm:
        smach.StateMachine.add(
            "DELIVER",
            ex,
            transitions={"succeeded": "done", "aborted": "failed", "preempted": "failed"},
        )
    recorder = EventRecorder()
    sm.add_listener(recorder)
    assert sm.execute() == "done"
    assert any(e.path.startswith("/ROOT/DELIVER/PLAN/") for e in recorder.events)


@pytest.mark.timeout(60)
def test_concurrent_execution_runs_independent_steps_of_two_robots_together(planner) -> None:  # type: ignore[no-untyped-def]
    task = rooms("p02.pddl")
    world = SimulatedWorld(task)
    skills = symbolic_skills(world)
    ex = Executive(task, skills, planner, concurrent=True)
    recorder = EventRecorder()
    ex.add_listener(recorder)
    assert ex.execute() == "succeeded"
    assert any("PARALLEL_2" in e.path for e in recorder.events)


def test_executive_reports_skill_problems_when_checked() -> None:
    task = rooms()
    ex = Executive(task, SkillRegistry(), get_planner("fast-downward"))
    with pytest.raises(smach.InvalidStateError, match="no skill registered"):
        ex.check_consistency()
