"""The table-clearing mission: the push monitor, objects that fall or lie elsewhere.

What every mission does (faults, seeds, the scripted baseline, generated problems) is
tested in test_missions.py.
"""

from __future__ import annotations

from typing import Any

import pytest
from pr2_missions import planner, run_planned, run_scripted, sweep, target

from plan_bridge.execution.events import StepFinished
from plan_bridge.execution.executive import Executive
from plan_bridge.missions.mission import Target
from smach.testing import EventRecorder

NAME = "table_clearing"


@pytest.mark.timeout(60)
@pytest.mark.parametrize(("problem", "objects"), [("p01", 2), ("p02", 5), ("p03", 10)])
def test_the_plan_grows_with_the_objects(problem: str, objects: int) -> None:
    run = run_planned(target(NAME, problem), 0, 0.0, planner())
    assert run.outcome == "succeeded"
    # A pick and a place per object, then the cart run.
    assert len(run.executed) >= 2 * objects + 3


def test_planned_beats_scripted_where_the_script_did_not_anticipate_the_fault() -> None:
    rescued = [
        r.seed
        for r in sweep(NAME, 0.2)
        if r.goal_reached and not run_scripted(target(NAME), r.seed, 0.2).goal_reached
    ]
    assert rescued


# -- skills ----------------------------------------------------------------------------------
def _world(target: Target) -> Any:
    assert target.module is not None
    return target.module.world.TableWorld(target.task, seed=0, fail_rate=0.0)


@pytest.mark.timeout(10)
def test_push_monitor_backs_up_a_jammed_cart_and_pushes_again() -> None:
    mission = target(NAME)
    world = _world(mission)
    jams = iter([True])
    world.chance = lambda kind: kind == "wheels-stalled" and next(jams, False)
    skill = mission.module.skills.push_machine(  # type: ignore[union-attr]
        world, {"robot": "pr2", "cart": "cart1", "source": "table-n", "target": "doorway"}
    )
    recorder = EventRecorder()
    skill.add_listener(recorder)
    assert skill.execute() == "succeeded"
    entered = [e.path for e in recorder.of_kind("state_entered")]
    assert entered.count("/ROOT/BACK_UP") == 1 and entered.count("/ROOT/PUSH") == 2
    assert entered.count("/ROOT/PUSH/MONITOR_WHEELS") == entered.count("/ROOT/PUSH/DRIVE_CART") == 2
    assert skill.userdata.observations[("cart-at", "cart1", "doorway")] is True
    assert [f.kind for f in world.faults] == ["wheels-stalled"]


@pytest.mark.timeout(10)
def test_push_into_a_blocked_corridor_reports_it_not_clear() -> None:
    mission = target(NAME)
    world = _world(mission)
    world._blocked.add(frozenset(("table-n", "doorway")))
    skill = mission.module.skills.push_machine(  # type: ignore[union-attr]
        world, {"robot": "pr2", "cart": "cart1", "source": "table-n", "target": "doorway"}
    )
    assert skill.execute() == "aborted"
    seen = skill.userdata.observations
    assert seen[("clear", "table-n", "doorway")] is False
    assert seen[("clear", "doorway", "table-n")] is False
    assert ("cart-at", "cart1", "table-n") in world.facts


@pytest.mark.timeout(10)
def test_pick_reports_an_object_that_fell_to_the_floor() -> None:
    mission = target(NAME)
    world = _world(mission)
    world.chance = lambda kind: kind == "grasp-slip"
    world.rng.random = lambda: 0.0  # below FLOOR_SHARE: to the floor
    skill = mission.module.skills.pick_machine(  # type: ignore[union-attr]
        world, {"robot": "pr2", "item": "cup1", "spot": "zone-n"}
    )
    assert skill.execute() == "aborted"
    seen = skill.userdata.observations
    assert seen[("item-at", "cup1", "floor-n")] is True
    assert seen[("item-at", "cup1", "zone-n")] is False


@pytest.mark.timeout(60)
def test_a_misplaced_object_is_found_and_the_executive_replans() -> None:
    mission = target(NAME)
    setup = mission.setup(seed=0, fail_rate=0.0)
    world = setup.world
    # plate2 lies in zone-n, not in zone-s as the problem says.
    with world._lock:
        world._facts.discard(("item-at", "plate2", "zone-s"))
        world._facts.add(("item-at", "plate2", "zone-n"))
    executive = Executive(mission.task, setup.skills, planner("pyperplan"))
    recorder = EventRecorder()
    executive.add_listener(recorder)
    assert executive.execute() == "succeeded" and world.goal_reached()
    assert "replan" in [d["decision"] for d in executive.report.decisions]
    steps = [e.action for e in recorder.events if isinstance(e, StepFinished)]
    assert "(pick pr2 plate2 zone-n table-n)" in steps
