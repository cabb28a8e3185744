"""A user's own skill next to simulated ones: the skill contract in every world.

Robot-style domains written for these tests (tests/plan_bridge/data/warehouse_bot,
classical; tests/plan_bridge/data/timed_rover, temporal and numeric): the most used
action (``drive``) runs as the user's skill, every other action is simulated.
"""

from __future__ import annotations

import threading
from pathlib import Path

import pytest

import smach
from plan_bridge.execution.executive import Executive
from plan_bridge.execution.simulation import SimulatedWorld, symbolic_skills
from plan_bridge.execution.timed_world import TimedWorld, timed_skills
from plan_bridge.pddl.task import PlanningTask, load_task
from plan_bridge.skills.registry import SkillRegistry

DATA = Path(__file__).parents[1] / "data"


def task_of(name: str) -> PlanningTask:
    return load_task(DATA / name / "domain.pddl", DATA / name / "problems" / "p01.pddl")


@pytest.fixture(scope="module")
def warehouse() -> PlanningTask:
    return task_of("warehouse_bot")


@pytest.fixture(scope="module")
def rover() -> PlanningTask:
    return task_of("timed_rover")


class UserDrive(smach.State):
    """A user's drive skill: it would command a robot; here it records each call.

    ``failures``: how many of the first calls abort without observing anything.
    """

    def __init__(self, calls: list[tuple[str, ...]], failures: int = 0) -> None:
        super().__init__(outcomes=["succeeded", "aborted", "preempted"], input_keys=["arguments"])
        self.calls = calls
        self.failures = failures
        self.lock = threading.Lock()

    def execute(self, ud: smach.UserData) -> str:
        with self.lock:
            self.calls.append(tuple(ud.arguments))
            failing = len(self.calls) <= self.failures
        return "aborted" if failing else "succeeded"


def user_registry(calls: list[tuple[str, ...]], failures: int = 0) -> SkillRegistry:
    registry = SkillRegistry()
    registry.add("drive", lambda *args: UserDrive(calls, failures))
    return registry


@pytest.mark.timeout(120)
@pytest.mark.parametrize(("fail_rate", "seed"), [(0.0, 0), (0.3, 1), (0.3, 2), (0.3, 3)])
def test_a_user_skill_among_symbolic_ones_reaches_the_goal(
    warehouse: PlanningTask, fail_rate: float, seed: int
) -> None:
    calls: list[tuple[str, ...]] = []
    world = SimulatedWorld(warehouse, seed=seed, fail_rate=fail_rate)
    executive = Executive(warehouse, symbolic_skills(world, user_registry(calls)))

    assert executive.execute() == "succeeded", executive.report.explanation
    assert world.goal_reached()  # the simulated truth learned what the user's drives did
    assert ("rb1", "dock", "inbound") in calls
    assert ("located", "rb1", "dock") in world.facts


@pytest.mark.timeout(120)
def test_the_world_takes_the_effects_of_a_user_skill_only_when_it_succeeds(
    warehouse: PlanningTask,
) -> None:
    calls: list[tuple[str, ...]] = []
    world = SimulatedWorld(warehouse, seed=0)
    executive = Executive(warehouse, symbolic_skills(world, user_registry(calls, failures=1)))

    assert executive.execute() == "succeeded", executive.report.explanation
    # The first drive aborted without observing: the world did not move the robot, the
    # executive sensed around it before recovering, and the mission went on.
    decisions = [d["decision"] for d in executive.report.decisions]
    assert "sense" in decisions
    assert executive.report.actions_failed == 1
    assert world.goal_reached()


@pytest.mark.timeout(120)
@pytest.mark.parametrize(("fail_rate", "seed"), [(0.0, 0), (0.3, 1), (0.3, 4)])
def test_a_user_durative_skill_among_timed_ones_reaches_the_goal(
    rover: PlanningTask, fail_rate: float, seed: int
) -> None:
    calls: list[tuple[str, ...]] = []
    world = TimedWorld(rover, seed=seed, fail_rate=fail_rate)
    executive = Executive(rover, timed_skills(world, user_registry(calls)))

    assert executive.execute() == "succeeded", executive.report.explanation
    assert world.goal_reached()
    assert calls[0] == ("rv", "base", "ridge")


@pytest.mark.timeout(120)
def test_an_aborting_user_durative_skill_is_undone_in_the_belief_and_the_mission_recovers(
    rover: PlanningTask,
) -> None:
    calls: list[tuple[str, ...]] = []
    world = TimedWorld(rover, seed=0)
    executive = Executive(rover, timed_skills(world, user_registry(calls, failures=1)))
    seen: list[frozenset[tuple[str, ...]]] = []
    executive.belief.add_listener(lambda: seen.append(executive.belief.facts))

    assert executive.execute() == "succeeded", executive.report.explanation
    # The failed drive's at-start effect (not parked anywhere) was taken back: after
    # it the rover was believed parked at base again, and a new plan got it there.
    assert executive.report.actions_failed == 1
    assert any(("parked", "rv", "base") in facts for facts in seen[1:])
    assert world.goal_reached()
    assert len(calls) >= 2


@pytest.mark.timeout(120)
def test_the_executive_defaults_plan_temporal_problems(rover: PlanningTask) -> None:
    world = TimedWorld(rover, seed=0)
    executive = Executive(rover, timed_skills(world))

    assert executive.execute() == "succeeded", executive.report.explanation
    assert executive.report.planners_won  # auto chose a temporal planner (not fast-downward)
    assert "fast-downward" not in executive.report.planners_won


@pytest.mark.timeout(60)
def test_the_executive_finds_the_world_of_its_simulated_skills(warehouse: PlanningTask) -> None:
    world = SimulatedWorld(warehouse, seed=0)
    assert Executive(warehouse, symbolic_skills(world)).world is world
    assert Executive(warehouse, SkillRegistry()).world is None
