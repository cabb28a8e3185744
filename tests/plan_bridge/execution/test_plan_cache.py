"""The plan cache: plans per (task, state, goal), bounded, told apart by the task's text."""

from __future__ import annotations

from pathlib import Path

import pytest

from plan_bridge.execution.plan_cache import PlanCache
from plan_bridge.pddl.task import PlanningTask, load_task
from plan_bridge.planning.planner import PlanStep

ROOMS = Path(__file__).parents[1] / "data" / "rooms"
PLAN = [PlanStep("move", ("robot1", "hall", "kitchen"))]


def rooms(problem: str = "p01.pddl") -> PlanningTask:
    return load_task(ROOMS / "domain.pddl", ROOMS / "problems" / problem)


def test_a_plan_is_found_again_for_the_same_text_state_and_goal() -> None:
    cache = PlanCache()
    task = rooms()
    cache.put(task, task.initial_facts, None, PLAN, "lama-first")
    again = rooms()  # another object, the same text
    assert cache.get(again, set(again.initial_facts)) == (PLAN, "lama-first")
    assert cache.hits == 1


def test_another_state_goal_or_problem_is_a_miss() -> None:
    cache = PlanCache()
    task = rooms()
    cache.put(task, task.initial_facts, None, PLAN)
    assert cache.get(task, task.initial_facts - {("free", "robot1")}) is None
    assert cache.get(task, task.initial_facts, {("free", "robot1")}) is None
    assert cache.get(rooms("p02.pddl"), task.initial_facts) is None
    assert cache.misses == 3


def test_the_least_recently_used_plan_is_dropped_beyond_the_bound() -> None:
    cache = PlanCache(max_entries=2)
    task = rooms()
    states = [frozenset({("lights-on", room)}) for room in ("hall", "kitchen", "office")]
    cache.put(task, states[0], None, PLAN)
    cache.put(task, states[1], None, PLAN)
    assert cache.get(task, states[0]) is not None  # now the most recently used
    cache.put(task, states[2], None, PLAN)
    assert len(cache) == 2
    assert cache.get(task, states[1]) is None and cache.get(task, states[0]) is not None


def test_tasks_without_text_are_told_apart_by_identity() -> None:
    import dataclasses

    cache = PlanCache()
    task = rooms()
    one = dataclasses.replace(task, domain_text=None, problem_text=None)
    two = dataclasses.replace(task, domain_text=None, problem_text=None)
    cache.put(one, task.initial_facts, None, PLAN)
    assert cache.get(one, task.initial_facts) is not None
    assert cache.get(two, task.initial_facts) is None


def test_a_cache_without_room_is_refused() -> None:
    with pytest.raises(ValueError, match="max_entries must be >= 1"):
        PlanCache(max_entries=0)
