"""Grounding for the warm search: lifted actions compiled once, reachable instances."""

from __future__ import annotations

from pathlib import Path

import pytest

from plan_bridge.pddl.task import PlanningTask, load_task, load_task_from_text
from plan_bridge.planning.grounding import (
    GroundingLimitError,
    LiftedModel,
    UnsupportedProblemError,
)

ROOT = Path(__file__).resolve().parents[3]
DOMAINS = ROOT / "domains"
DATA = ROOT / "tests" / "plan_bridge" / "data"

LOCKS_DOMAIN = """\
(define (domain locks)
  (:requirements :strips :typing :negative-preconditions :equality)
  (:types room)
  (:predicates (at ?r - room) (link ?a ?b - room) (locked ?r - room) (seen ?r - room))
  (:action go
    :parameters (?a ?b - room)
    :precondition (and (at ?a) (link ?a ?b) (not (locked ?b)) (not (= ?a ?b)))
    :effect (and (at ?b) (seen ?b) (not (at ?a)))))
"""

LOCKS_PROBLEM = """\
(define (problem three) (:domain locks)
  (:objects a b c - room)
  (:init (at a) (link a b) (link b c) (link a a) (locked c))
  (:goal (seen b)))
"""


def _mission(name: str, problem: str = "p01") -> PlanningTask:
    return load_task(
        DOMAINS / name / "domain.pddl", DOMAINS / name / "problems" / f"{problem}.pddl"
    )


@pytest.fixture(scope="module")
def locks() -> PlanningTask:
    return load_task_from_text(LOCKS_DOMAIN, LOCKS_PROBLEM)


def test_grounding_keeps_only_actions_reachable_and_allowed_by_static_literals(
    locks: PlanningTask,
) -> None:
    model = LiftedModel(locks.problem)
    task = model.ground(locks.initial_facts)
    # (go a a) breaks the inequality, (go b c) enters a locked room (static), and
    # nothing ever leaves c.
    assert [(op.name, op.arguments) for op in task.operators] == [("go", ("a", "b"))]
    assert model.static_predicates == {"link", "locked"}
    assert ("at", "b") in task.index and ("at", "c") not in task.index


def test_a_grounding_covers_states_inside_its_reach_with_the_same_static_atoms(
    locks: PlanningTask,
) -> None:
    task = LiftedModel(locks.problem).ground(locks.initial_facts)
    statics = {fact for fact in locks.initial_facts if fact[0] in ("link", "locked")}
    assert task.covers({*statics, ("at", "b"), ("seen", "b")})
    assert not task.covers({*statics - {("locked", "c")}, ("at", "b")})  # a static changed
    assert not task.covers({*statics, ("at", "c")})  # outside what it reached


def test_goal_masks_are_none_when_a_goal_atom_is_unreachable(locks: PlanningTask) -> None:
    task = LiftedModel(locks.problem).ground(locks.initial_facts)
    assert task.goal([("seen", "b")], []) is not None
    assert task.goal([("seen", "c")], []) is None
    assert task.goal([("locked", "a")], []) is None  # a static atom that is false


@pytest.mark.parametrize("mission", ["fetch_drink", "door_opening", "table_clearing", "recharge"])
def test_the_shipped_missions_compile_and_ground(mission: str) -> None:
    task = _mission(mission, "p03")
    grounded = LiftedModel(task.problem).ground(task.initial_facts)
    assert grounded.operators
    assert all(op.add for op in grounded.operators)


def test_conditional_effects_and_quantifiers_are_left_to_the_engines() -> None:
    task = load_task(DATA / "rooms" / "domain.pddl", DATA / "rooms" / "problems" / "p01.pddl")
    with pytest.raises(UnsupportedProblemError):
        LiftedModel(task.problem)


def test_durative_and_numeric_problems_are_left_to_the_engines() -> None:
    courier = _mission("timed_courier")
    with pytest.raises(UnsupportedProblemError):
        LiftedModel(courier.problem)


def test_grounding_stops_at_its_operator_limit() -> None:
    task = _mission("door_opening", "p03")
    with pytest.raises(GroundingLimitError, match="more than 5 ground actions"):
        LiftedModel(task.problem).ground(task.initial_facts, max_operators=5)


def test_models_compiled_one_after_another_ground_the_same_actions_each_time(
    bench: Path,
) -> None:
    # Join orders are cached per action: a model's cache must never serve another's
    # actions (an action compiled later may reuse a freed one's memory address).
    names = ("blocks/probBLOCKS-4-0", "gripper/prob01", "miconic/s3-0", "tpp/p03")
    tasks = []
    for name in names:
        domain, problem = name.split("/")
        tasks.append(load_task(bench / domain / "domain.pddl", bench / domain / f"{problem}.pddl"))
    counts = [
        [len(LiftedModel(task.problem).ground(task.initial_facts).operators) for task in tasks]
        for _ in range(4)
    ]
    assert counts[0] == [40, 36, 36, 11]
    assert all(row == counts[0] for row in counts)
