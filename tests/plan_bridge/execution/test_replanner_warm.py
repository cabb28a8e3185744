"""The replanner and the warm search: ``auto`` plans missions with it, and a plan of
it that the executive's action model refuses is planned by an engine instead."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import Any

import pytest

from plan_bridge.execution.executive import Executive
from plan_bridge.execution.simulation import SimulatedWorld, symbolic_skills
from plan_bridge.pddl.task import FactLike, PlanningTask, load_task
from plan_bridge.planning.engines import WARM
from plan_bridge.planning.registry import get_planner
from plan_bridge.planning.types import PlanResult, PlanStatus, PlanStep

FETCH = Path(__file__).resolve().parents[3] / "domains" / "fetch_drink"

pytestmark = pytest.mark.timeout(120)


def _fetch() -> PlanningTask:
    return load_task(FETCH / "domain.pddl", FETCH / "problems" / "p01.pddl")


class UnsoundWarm:
    """Answers like the warm search, with a plan that does not apply."""

    name = "unsound"

    def __init__(self) -> None:
        self.calls = 0

    def solve(
        self,
        task: PlanningTask,
        *,
        timeout: float,
        initial_state: Iterable[FactLike] | None = None,
        goal: Iterable[FactLike] | None = None,
        **options: Any,
    ) -> PlanResult:
        self.calls += 1
        step = PlanStep("hand-over", ("pr2", "cola", "alice", "living-room"))
        return PlanResult(PlanStatus.SOLVED, [step], planner=WARM)


def test_auto_plans_a_mission_with_the_warm_search() -> None:
    task = _fetch()
    executive = Executive(task, symbolic_skills(SimulatedWorld(task)), get_planner("auto"))
    executive.execute()
    assert executive.report.goal_reached
    assert executive.report.planners_won == {WARM: 1}


def test_a_warm_plan_the_action_model_refuses_is_planned_by_fast_downward() -> None:
    task = _fetch()
    planner = UnsoundWarm()
    executive = Executive(task, symbolic_skills(SimulatedWorld(task)), planner)
    executive.execute()
    assert planner.calls == 1
    assert executive.report.goal_reached
    assert executive.report.planners_won == {"fast-downward": 1}
