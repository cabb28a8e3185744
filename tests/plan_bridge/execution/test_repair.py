"""The recovery ladder as a list of strategies: the default rungs, a user's own one."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

import smach
from plan_bridge.execution.executive import Executive
from plan_bridge.execution.repair import (
    Failure,
    MissionEnded,
    Recovery,
    RecoveryStrategy,
    Replan,
    default_ladder,
)
from plan_bridge.execution.simulation import SimulatedWorld, symbolic_skills
from plan_bridge.pddl.task import PlanningTask, load_task
from plan_bridge.planning.planner import PlanStep, get_planner

ROOMS = Path(__file__).parents[1] / "data" / "rooms"

pytestmark = pytest.mark.timeout(60)


def rooms() -> PlanningTask:
    return load_task(ROOMS / "domain.pddl", ROOMS / "problems" / "p01.pddl")


@pytest.fixture(scope="module")
def planner():  # type: ignore[no-untyped-def]
    return get_planner("fast-downward")


class WaitForHelp:
    """A user's rung: a step that aborted is run again once a person helped (here at
    once), at most ``patience`` times per mission, before the built-in rungs."""

    name = "wait-for-help"

    def __init__(self, patience: int = 1) -> None:
        self.patience = patience
        self.helped: list[str] = []

    def attempt(self, failure: Failure, ladder: Recovery) -> list[PlanStep] | None:
        if not failure.aborted or len(self.helped) >= self.patience:
            return None
        self.helped.append(str(failure.rest[0]))
        ladder.decide("wait-for-help", f"{failure.reason}; a person helped", str(failure.rest[0]))
        return failure.rest


class EndMission:
    """A user's rung that ends the mission with its own explanation."""

    name = "end"

    def attempt(self, failure: Failure, ladder: Recovery) -> list[PlanStep] | None:
        raise MissionEnded("aborted", f"given up: {failure.reason}")


def flaky_pick_skills(world: SimulatedWorld, failures: int) -> Any:
    """The world's symbolic skills, with a ``pick`` that aborts ``failures`` times."""
    skills = symbolic_skills(world)
    left = [failures]

    class FlakyPick(smach.State):
        def __init__(self, *args: str) -> None:
            super().__init__(
                outcomes=["succeeded", "aborted", "preempted"], output_keys=["observations"]
            )
            self.args = args

        def execute(self, ud: smach.UserData) -> str:
            if left[0] > 0:
                left[0] -= 1
                return "aborted"
            ok, ud.observations = world.perform(PlanStep("pick", self.args))
            return "succeeded" if ok else "aborted"

    skills.add("pick", FlakyPick)
    return skills


def test_the_default_ladder_walks_the_documented_rungs_in_order() -> None:
    ladder = default_ladder()
    assert [rung.name for rung in ladder] == [
        "continue",
        "retry",
        "variant",
        "redo",
        "repair",
        "replan",
    ]
    assert all(isinstance(rung, RecoveryStrategy) for rung in ladder)
    assert default_ladder() is not default_ladder()  # a new list to add to


def test_a_users_strategy_first_in_the_ladder_recovers_before_the_built_in_rungs(
    planner: Any,
) -> None:
    task = rooms()
    world = SimulatedWorld(task)
    helper = WaitForHelp()
    ex = Executive(
        task,
        flaky_pick_skills(world, failures=1),
        planner,
        recovery_ladder=[helper, *default_ladder()],
    )
    assert ex.execute() == "succeeded"
    assert helper.helped == ["(pick robot1 cup kitchen)"]
    decisions = [d["decision"] for d in ex.report.decisions]
    assert "wait-for-help" in decisions and "retry" not in decisions
    assert ex.report.retries == 0 and ex.report.replans == 0


def test_the_built_in_rungs_follow_when_the_users_strategy_declines(planner: Any) -> None:
    task = rooms()
    world = SimulatedWorld(task)
    ex = Executive(
        task,
        flaky_pick_skills(world, failures=2),
        planner,
        recovery_ladder=[WaitForHelp(patience=1), *default_ladder()],
    )
    assert ex.execute() == "succeeded"
    decisions = [d["decision"] for d in ex.report.decisions]
    assert decisions.index("wait-for-help") < decisions.index("retry")
    assert ex.report.retries == 1


def test_a_strategy_ends_the_mission_with_its_own_explanation(planner: Any) -> None:
    task = rooms()
    world = SimulatedWorld(task)
    ex = Executive(
        task, flaky_pick_skills(world, failures=1), planner, recovery_ladder=[EndMission()]
    )
    assert ex.execute() == "aborted"
    assert ex.report.explanation.startswith("given up: (pick robot1 cup kitchen) aborted")


def test_a_ladder_where_no_rung_gives_a_plan_ends_the_mission(planner: Any) -> None:
    task = rooms()
    world = SimulatedWorld(task)
    ex = Executive(task, flaky_pick_skills(world, failures=1), planner, recovery_ladder=[Replan()])
    ex.policy = ex.policy.__class__(replan=False)
    assert ex.execute() == "aborted"
    assert "the policy allows no further recovery" in ex.report.explanation
    assert ex.report.replans == 0
