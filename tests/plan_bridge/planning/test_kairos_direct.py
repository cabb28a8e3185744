"""Kairos in the planner worker without unified-planning's round trip: text straight to
Kairos' own reader, for tasks read from PDDL and tasks built in memory."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from plan_bridge.belief import FactSnapshot
from plan_bridge.execution.semantics import ActionModel
from plan_bridge.maps.tasks import RouteTasks
from plan_bridge.pddl.task import load_task
from plan_bridge.planning.kairos_direct import solve_with_kairos
from plan_bridge.planning.problem_source import problem_source

ROOT = Path(__file__).resolve().parents[3]
COURIER = ROOT / "domains" / "timed_courier"

pytestmark = pytest.mark.timeout(120)


def start(task: Any) -> FactSnapshot:
    return FactSnapshot(task.initial_facts, ActionModel(task).initial_values())


def test_a_task_read_from_pddl_is_planned_and_replanned_from_another_state(kairos: Any) -> None:
    task = load_task(COURIER / "domain.pddl", COURIER / "problems" / "p01.pddl")
    first = kairos.solve(task, timeout=30)
    assert first.solved and first.temporal
    assert ActionModel(task).check_plan(first.actions, start(task)).valid
    # The courier at the hall already: the worker restates the text it holds.
    moved = (task.initial_facts - {("at", "courier", "depot")}) | {("at", "courier", "hall")}
    again = kairos.solve(task, timeout=30, initial_state=moved)
    assert again.solved and again.problem_reused
    assert not any(s.arguments[:2] == ("courier", "depot") for s in again.actions[:1])


def test_a_task_built_in_memory_travels_as_data_and_is_planned(kairos: Any, house: Any) -> None:
    view = RouteTasks(house())
    task = view.task_for(view.belief(), [("at", "apple", "shelf_top")])
    source = problem_source(task)
    assert source.text.spec is not None and source.text.problem == ""  # no PDDL text
    result = kairos.solve(task, timeout=30)
    assert result.solved
    assert [s.action for s in result.actions] == ["navigate", "pick", "navigate", "place"]
    assert ActionModel(task).check_plan(result.actions, start(task)).valid


class _Base:
    """What the worker keeps of a base problem, with a domain Kairos does not read."""

    domain_text = "(define (domain odd) (:requirements :strips) (:predicates (p)) (:oddity))"
    problem_text = "(define (problem q) (:domain odd) (:init) (:goal (p)))"
    spec = None
    kairos = None
    true_atoms: dict[tuple[str, ...], Any] = {}


def test_a_domain_kairos_does_not_read_is_left_to_unified_planning() -> None:
    base = _Base()
    assert solve_with_kairos(base, {"timeout": 5}) is None
    assert base.kairos is not None and base.kairos.refused  # and not asked again
