"""The warm path: the warm search in the planner worker, cold starts, and ``auto``."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from plan_bridge.execution.semantics import ActionModel
from plan_bridge.pddl.task import PlanningTask, load_task, load_task_from_text
from plan_bridge.planning import engines
from plan_bridge.planning.engines import WARM, AutoPlanner, WarmPlanner, engines_for
from plan_bridge.planning.grounding import Operator
from plan_bridge.planning.planner import PlanStatus, get_planner
from plan_bridge.planning.warm import check_plan
from plan_bridge.planning.worker import WorkerPool

ROOT = Path(__file__).resolve().parents[3]
FETCH = ROOT / "domains" / "fetch_drink"

pytestmark = pytest.mark.timeout(120)


@pytest.fixture(scope="module")
def pool() -> Iterator[WorkerPool]:
    pool = WorkerPool(max_workers=1)
    pool.warm_up(1)
    yield pool
    pool.close()


def _fetch() -> PlanningTask:
    return load_task(FETCH / "domain.pddl", FETCH / "problems" / "p02.pddl")


def _ready(planner: WarmPlanner, task: PlanningTask) -> None:
    """Make sure the pool's worker has started (so solves go to it)."""
    with planner.pool.worker() as worker:
        worker.wait_ready()


def test_the_warm_search_plans_in_the_worker_and_reuses_its_grounding_on_a_replan(
    pool: WorkerPool,
) -> None:
    task = _fetch()
    planner = WarmPlanner(pool=pool)
    _ready(planner, task)
    first = planner.solve(task, timeout=10)
    assert first.solved and first.planner == WARM
    model = ActionModel(task)
    assert model.check_plan(first.actions, task.initial_facts).valid
    # A replan from the state after the first step: no parse, no new grounding.
    state = model.ground(first.actions[0]).apply(task.initial_facts)
    second = planner.solve(task, timeout=10, initial_state=state)
    assert second.solved and second.problem_reused and "(reused)" in second.log
    assert model.check_plan(second.actions, state).valid


def test_a_replan_toward_other_goal_atoms_reaches_them(pool: WorkerPool) -> None:
    task = _fetch()
    planner = WarmPlanner(pool=pool)
    goal = [("fridge-open", "kitchen-fridge")]
    result = planner.solve(task, timeout=10, goal=goal)
    assert result.solved and result.plan_strings()[-1].startswith("(open-fridge")


def test_a_cold_start_searches_in_the_calling_process_without_starting_a_worker() -> None:
    idle = WorkerPool(max_workers=1)
    try:
        result = WarmPlanner(pool=idle).solve(_fetch(), timeout=10)
        assert result.solved and idle._count == 0
    finally:
        idle.close()


def test_an_unreachable_goal_is_proved_unsolvable_and_explained(pool: WorkerPool) -> None:
    task = _fetch()
    state = task.initial_facts - {fact for fact in task.initial_facts if fact[0] == "clear"}
    result = WarmPlanner(pool=pool).solve(task, timeout=10, initial_state=state)
    assert result.status is PlanStatus.UNSOLVABLE
    assert result.engine_status == "UNSOLVABLE_PROVEN"
    assert "warm-gbfs proved that no plan exists" in result.explanation


def test_auto_for_execution_plans_classical_missions_with_the_warm_search(
    pool: WorkerPool,
) -> None:
    task = _fetch()
    one_shot = AutoPlanner(pool=pool)
    assert one_shot.engines(task)[0] == "fast-downward"
    executing = one_shot.for_execution()
    assert executing.name == "auto" and executing.engines(task)[0] == WARM
    assert executing.solve(task, timeout=30).planner == WARM


def test_auto_leaves_problems_with_action_costs_or_time_to_the_engines() -> None:
    courier = load_task(
        ROOT / "domains" / "timed_courier" / "domain.pddl",
        ROOT / "domains" / "timed_courier" / "problems" / "p01.pddl",
    )
    assert WARM not in engines_for(courier, warm=True)
    costs = load_task_from_text(
        "(define (domain c) (:requirements :strips :action-costs)"
        " (:predicates (done)) (:functions (total-cost))"
        " (:action do :parameters () :precondition (and) :effect (and (done)"
        " (increase (total-cost) 1))))",
        "(define (problem c1) (:domain c) (:init (= (total-cost) 0)) (:goal (done))"
        " (:metric minimize (total-cost)))",
    )
    assert WARM not in engines_for(costs, warm=True)
    assert "metric" in engines.warm_unsupported(costs)


def test_after_the_warm_search_spends_its_budget_fast_downward_plans_the_task(
    pool: WorkerPool, monkeypatch: pytest.MonkeyPatch, bench: Path
) -> None:
    folder = bench / "visitall-sat11-strips"
    task = load_task(folder / "domain.pddl", folder / "problem12.pddl")
    monkeypatch.setattr(engines, "WARM_BUDGET_S", 0.02)
    planner = AutoPlanner(pool=pool, warm=True)
    result = planner.solve(task, timeout=60)
    assert result.solved and result.planner == "fast-downward"
    # It ran out of budget while grounding or searching.
    assert any(note.startswith("tried first: warm-gbfs: ") for note in result.warnings)
    # The task is Fast Downward's from now on.
    assert planner.engines(task)[0] == "fast-downward"


def test_get_planner_names_the_warm_search() -> None:
    assert isinstance(get_planner(WARM), WarmPlanner)


def test_the_plan_check_refuses_a_step_whose_precondition_does_not_hold() -> None:
    task = _fetch()
    bogus = Operator("hand-over", ("pr2", "cola", "alice", "kitchen"), 0, 0, 0, 0, (), ())
    flaw = check_plan(task.problem, (bogus,), frozenset(task.initial_facts), None, None)
    assert "step 1 (hand-over pr2 cola alice kitchen) is not applicable" in flaw
    wrong_type = Operator("hand-over", ("pr2", "alice", "alice", "kitchen"), 0, 0, 0, 0, (), ())
    assert "alice is not a drink" in check_plan(
        task.problem, (wrong_type,), frozenset(task.initial_facts), None, None
    )
