"""A skill state without a ``preempted`` outcome (as many SMACH tutorial states are) is
accepted: ``check`` warns, and a preempt lets its step finish before the plan stops."""

from __future__ import annotations

import threading
from pathlib import Path

import pytest

import smach
from plan_bridge.execution.executive import Executive
from plan_bridge.execution.simulation import SimulatedWorld, symbolic_skills
from plan_bridge.pddl.task import PlanningTask, load_task
from plan_bridge.skills.registry import SkillRegistry

COURIER = Path(__file__).parents[1] / "data" / "courier"


@pytest.fixture(scope="module")
def task() -> PlanningTask:
    return load_task(COURIER / "domain.pddl", COURIER / "problems" / "p01.pddl")


class Drive(smach.State):
    """A tutorial-style state: two outcomes, no preempt handling."""

    def __init__(self, started: threading.Event, release: threading.Event) -> None:
        super().__init__(outcomes=["succeeded", "aborted"])
        self.started, self.release = started, release

    def execute(self, ud: smach.UserData) -> str:
        self.started.set()
        self.release.wait(30)
        return "succeeded"


def registry_with(
    started: threading.Event, release: threading.Event, world: SimulatedWorld
) -> SkillRegistry:
    mine = SkillRegistry()
    mine.register("drive")(lambda r, a, b: Drive(started, release))
    return symbolic_skills(world, mine)


def test_check_accepts_a_skill_without_preempted_and_warns_about_it(task: PlanningTask) -> None:
    world = SimulatedWorld(task, seed=0, fail_rate=0.0)
    skills = registry_with(threading.Event(), threading.Event(), world)
    warnings: list[str] = []
    assert skills.check(task, warnings) == []
    assert warnings == [
        "skill 'drive': it has no outcome 'preempted' (outcomes: succeeded, aborted): a preempt "
        "does not stop it; the executive lets such a step finish before it stops the plan"
    ]


@pytest.mark.timeout(60)
def test_a_preempt_lets_such_a_step_finish_then_stops_the_plan(task: PlanningTask) -> None:
    world = SimulatedWorld(task, seed=0, fail_rate=0.0)
    started, release = threading.Event(), threading.Event()
    executive = Executive(task, registry_with(started, release, world))
    outcome: list[str] = []
    runner = threading.Thread(target=lambda: outcome.append(executive.execute()))
    runner.start()
    assert started.wait(30)
    executive.request_preempt()
    release.set()  # the skill ignores the preempt and finishes its drive
    runner.join(30)
    assert outcome == ["preempted"]
    assert executive.report.executed == ["(drive rover lab store)"]  # grab never started
    assert world.holds("robot-at", "rover", "store")  # the finished drive counted
