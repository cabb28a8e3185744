"""The warm search: sound plans, proofs of unsolvability, a budget it keeps."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from plan_bridge.execution.semantics import ActionModel
from plan_bridge.pddl.task import PlanningTask, load_task, load_task_from_text
from plan_bridge.planning.grounding import LiftedModel
from plan_bridge.planning.planner import PlanStep
from plan_bridge.planning.search import SearchOutcome, greedy_search

ROOT = Path(__file__).resolve().parents[3]
DOMAINS = ROOT / "domains"
MISSIONS = ("fetch_drink", "door_opening", "table_clearing", "recharge", "two_robot_delivery")
#: Small and medium IPC problems the search solves within a second here.
IPC = (
    "blocks/probBLOCKS-8-0",
    "gripper/prob03",
    "miconic/s6-0",
    "rovers/p05",
    "satellite/p03-pfile3",
    "depot/p02",
    "logistics98/prob01",
    "tpp/p05",
)

TOKEN_DOMAIN = """\
(define (domain token)
  (:requirements :strips)
  (:predicates (a) (b) (token))
  (:action spend-on-a :parameters () :precondition (token) :effect (and (a) (not (token))))
  (:action spend-on-b :parameters () :precondition (token) :effect (and (b) (not (token)))))
"""
TOKEN_PROBLEM = "(define (problem both) (:domain token) (:init (token)) (:goal (and (a) (b))))"


def _search(task: PlanningTask, seconds: float = 10.0) -> SearchOutcome:
    model = LiftedModel(task.problem)
    grounded = model.ground(task.initial_facts)
    goal = grounded.goal(model.goal_positive, model.goal_negative)
    assert goal is not None
    init = grounded.bits(task.initial_facts)
    return greedy_search(grounded, init, goal, deadline=time.monotonic() + seconds)


def _steps(outcome: SearchOutcome) -> list[PlanStep]:
    return [PlanStep(op.name, op.arguments) for op in outcome.plan]


@pytest.mark.parametrize("mission", MISSIONS)
@pytest.mark.parametrize("problem", ["p01", "p02", "p03"])
def test_plans_of_the_shipped_missions_pass_the_executives_plan_check(
    mission: str, problem: str
) -> None:
    task = load_task(
        DOMAINS / mission / "domain.pddl", DOMAINS / mission / "problems" / f"{problem}.pddl"
    )
    outcome = _search(task)
    assert outcome.status == "solved"
    assert ActionModel(task).check_plan(_steps(outcome), task.initial_facts).valid


@pytest.mark.parametrize("name", IPC)
def test_plans_of_ipc_problems_pass_the_executives_plan_check(bench: Path, name: str) -> None:
    domain, problem = name.split("/")
    task = load_task(bench / domain / "domain.pddl", bench / domain / f"{problem}.pddl")
    outcome = _search(task)
    assert outcome.status == "solved"
    assert ActionModel(task).check_plan(_steps(outcome), task.initial_facts).valid


def test_replans_from_states_along_a_plan_pass_the_plan_check() -> None:
    task = load_task(
        DOMAINS / "recharge" / "domain.pddl", DOMAINS / "recharge" / "problems" / "p02.pddl"
    )
    model = ActionModel(task)
    lifted = LiftedModel(task.problem)
    plan = _steps(_search(task))
    state = frozenset(task.initial_facts)
    for step in plan[: len(plan) // 2]:
        state = model.ground(step).apply(state)
        grounded = lifted.ground(state)
        goal = grounded.goal(lifted.goal_positive, lifted.goal_negative)
        assert goal is not None
        outcome = greedy_search(
            grounded, grounded.bits(state), goal, deadline=time.monotonic() + 10
        )
        assert outcome.status == "solved"
        assert model.check_plan(_steps(outcome), state).valid


def test_an_exhausted_search_proves_that_no_plan_exists() -> None:
    task = load_task_from_text(TOKEN_DOMAIN, TOKEN_PROBLEM)
    outcome = _search(task)
    assert outcome.status == "unsolvable" and outcome.plan == ()


def test_the_search_gives_up_at_its_deadline(bench: Path) -> None:
    folder = bench / "visitall-sat11-strips"
    task = load_task(folder / "domain.pddl", folder / "problem12.pddl")
    outcome = _search(task, seconds=0.0)
    assert outcome.status == "budget" and outcome.expansions >= 1


def test_a_state_that_satisfies_the_goal_needs_an_empty_plan() -> None:
    task = load_task_from_text(TOKEN_DOMAIN, TOKEN_PROBLEM)
    model = LiftedModel(task.problem)
    state = {("a",), ("b",)}
    grounded = model.ground(state)
    goal = grounded.goal(model.goal_positive, model.goal_negative)
    assert goal is not None
    outcome = greedy_search(grounded, grounded.bits(state), goal, deadline=time.monotonic() + 1)
    assert outcome.status == "solved" and outcome.plan == ()


def test_a_state_covered_by_an_older_grounding_gets_the_plan_a_fresh_grounding_gives() -> None:
    task = load_task(
        DOMAINS / "recharge" / "domain.pddl", DOMAINS / "recharge" / "problems" / "p03.pddl"
    )
    model = ActionModel(task)
    lifted = LiftedModel(task.problem)
    older = lifted.ground(task.initial_facts)
    state = frozenset(task.initial_facts)
    for step in _steps(_search(task))[:5]:
        state = model.ground(step).apply(state)
    assert older.covers(state)
    plans = []
    for grounded in (older, lifted.ground(state)):
        goal = grounded.goal(lifted.goal_positive, lifted.goal_negative)
        assert goal is not None
        outcome = greedy_search(
            grounded, grounded.bits(state), goal, deadline=time.monotonic() + 10
        )
        plans.append(_steps(outcome))
    assert plans[0] == plans[1]


def test_plans_do_not_depend_on_the_hash_seed() -> None:
    code = (
        "import time\n"
        "from plan_bridge.pddl.task import load_task\n"
        "from plan_bridge.planning.grounding import LiftedModel\n"
        "from plan_bridge.planning.search import greedy_search\n"
        f"task = load_task({str(DOMAINS / 'recharge' / 'domain.pddl')!r}, "
        f"{str(DOMAINS / 'recharge' / 'problems' / 'p03.pddl')!r})\n"
        "model = LiftedModel(task.problem)\n"
        "grounded = model.ground(task.initial_facts)\n"
        "goal = grounded.goal(model.goal_positive, model.goal_negative)\n"
        "out = greedy_search(grounded, grounded.bits(task.initial_facts), goal,"
        " deadline=time.monotonic() + 30)\n"
        "print([(op.name, op.arguments) for op in out.plan])\n"
    )
    outputs = set()
    for seed in ("1", "2"):
        proc = subprocess.run(
            [sys.executable, "-c", code],
            env={**os.environ, "PYTHONHASHSEED": seed},
            capture_output=True,
            text=True,
            timeout=60,
            check=True,
        )
        outputs.add(proc.stdout)
    assert len(outputs) == 1
