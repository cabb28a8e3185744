"""Engine choice by problem kind, the fallback portfolio, temporal plans and numbers."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import pytest

from plan_bridge.belief import Belief
from plan_bridge.execution.semantics import ActionModel
from plan_bridge.pddl.task import PlanningTask, load_task
from plan_bridge.planning.engines import AutoPlanner, engines_for, problem_kind
from plan_bridge.planning.planner import PlanResult, PlanStatus, get_planner

ROOT = Path(__file__).resolve().parents[3]
DATA = ROOT / "tests" / "plan_bridge" / "data"
COURIER = ROOT / "domains" / "timed_courier"

pytestmark = pytest.mark.timeout(120)


@pytest.fixture(scope="module")
def patrol() -> PlanningTask:
    return load_task(DATA / "temporal" / "domain.pddl", DATA / "temporal" / "problem.pddl")


@pytest.fixture(scope="module")
def courier() -> PlanningTask:
    return load_task(COURIER / "domain.pddl", COURIER / "problems" / "p02.pddl")


def test_kind_is_temporal_and_numeric_for_durative_actions_with_functions(
    patrol: PlanningTask,
) -> None:
    kind = problem_kind(patrol)
    assert kind.temporal and kind.numeric and kind.name == "temporal+numeric"


def test_a_strips_problem_is_classical_and_goes_to_fast_downward() -> None:
    task = load_task(DATA / "rooms" / "domain.pddl", DATA / "rooms" / "problems" / "p01.pddl")
    assert problem_kind(task).name == "classical"
    assert engines_for(task)[0] == "fast-downward"


def test_temporal_problems_go_to_kairos_first_then_tamer(patrol: PlanningTask) -> None:
    assert engines_for(patrol) == ["kairos", "tamer"]


def test_auto_plans_a_temporal_problem_with_start_times_durations_and_makespan(
    patrol: PlanningTask,
) -> None:
    result = get_planner("auto").solve(patrol, timeout=30)
    assert result.solved and result.planner == "kairos"
    assert all(step.start is not None and step.duration for step in result.actions)
    payload = result.to_json()
    assert payload["makespan"] == pytest.approx(result.makespan)
    assert {entry["action"] for entry in payload["actions"]} == set(result.plan_strings())
    model = ActionModel(patrol)
    facts = Belief(patrol.initial_facts, model.initial_values()).facts
    assert model.check_plan(result.actions, facts).valid


def test_tamer_plans_the_overlap_the_goal_needs(patrol: PlanningTask) -> None:
    result = get_planner("tamer").solve(patrol, timeout=30)
    assert result.solved
    light = next(s for s in result.actions if s.action == "hold-light")
    inspect = next(s for s in result.actions if s.action == "inspect")
    assert light.start is not None and inspect.start is not None
    assert light.start <= inspect.start < light.start + (light.duration or 0.0)


def test_the_portfolio_tries_the_next_engine_when_one_refuses(patrol: PlanningTask) -> None:
    result = AutoPlanner(engines=["fast-downward", "kairos"]).solve(patrol, timeout=30)
    assert result.solved and result.planner == "kairos"
    assert any(w.startswith("tried first: fast-downward") for w in result.warnings)


def test_tamer_is_stopped_at_the_hard_time_limit_although_it_ignores_timeouts(
    courier: PlanningTask,
) -> None:
    started = time.monotonic()
    result = get_planner("tamer").solve(courier, timeout=2.0)
    assert result.status is PlanStatus.TIMEOUT
    assert "killed" in result.explanation
    assert time.monotonic() - started < 15


def test_a_replan_from_a_belief_uses_its_numbers(patrol: PlanningTask) -> None:
    model = ActionModel(patrol)
    values = model.initial_values()
    values[("energy", "scout")] = 1.0  # too little to inspect
    values[("energy", "lamp")] = 9.0
    facts = set(patrol.initial_facts) | {("docked", "lamp")}
    belief = Belief(facts, values)
    result = get_planner("auto").solve(patrol, timeout=30, initial_state=belief.facts)
    assert result.solved
    inspect = next(s for s in result.actions if s.action == "inspect")
    assert inspect.arguments == ("lamp", "yard")
    assert model.check_plan(result.actions, belief.facts).valid


class _Answering:
    """An engine that answers ``result`` without planning (for the portfolio's choice)."""

    def __init__(self, result: PlanResult) -> None:
        self.result = result

    def solve(self, task: PlanningTask, **options: object) -> PlanResult:
        return self.result


def test_a_refusal_after_a_search_does_not_hide_what_the_search_found(
    patrol: PlanningTask,
) -> None:
    searched = PlanResult(
        PlanStatus.UNSOLVABLE, planner="kairos", explanation="kairos found no plan"
    )
    refused = PlanResult(
        PlanStatus.UNSUPPORTED, planner="tamer", explanation="tamer cannot handle HIERARCHICAL"
    )
    answers = {"kairos": _Answering(searched), "tamer": _Answering(refused)}

    class Portfolio(AutoPlanner):
        def planner(self, engine: str) -> Any:
            return answers[engine]

    result = Portfolio(engines=["kairos", "tamer"]).solve(patrol, timeout=10)
    assert result.status is PlanStatus.UNSOLVABLE
    assert result.explanation == "kairos found no plan"
    assert any(w.startswith("tried first: tamer") for w in result.warnings)
