"""The replanning budget and a search (issue 36): a replan that follows a place ruled
out (the object looked for is not there) does not count against ``max_replans``; a
failure still does."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest

import smach
from plan_bridge.belief import Belief, FactSnapshot
from plan_bridge.execution.executive import Executive, ReplanPolicy
from plan_bridge.execution.semantics import ActionModel
from plan_bridge.execution.task_view import adopt_map_atoms
from plan_bridge.maps.tasks import RouteTasks
from plan_bridge.skills.registry import OBSERVATIONS_KEY, SkillRegistry

pytestmark = pytest.mark.timeout(120)

#: Where the apple really is (the belief has lost it).
APPLE_AT = "shelf_top"


class _Act(smach.State):
    """A skill that reports what the robot sees and succeeds when ``ok()`` says so."""

    def __init__(self, ok: Callable[[], bool], seen: list[tuple[tuple[str, ...], bool]]) -> None:
        super().__init__(outcomes=["succeeded", "aborted", "preempted"], io_keys=[OBSERVATIONS_KEY])
        self.ok, self.seen = ok, seen

    def execute(self, ud: smach.UserData) -> str:
        ud.observations = self.seen
        return "succeeded" if self.ok() else "aborted"


def skills(*, picks_fail: int = 0) -> SkillRegistry:
    """navigate: the robot sees whether the apple is at the place it arrives at;
    search: finds it where it is; pick: fails ``picks_fail`` times first."""
    registry = SkillRegistry()
    failures = [picks_fail]

    def navigate(robot: str, origin: str, target: str) -> smach.State:
        return _Act(lambda: True, [(("at", "apple", target), target == APPLE_AT)])

    def search(robot: str, item: str, place: str, fixture: str) -> smach.State:
        return _Act(lambda: place == APPLE_AT, [])

    def pick(robot: str, item: str, place: str, fixture: str) -> smach.State:
        def ok() -> bool:
            failures[0] -= 1
            return failures[0] < 0

        return _Act(ok, [])

    registry.add("navigate", navigate)
    registry.add("search", search)
    registry.add("pick", pick)
    return registry


def mission(house: Any, kairos: Any, policy: ReplanPolicy, registry: SkillRegistry) -> Executive:
    """Hold the apple, which the belief has lost (it was on the desk; nobody knows where
    it is now): the robot looks on the desk first (nearest), then on the shelf."""
    view = RouteTasks(house())
    start = view.belief()
    facts = FactSnapshot({f for f in start if "apple" not in f[1:]}, start.values)
    goal = [("holding", "robot", "apple")]
    task = view.task_for(facts, goal)
    belief = Belief(facts, whereabouts=True)
    adopt_map_atoms(view, belief, task, ActionModel(task).initial_values())
    return Executive(task, registry, kairos, policy=policy, belief=belief, task_view=view)


def test_a_replan_after_a_place_ruled_out_is_not_counted_against_the_budget(
    house: Any, kairos: Any
) -> None:
    policy = ReplanPolicy(max_step_retries=0, max_replans=0)
    executive = mission(house, kairos, policy, skills())
    assert executive.execute() == "succeeded"
    report = executive.report
    assert report.replans >= 1  # the desk was ruled out: the robot looked further
    assert ("absent", "apple", "desk_top") not in executive.belief.facts  # found: forgotten
    assert any(step.startswith("(search robot apple shelf_top") for step in report.executed)


def test_a_failure_during_a_search_still_counts_against_the_budget(house: Any, kairos: Any) -> None:
    policy = ReplanPolicy(max_step_retries=0, max_replans=0)
    executive = mission(house, kairos, policy, skills(picks_fail=1))
    assert executive.execute() == "aborted"
    assert "budget exhausted" in executive.report.explanation
