"""The two-robot delivery: the robots' steps run concurrently, also while one recovers.

What every mission does (faults, seeds, the scripted baseline, generated problems) is
tested in test_missions.py.
"""

from __future__ import annotations

import pytest
from pr2_missions import planner, run_planned, target

from plan_bridge.execution.events import StepFinished
from plan_bridge.execution.executive import Executive
from smach.testing import EventRecorder

NAME = "two_robot_delivery"


def _parallel_robots(recorder: EventRecorder) -> list[set[str]]:
    """For each concurrent layer that ran, the robots whose steps ran in it."""
    layers: dict[str, set[str]] = {}
    for event in recorder.events:
        if isinstance(event, StepFinished) and "_PARALLEL_" in event.path:
            layer = event.path.rsplit("/", 1)[0]
            layers.setdefault(layer, set()).add(event.action.split()[1])
    return list(layers.values())


@pytest.mark.timeout(60)
@pytest.mark.parametrize("problem", ["p01", "p02", "p03"])
def test_every_problem_runs_both_robots_in_parallel(problem: str) -> None:
    mission = target(NAME, problem)
    assert mission.setup(seed=0, fail_rate=0.0).concurrent
    recorder = EventRecorder()
    run = run_planned(mission, 0, 0.0, planner(), recorder)
    assert run.outcome == "succeeded"
    assert {"r1", "r2"} in _parallel_robots(recorder)


@pytest.mark.timeout(60)
def test_steps_of_the_two_robots_run_inside_a_concurrence() -> None:
    recorder = EventRecorder()
    run_planned(target(NAME), 0, 0.0, planner("pyperplan"), recorder)
    steps = [e for e in recorder.events if isinstance(e, StepFinished)]
    layers = _parallel_robots(recorder)
    assert layers and all(robots == {"r1", "r2"} for robots in layers)
    # Every step of the plan ran inside a PARALLEL layer but the ones where one robot
    # was already done.
    inside = [e for e in steps if "_PARALLEL_" in e.path]
    assert len(inside) >= len(steps) // 2
    assert all(e.path.split("/")[-1].startswith(f"{e.index:02d}_") for e in steps)


@pytest.mark.timeout(60)
def test_executive_recovers_from_a_fault_of_one_robot_while_the_other_goes_on() -> None:
    mission = target(NAME)
    setup = mission.setup(seed=0, fail_rate=0.0)
    world = setup.world
    world.blocked_door = frozenset(("office", "hall-west"))  # r1's way to its storeroom
    executive = Executive(mission.task, setup.skills, planner("pyperplan"), concurrent=True)
    recorder = EventRecorder()
    executive.add_listener(recorder)
    assert executive.execute() == "succeeded" and world.goal_reached()
    assert [(f.kind, f.action) for f in world.faults] == [
        ("door-blocked", "(move r1 office hall-west)")
    ]
    decisions = [d["decision"] for d in executive.report.decisions]
    assert {"repair", "replan"} & set(decisions)
    failed = [e for e in recorder.events if isinstance(e, StepFinished) and e.outcome == "aborted"]
    assert [e.action for e in failed] == ["(move r1 office hall-west)"]
    assert "_PARALLEL_" in failed[0].path
    # After the recovery r1 goes round through the lab, still side by side with r2.
    assert "(move r1 office lab)" in executive.report.executed
    assert {"r1", "r2"} in _parallel_robots(recorder)[1:]
