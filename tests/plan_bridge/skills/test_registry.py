"""The skill registry and its start-up checks."""

from __future__ import annotations

from pathlib import Path

import pytest

import smach
from plan_bridge.pddl.task import load_task
from plan_bridge.planning.planner import PlanStep
from plan_bridge.skills.registry import SkillError, SkillRegistry
from smach.testing import ScriptedState

DATA = Path(__file__).parents[1] / "data"


@pytest.fixture(scope="module")
def task():  # type: ignore[no-untyped-def]
    return load_task(DATA / "rooms" / "domain.pddl", DATA / "rooms" / "problems" / "p01.pddl")


def good(*args: str) -> smach.State:
    return ScriptedState(["succeeded"], outcomes=["succeeded", "aborted", "preempted"])


def registry_with_all(**overrides):  # type: ignore[no-untyped-def]
    skills = SkillRegistry()
    for action in ("move", "pick", "drop", "switch-on"):
        if action not in overrides:
            skills.add(action, good)
    for action, (factory, outcome_map) in overrides.items():
        skills.add(action.replace("_", "-"), factory, outcome_map=outcome_map)
    return skills


def test_a_complete_registry_has_no_problems(task) -> None:  # type: ignore[no-untyped-def]
    assert registry_with_all().check(task) == []


def test_missing_skill_is_reported_per_action(task) -> None:  # type: ignore[no-untyped-def]
    skills = SkillRegistry()
    skills.add("move", good)
    problems = skills.check(task)
    assert any("action 'pick': no skill registered" in p for p in problems)
    assert len(problems) == 3


def test_wrong_arity_is_reported_with_the_factory_signature(task) -> None:  # type: ignore[no-untyped-def]
    def pick(robot: str) -> smach.State:
        return good()

    problems = registry_with_all(pick=(pick, None)).check(task)
    assert len(problems) == 1
    assert "cannot take 3 argument(s)" in problems[0]


def test_unmapped_extra_outcome_is_reported_and_mapping_fixes_it(task) -> None:  # type: ignore[no-untyped-def]
    def pick(*args: str) -> smach.State:
        return ScriptedState(
            ["succeeded"], outcomes=["succeeded", "aborted", "preempted", "dropped"]
        )

    problems = registry_with_all(pick=(pick, None)).check(task)
    assert len(problems) == 1 and "'dropped'" in problems[0]
    assert registry_with_all(pick=(pick, {"dropped": "aborted"})).check(task) == []


def test_skill_for_an_unknown_action_is_reported(task) -> None:  # type: ignore[no-untyped-def]
    skills = registry_with_all()
    skills.add("fly", good)
    assert any("no action 'fly'" in p for p in skills.check(task))


def test_registering_an_action_twice_is_an_error() -> None:
    skills = SkillRegistry()
    skills.add("pick", good)
    with pytest.raises(SkillError, match="already registered"):
        skills.add("pick", good)


def test_create_without_skill_or_fallback_names_the_step() -> None:
    with pytest.raises(SkillError, match=r"no skill for action 'pick' \(step \(pick a b\)\)"):
        SkillRegistry().create(PlanStep("pick", ("a", "b")))


def test_factory_errors_and_non_states_become_skill_errors() -> None:
    skills = SkillRegistry()
    skills.add("boom", lambda: 1 / 0)
    skills.add("bad", lambda: "not a state")
    with pytest.raises(SkillError, match="raised ZeroDivisionError"):
        skills.create(PlanStep("boom"))
    with pytest.raises(SkillError, match=r"not a smach\.State"):
        skills.create(PlanStep("bad"))
